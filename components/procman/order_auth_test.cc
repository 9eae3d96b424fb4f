#include "procman/order_auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

namespace sarmap {
namespace procman {
namespace {

Key TestKey(uint8_t seed) {
  Key k(32);
  for (size_t i = 0; i < k.size(); ++i) k[i] = static_cast<uint8_t>(seed + 7 * i);
  return k;
}

sarmap::pm_orders_t SomeOrders(int64_t counter) {
  sarmap::pm_orders_t o;
  o.header.utime = 1700000000000000;
  o.header.seq = 3;
  o.header.frame = "";
  o.sheriff_id = "sheriff@base";
  o.deputy_id = "compute";
  o.counter = counter;
  sarmap::pm_command_order_t c;
  c.command_id = "sarmap-slam";
  c.group = "mapping";
  c.exec = "sarmap-slam";
  c.use_shell = false;
  c.auto_respawn = true;
  c.stop_signal = 2;
  c.stop_time_allowed_s = 5;
  c.desired_running = true;
  c.desired_runid = 1;
  o.commands.push_back(c);
  o.num_commands = 1;
  std::fill(std::begin(o.hmac_sha256), std::end(o.hmac_sha256), 0);
  return o;
}

// RFC 4231 test case 2: pins that we compute HMAC-SHA256 itself, not something like it.
TEST(OrderAuth, HmacMatchesRfc4231) {
  const std::string key_text = "Jefe";
  const std::string data = "what do ya want for nothing?";
  const Digest d = HmacSha256(Key(key_text.begin(), key_text.end()),
                              reinterpret_cast<const uint8_t*>(data.data()), data.size());
  char hex[65];
  for (size_t i = 0; i < d.size(); ++i) snprintf(hex + 2 * i, 3, "%02x", d[i]);
  EXPECT_STREQ(hex, "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
}

TEST(OrderAuth, SignedOrdersVerifyAndAnyChangeBreaksThem) {
  const Key key = TestKey(1);
  sarmap::pm_orders_t o = SomeOrders(10);
  SignOrders(key, &o);
  EXPECT_TRUE(SignatureValid(key, o));
  EXPECT_FALSE(SignatureValid(TestKey(2), o));

  sarmap::pm_orders_t changed = o;
  changed.commands[0].exec = "rm -rf /";
  EXPECT_FALSE(SignatureValid(key, changed));
  changed = o;
  changed.deputy_id = "sensors";
  EXPECT_FALSE(SignatureValid(key, changed));
  changed = o;
  changed.counter = 11;
  EXPECT_FALSE(SignatureValid(key, changed));
}

TEST(OrderAuth, RefusesUnsignedForgedAndReplayed) {
  const Key key = TestKey(1);
  ReplayGuard guard;
  const int64_t t = 1700000000000000;  // counters are wall-clock microseconds
  sarmap::pm_orders_t unsigned_orders = SomeOrders(t);
  EXPECT_EQ(VerifyOrders(key, unsigned_orders, &guard), Verdict::kUnsigned);

  sarmap::pm_orders_t forged = SomeOrders(t + 1);
  SignOrders(TestKey(9), &forged);
  EXPECT_EQ(VerifyOrders(key, forged, &guard), Verdict::kForged);

  sarmap::pm_orders_t first = SomeOrders(t + 2);
  SignOrders(key, &first);
  EXPECT_EQ(VerifyOrders(key, first, &guard), Verdict::kAccepted);
  EXPECT_EQ(guard.Last("sheriff@base"), t + 2);
  EXPECT_EQ(VerifyOrders(key, first, &guard), Verdict::kReplayed);  // the same again
  sarmap::pm_orders_t older = SomeOrders(t + 1);
  SignOrders(key, &older);
  EXPECT_EQ(VerifyOrders(key, older, &guard), Verdict::kReplayed);
  sarmap::pm_orders_t next = SomeOrders(t + 1000000);
  SignOrders(key, &next);
  EXPECT_EQ(VerifyOrders(key, next, &guard), Verdict::kAccepted);
  // Another sheriff name has its own counters.
  sarmap::pm_orders_t other = SomeOrders(5);
  other.sheriff_id = "sheriff@laptop";
  SignOrders(key, &other);
  EXPECT_EQ(VerifyOrders(key, other, &guard), Verdict::kAccepted);
}

sarmap::pm_orders_t Signed(const Key& key, const std::string& sheriff, int64_t counter) {
  sarmap::pm_orders_t o = SomeOrders(counter);
  o.sheriff_id = sheriff;
  SignOrders(key, &o);
  return o;
}

TEST(OrderAuth, InstancesOfOneSheriffName) {
  const Key key = TestKey(1);
  ReplayGuard guard;  // window 2 s
  const int64_t t = 1700000000000000;
  // A live sheriff and a one-shot command of the same name send at once: their counters
  // interleave on the wire; neither is a replay.
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/100", t + 500000), &guard), Verdict::kAccepted);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/200", t + 400000), &guard), Verdict::kAccepted);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/100", t + 450000), &guard), Verdict::kReplayed);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/200", t + 400000), &guard), Verdict::kReplayed);
  // A restarted sheriff (new instance) continues upward.
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/300", t + 10000000), &guard), Verdict::kAccepted);
  // Instances left behind by more than the window are held to the name's newest counter,
  // also with orders of theirs the deputy never saw.
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/100", t + 600000), &guard), Verdict::kReplayed);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "s@h/400", t + 7000000), &guard), Verdict::kReplayed);
  EXPECT_EQ(guard.Last("s@h/100"), -1);  // forgotten: the state stays small
  EXPECT_EQ(guard.Newest("s@h/999"), t + 10000000);
}

TEST(OrderAuth, CountersSurviveADeputyRestart) {
  char dir_template[] = "/tmp/procman_replay_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string path = std::string(dir_template) + "/counters";
  const Key key = TestKey(3);
  sarmap::pm_orders_t o = SomeOrders(1700000000000000);
  o.sheriff_id = "sheriff with spaces";
  SignOrders(key, &o);
  {
    ReplayGuard guard(path);
    bool persisted = false;
    EXPECT_EQ(VerifyOrders(key, o, &guard, &persisted), Verdict::kAccepted);
    EXPECT_TRUE(persisted);
  }
  ReplayGuard restarted(path);
  EXPECT_EQ(restarted.Last("sheriff with spaces"), 1700000000000000);
  EXPECT_EQ(VerifyOrders(key, o, &restarted), Verdict::kReplayed);

  std::ofstream(path) << "garbage\n";
  EXPECT_THROW(ReplayGuard{path}, std::runtime_error);
  unlink(path.c_str());
  rmdir(dir_template);
}

TEST(OrderAuth, SheriffCountersOnlyGoUp) {
  CounterSource a;
  int64_t prev = 0;
  for (int i = 0; i < 1000; ++i) {
    const int64_t c = a.Next();
    EXPECT_GT(c, prev);
    prev = c;
  }
  // A restarted sheriff (new source) continues above: counters come from the wall clock.
  CounterSource b;
  EXPECT_GT(b.Next(), prev - 1000000);
}

TEST(OrderAuth, KeyFileChecks) {
  char dir_template[] = "/tmp/procman_key_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string path = std::string(dir_template) + "/procman.key";
  EXPECT_THROW(LoadKeyFile(path), std::runtime_error);  // missing
  std::ofstream(path) << "short";
  chmod(path.c_str(), 0600);
  EXPECT_THROW(LoadKeyFile(path), std::runtime_error);  // too short
  std::ofstream(path) << "0123456789abcdef0123456789abcdef";
  chmod(path.c_str(), 0644);
  EXPECT_THROW(LoadKeyFile(path), std::runtime_error);  // readable by others
  chmod(path.c_str(), 0600);
  EXPECT_EQ(LoadKeyFile(path).size(), 32u);
  unlink(path.c_str());
  rmdir(dir_template);
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
