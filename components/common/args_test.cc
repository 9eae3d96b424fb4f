#include "common/args.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace common {
namespace {

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> out;
  for (auto& a : args) out.push_back(a.data());
  return out;
}

TEST(ArgParserTest, ParsesFlagsPositionalsAndNodeOptions) {
  ArgParser p("prog", "does things");
  NodeArgs node;
  double speed = 1.0;
  std::string log;
  p.AddNodeOptions(&node);
  p.AddFlag("--speed", &speed, "replay speed");
  p.AddPositional("LOG", &log, "a log");
  std::vector<std::string> args = {"prog", "--speed=2.5", "--set", "a=1", "--set", "b.c=x",
                                   "file.log", "--lcm-url", "udpm://x"};
  auto argv = Argv(args);
  ASSERT_TRUE(p.Parse(static_cast<int>(argv.size()), argv.data()));
  EXPECT_DOUBLE_EQ(speed, 2.5);
  EXPECT_EQ(log, "file.log");
  EXPECT_EQ(node.overrides, std::vector<std::string>({"a=1", "b.c=x"}));
  EXPECT_EQ(node.lcm_url, "udpm://x");
  EXPECT_NE(p.Help().find("--print-config"), std::string::npos);
}

TEST(ArgParserTest, RejectsUnknownMissingAndMalformed) {
  ArgParser p("prog", "");
  double speed = 1.0;
  std::string log;
  p.AddFlag("--speed", &speed, "");
  p.AddPositional("LOG", &log, "");
  std::vector<std::string> unknown = {"prog", "--fast", "x"};
  auto a1 = Argv(unknown);
  EXPECT_THROW(p.Parse(3, a1.data()), ArgError);
  std::vector<std::string> missing = {"prog"};
  auto a2 = Argv(missing);
  EXPECT_THROW(p.Parse(1, a2.data()), ArgError);
  std::vector<std::string> bad = {"prog", "--speed", "fast", "x"};
  auto a3 = Argv(bad);
  EXPECT_THROW(p.Parse(4, a3.data()), ArgError);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
