#include "procman/exec_line.h"

#include <gtest/gtest.h>

#include <map>

namespace sarmap {
namespace procman {
namespace {

const std::map<std::string, std::string> kEnv = {{"HOME", "/home/op"}, {"N", "3"}, {"SP", "a b"}};

const char* Lookup(const std::string& name) {
  auto it = kEnv.find(name);
  return it == kEnv.end() ? nullptr : it->second.c_str();
}

TEST(ExecLine, SplitsQuotesAndExpands) {
  const ExecPlan p = PlanExec(
      "LD_LIBRARY_PATH=/opt/x  A=$N sarmap-slam --config '$HOME/my cfg.yaml' --set a=${N} "
      "\"$HOME/x y\" $SP $UNSET end\\ word ${UNSET:-dflt} ${N:-dflt}",
      Lookup);
  ASSERT_EQ(p.env.size(), 2u);
  EXPECT_EQ(p.env[0], (std::pair<std::string, std::string>{"LD_LIBRARY_PATH", "/opt/x"}));
  EXPECT_EQ(p.env[1], (std::pair<std::string, std::string>{"A", "3"}));
  // Expansion is not word-split (unlike sh): "$SP" stays one word.
  EXPECT_EQ(p.argv,
            (std::vector<std::string>{"sarmap-slam", "--config", "$HOME/my cfg.yaml", "--set",
                                      "a=3", "/home/op/x y", "a b", "end word", "dflt", "3"}));
}

TEST(ExecLine, AssignmentsOnlyAtTheStart) {
  const ExecPlan p = PlanExec("prog X=1", Lookup);
  EXPECT_TRUE(p.env.empty());
  EXPECT_EQ(p.argv, (std::vector<std::string>{"prog", "X=1"}));
}

TEST(ExecLine, ShellSyntaxNeedsUseShell) {
  for (const char* bad :
       {"a | b", "a && b", "a > log", "a; b", "echo `id`", "echo $(id)", "'open", "X=1", ""}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(PlanExec(bad, Lookup), std::invalid_argument);
  }
  // Quoted, it is just text.
  EXPECT_EQ(PlanExec("echo 'a | b'", Lookup).argv[1], "a | b");
}

TEST(ExecLine, FindsExecutables) {
  EXPECT_EQ(FindExecutable("sh", "/nonexistent:/bin:/usr/bin"), "/bin/sh");
  EXPECT_EQ(FindExecutable("/bin/sh", ""), "/bin/sh");
  EXPECT_EQ(FindExecutable("no-such-program-xyz", "/bin:/usr/bin"), "");
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
