#include "common/logging.h"

#include <gtest/gtest.h>

#include <string>

#include "common/node.h"

namespace sarmap {
namespace common {
namespace {

TEST(EscapeForLog, KeepsPrintableAsciiAndEscapesEverythingElse) {
  EXPECT_EQ(EscapeForLog("sarmap-slam on compute/mapping: ok [1] ~"),
            "sarmap-slam on compute/mapping: ok [1] ~");
  // A forged log line: a newline, then a fake entry in red.
  const std::string forged = "x\nE 10:00:00.000 sarmap-procman] \x1b[31mdeputy LOST\x1b[0m";
  const std::string escaped = EscapeForLog(forged);
  EXPECT_EQ(escaped, "x\\x0aE 10:00:00.000 sarmap-procman] \\x1b[31mdeputy LOST\\x1b[0m");
  for (char c : escaped) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << static_cast<int>(c);
  EXPECT_EQ(EscapeForLog(std::string("a\0b\r\t\x7f", 6)), "a\\x00b\\x0d\\x09\\x7f");
  EXPECT_EQ(EscapeForLog("caf\xc3\xa9"), "caf\\xc3\\xa9");  // not ASCII: bytes, never a glyph
  // A backslash is doubled, so the text "\x1b" cannot pass for an escaped byte.
  EXPECT_EQ(EscapeForLog("\\x1b"), "\\\\x1b");
  EXPECT_EQ(EscapeForLog(""), "");
}

TEST(EscapeForLog, CutsLongStringsAndSaysHowLongTheyWere) {
  const std::string long_name(60000, 'a');
  const std::string escaped = EscapeForLog(long_name, 8);
  EXPECT_EQ(escaped, "aaaaaaaa...(60000 bytes)");
  EXPECT_EQ(EscapeForLog("abc", 3), "abc");
  EXPECT_LT(EscapeForLog(long_name).size(), 300u);  // the default bound
}

// A message refused by a node is logged on one line, whatever its sender put in it.
TEST(EscapeForLog, ANodeLogsARefusedMessageOnOneEscapedLine) {
  Node node("logging_test", "memq://");
  testing::internal::CaptureStderr();
  node.Reject("PEOPLE_MAP", "keyword 'help\nE 10:00:00.000 sarmap-slam] \x1b[2Jdiverged'");
  const std::string logged = testing::internal::GetCapturedStderr();
  ASSERT_FALSE(logged.empty());
  EXPECT_EQ(logged.find('\n'), logged.size() - 1) << logged;  // one line
  EXPECT_EQ(logged.find('\x1b'), std::string::npos) << logged;
  EXPECT_NE(logged.find("help\\x0aE 10:00:00.000"), std::string::npos) << logged;
}

}  // namespace
}  // namespace common
}  // namespace sarmap
