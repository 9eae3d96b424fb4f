#include "common/command_auth.h"

#include <gtest/gtest.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <vector>

#include "common/decode.h"
#include "common/testing/test_keys.h"
#include "sarmap/teleop_t.hpp"
#include "sarmap/velocity_command_t.hpp"

namespace sarmap {
namespace common {
namespace {

using testing_util::TestKey;

velocity_command_t Command(int64_t utime, double linear_mps) {
  velocity_command_t m{};
  m.header.utime = utime;
  m.header.frame = "base";
  m.linear_mps = linear_mps;
  m.angular_radps = 0.1;
  m.source = "explore";
  return m;
}

// RFC 4231 test case 2: the HMAC itself.
TEST(CommandAuth, HmacSha256MatchesRfc4231) {
  const std::string k = "Jefe", data = "what do ya want for nothing?";
  const AuthDigest d = HmacSha256(AuthKey(k.begin(), k.end()),
                                  reinterpret_cast<const uint8_t*>(data.data()), data.size());
  const uint8_t expected[4] = {0x5b, 0xdc, 0xc1, 0x46};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(d[i], expected[i]) << i;
  EXPECT_EQ(d[31], 0x43);
}

TEST(CommandAuth, SignedCommandsPassForgedTamperedAndReplayedOnesDoNot) {
  const AuthKey key = TestKey(1);
  CommandGate gate(key);
  std::string why;

  velocity_command_t unsigned_cmd = Command(100, 0.3);
  EXPECT_FALSE(gate.Accept(unsigned_cmd, &why));
  EXPECT_NE(why.find("not signed"), std::string::npos) << why;

  velocity_command_t other_key = Command(100, 0.3);
  ASSERT_TRUE(SignMessage(TestKey(2), &other_key));
  EXPECT_FALSE(gate.Accept(other_key, &why));

  velocity_command_t good = Command(100, 0.3);
  ASSERT_TRUE(SignMessage(key, &good));
  EXPECT_TRUE(MessageSigned(key, good));
  velocity_command_t tampered = good;
  tampered.linear_mps = 1e6;  // a signed command's speed changed on the way
  EXPECT_FALSE(gate.Accept(tampered, &why));
  EXPECT_TRUE(gate.Accept(good, &why)) << why;
  // The same command again, and an older one: replays.
  EXPECT_FALSE(gate.Accept(good, &why));
  EXPECT_NE(why.find("replay"), std::string::npos) << why;
  velocity_command_t older = Command(50, 0.0);
  ASSERT_TRUE(SignMessage(key, &older));
  EXPECT_FALSE(gate.Accept(older, &why));
  velocity_command_t next = Command(133, 0.2);
  ASSERT_TRUE(SignMessage(key, &next));
  EXPECT_TRUE(gate.Accept(next, &why)) << why;
  // A signed command stamped far ahead of the receiver's clock (its sender was fed a forged
  // input) is refused and does not become the newest: the next real command still acts.
  velocity_command_t future = Command(133 + 3600000000LL, 0.2);
  ASSERT_TRUE(SignMessage(key, &future));
  EXPECT_FALSE(gate.Accept(future, &why, 140));
  EXPECT_NE(why.find("ahead"), std::string::npos) << why;
  velocity_command_t after = Command(166, 0.2);
  ASSERT_TRUE(SignMessage(key, &after));
  EXPECT_TRUE(gate.Accept(after, &why, 170)) << why;

  // TELEOP the same way; a string with a NUL byte has no encoding and is never accepted.
  teleop_t stop{};
  stop.header.utime = 10;
  stop.operator_id = "op";
  stop.emergency_stop = true;
  ASSERT_TRUE(SignMessage(key, &stop));
  CommandGate teleop_gate(key);
  EXPECT_TRUE(teleop_gate.Accept(stop, &why));
  teleop_t nul = stop;
  nul.header.utime = 11;
  nul.operator_id = std::string("o\0p", 3);
  EXPECT_FALSE(SignMessage(key, &nul));
  EXPECT_FALSE(teleop_gate.Accept(nul, &why));
}

// What the receiver checks is the message decoded from the bytes the sender published.
TEST(CommandAuth, ASignatureSurvivesEncodingAndDecoding) {
  const AuthKey key = TestKey(3);
  velocity_command_t sent = Command(1700000000123456, -0.25);
  sent.header.seq = 41;
  ASSERT_TRUE(SignMessage(key, &sent));
  std::vector<uint8_t> bytes(static_cast<size_t>(sent.getEncodedSize()));
  ASSERT_EQ(sent.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  velocity_command_t received;
  std::string why;
  ASSERT_TRUE(DecodeMessage(bytes.data(), bytes.size(), &received, &why)) << why;
  EXPECT_TRUE(MessageSigned(key, received));
}

TEST(CommandAuth, WithoutAKeyEveryCommandPasses) {
  CommandGate gate;
  EXPECT_FALSE(gate.enabled());
  std::string why;
  EXPECT_TRUE(gate.Accept(Command(5, 0.1), &why));
  EXPECT_TRUE(gate.Accept(Command(5, 0.1), &why));
}

TEST(CommandAuth, KeyFilesThatAreMissingShortOrOpenAreErrors) {
  const std::string dir = "/tmp/sarmap_command_auth_test_" + std::to_string(getpid());
  mkdir(dir.c_str(), 0700);
  EXPECT_THROW(LoadAuthKeyFile(dir + "/missing.key"), std::runtime_error);
  const std::string short_key = dir + "/short.key";
  std::ofstream(short_key) << "0123456789";
  chmod(short_key.c_str(), 0600);
  EXPECT_THROW(LoadAuthKeyFile(short_key), std::runtime_error);
  const std::string open_key = dir + "/open.key";
  std::ofstream(open_key) << "0123456789abcdef0123456789abcdef";
  chmod(open_key.c_str(), 0644);
  EXPECT_THROW(LoadAuthKeyFile(open_key), std::runtime_error);
  chmod(open_key.c_str(), 0600);
  EXPECT_EQ(LoadAuthKeyFile(open_key).size(), 32u);
  unlink(short_key.c_str());
  unlink(open_key.c_str());
  rmdir(dir.c_str());
}

TEST(CommandAuth, ATildeIsTheUsersHomeFromThePasswordDatabase) {
  const passwd* user = getpwuid(getuid());
  ASSERT_NE(user, nullptr);
  EXPECT_EQ(ExpandUserHome("~/.config/sarmap/procman.key"),
            std::string(user->pw_dir) + "/.config/sarmap/procman.key");
  EXPECT_EQ(ExpandUserHome("~"), std::string(user->pw_dir));
  EXPECT_EQ(ExpandUserHome("/etc/sarmap/procman.key"), "/etc/sarmap/procman.key");
  EXPECT_EQ(ExpandUserHome("keys/~/a.key"), "keys/~/a.key");
  EXPECT_EQ(ExpandUserHome("~other/a.key"), "~other/a.key");  // another user's home: as given
}

}  // namespace
}  // namespace common
}  // namespace sarmap
