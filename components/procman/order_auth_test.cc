#include "procman/order_auth.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <limits>

#include "common/testing/test_keys.h"
#include "procman/orders_test_util.h"

namespace sarmap {
namespace procman {
namespace {

using common::testing_util::TestKey;

sarmap::pm_orders_t SomeOrders(int64_t counter) {
  sarmap::pm_orders_t o =
      testing_util::OrdersToRun("sheriff@base", "compute", "sarmap-slam", "sarmap-slam", counter);
  o.header.utime = 1700000000000000;
  o.header.seq = 3;
  o.commands[0].group = "mapping";
  o.commands[0].stop_time_allowed_s = 5;
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
  changed.deputy_session = 1;
  EXPECT_FALSE(SignatureValid(key, changed));
  changed = o;
  changed.counter = 11;
  EXPECT_FALSE(SignatureValid(key, changed));
}

constexpr int64_t kSession = 0x1234567890;

sarmap::pm_orders_t Signed(const Key& key, const std::string& sheriff, int64_t counter,
                           int64_t session = kSession) {
  sarmap::pm_orders_t o = SomeOrders(counter);
  o.sheriff_id = sheriff;
  o.deputy_session = session;
  SignOrders(key, &o);
  return o;
}

TEST(OrderAuth, RefusesUnsignedForgedAndReplayed) {
  const Key key = TestKey(1);
  ReplayGuard guard(kSession);   // window 5 s
  const int64_t now = 60000000;  // the deputy's session clock: a minute since it started
  sarmap::pm_orders_t unsigned_orders = SomeOrders(now);
  unsigned_orders.deputy_session = kSession;
  EXPECT_EQ(VerifyOrders(key, unsigned_orders, &guard, now), Verdict::kUnsigned);

  sarmap::pm_orders_t forged = SomeOrders(now + 1);
  forged.deputy_session = kSession;
  SignOrders(TestKey(9), &forged);
  EXPECT_EQ(VerifyOrders(key, forged, &guard, now), Verdict::kForged);

  const sarmap::pm_orders_t first = Signed(key, "sheriff@base/1", now + 2);
  EXPECT_EQ(VerifyOrders(key, first, &guard, now), Verdict::kAccepted);
  EXPECT_EQ(guard.Last("sheriff@base/1"), now + 2);
  EXPECT_EQ(VerifyOrders(key, first, &guard, now + 10), Verdict::kReplayed);  // the same again
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/1", now + 1), &guard, now + 10),
            Verdict::kReplayed);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/1", now + 1000000), &guard, now + 1000000),
            Verdict::kAccepted);
  // Another sheriff instance has its own counters.
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@laptop/7", now - 4000000), &guard, now),
            Verdict::kAccepted);
}

// A restarted deputy has a new session, so a captured order is not accepted again (with the
// counter state in a file, losing the file or restarting the deputy would accept it).
TEST(OrderAuth, CapturedOrderIsRefusedByARestartedDeputy) {
  const Key key = TestKey(3);
  const sarmap::pm_orders_t captured = Signed(key, "sheriff@base/1", 2000000);
  ReplayGuard first_run(kSession);
  EXPECT_EQ(VerifyOrders(key, captured, &first_run, 2000000), Verdict::kAccepted);
  // The deputy restarts: a new session, its clock from zero again, nothing on disk.
  ReplayGuard second_run(RandomNonce());
  ASSERT_NE(second_run.session(), kSession);
  for (const int64_t now : {int64_t{0}, int64_t{1000000}, int64_t{2000000}, int64_t{3000000}}) {
    EXPECT_EQ(VerifyOrders(key, captured, &second_run, now), Verdict::kOtherSession) << now;
  }
  // The same order re-signed for the new session (only a key holder can) is accepted.
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/1", 2000000, second_run.session()),
                         &second_run, 2000000),
            Verdict::kAccepted);
}

// One order with a near-maximum counter must not lock its sheriff name out for good.
TEST(OrderAuth, NearMaximumCounterIsRefusedAndLocksNobodyOut) {
  const Key key = TestKey(1);
  ReplayGuard guard(kSession);
  const int64_t now = 10000000;
  const int64_t max = std::numeric_limits<int64_t>::max();
  for (const int64_t c : {max, max - 1, now + guard.window_us() + 1, int64_t{0}}) {
    EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/1", c), &guard, now),
              Verdict::kOutOfWindow)
        << c;
  }
  EXPECT_EQ(guard.Last("sheriff@base/1"), -1);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/1", now), &guard, now), Verdict::kAccepted);
  // The furthest a counter can get ahead is the window: it holds that instance back for at
  // most the window, and other instances of the name not at all.
  const int64_t ahead = now + guard.window_us();
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/2", ahead), &guard, now),
            Verdict::kAccepted);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/3", now + 1), &guard, now + 1),
            Verdict::kAccepted);
  EXPECT_EQ(VerifyOrders(key, Signed(key, "sheriff@base/2", ahead + 1), &guard, ahead + 1),
            Verdict::kAccepted);
}

TEST(OrderAuth, InstancesOutsideTheWindowAreForgotten) {
  const Key key = TestKey(1);
  ReplayGuard guard(kSession);
  int64_t now = 1000000;
  for (int i = 0; i < 50; ++i, now += 1000000) {
    EXPECT_EQ(VerifyOrders(key, Signed(key, "one-shot/" + std::to_string(i), now), &guard, now),
              Verdict::kAccepted);
  }
  // Only the instances of the last window are remembered...
  EXPECT_LE(guard.instances(), 6u);
  // ...and an order of a forgotten one is refused all the same (older than the window).
  EXPECT_EQ(VerifyOrders(key, Signed(key, "one-shot/3", 4000000 + 1), &guard, now),
            Verdict::kOutOfWindow);
}

sarmap::pm_info_t SomeInfo(int64_t session, int64_t clock_us, int64_t echo) {
  sarmap::pm_info_t info;
  info.header.utime = 1;
  info.header.seq = 0;
  info.deputy_id = "compute";
  info.host = "robot";
  info.cpu_load = 0.25;
  info.phys_mem_total_bytes = 1 << 30;
  info.phys_mem_free_bytes = 1 << 29;
  info.refused_orders = 0;
  info.last_order_counter = -1;
  info.num_commands = 0;
  info.session = session;
  info.session_clock_us = clock_us;
  info.probe_echo = echo;
  std::fill(std::begin(info.hmac_sha256), std::end(info.hmac_sha256), 0);
  return info;
}

sarmap::pm_info_t SignedInfo(const Key& key, int64_t session, int64_t clock_us, int64_t echo) {
  sarmap::pm_info_t info = SomeInfo(session, clock_us, echo);
  SignInfo(key, &info);
  return info;
}

TEST(OrderAuth, SheriffAcceptsOnlySignedLiveReports) {
  const Key key = TestKey(1);
  InfoGuard guard;
  // Before any probe of ours, even a genuine report is unconfirmed (it could be a recording).
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession, 100, 0)), InfoVerdict::kUnconfirmed);
  guard.AddChallenge(777);
  EXPECT_EQ(guard.Verify(key, SomeInfo(kSession, 200, 777)), InfoVerdict::kUnsigned);
  sarmap::pm_info_t forged = SomeInfo(kSession, 200, 777);
  SignInfo(TestKey(9), &forged);
  EXPECT_EQ(guard.Verify(key, forged), InfoVerdict::kForged);
  sarmap::pm_info_t tampered = SignedInfo(key, kSession, 200, 777);
  tampered.cpu_load = 0.5;
  EXPECT_EQ(guard.Verify(key, tampered), InfoVerdict::kForged);
  // Signed and echoing our nonce: the session is confirmed.
  const sarmap::pm_info_t live = SignedInfo(key, kSession, 300, 777);
  EXPECT_EQ(guard.Verify(key, live), InfoVerdict::kNewSession);
  EXPECT_EQ(guard.Session("compute"), kSession);
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession, 400, 777)), InfoVerdict::kAccepted);
  // Played back: not newer than what we have.
  EXPECT_EQ(guard.Verify(key, live), InfoVerdict::kStale);
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession, 400, 777)), InfoVerdict::kStale);
  // A recording of another session, even one that echoed our nonce, cannot take over...
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession + 1, 5000, 777)), InfoVerdict::kUnconfirmed);
  // ...a restarted deputy answering our next probe does.
  guard.AddChallenge(888);
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession + 2, 50, 888)), InfoVerdict::kNewSession);
  EXPECT_EQ(guard.Session("compute"), kSession + 2);
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession, 500, 777)), InfoVerdict::kUnconfirmed);
}

sarmap::pm_output_t Output(int64_t session, int64_t clock_us, const std::string& text) {
  sarmap::pm_output_t out{};
  out.deputy_id = "compute";
  out.num_commands = 1;
  out.command_ids = {"sarmap-slam"};
  out.text = {text};
  out.session = session;
  out.session_clock_us = clock_us;
  return out;
}

sarmap::pm_output_t SignedOutput(const Key& key, int64_t session, int64_t clock_us,
                                 const std::string& text) {
  sarmap::pm_output_t out = Output(session, clock_us, text);
  SignOutput(key, &out);
  return out;
}

TEST(OrderAuth, SheriffShowsOnlyTheDeputysOwnOutput) {
  const Key key = TestKey(1);
  InfoGuard guard;
  // Nothing is shown before the deputy's session is confirmed by one of its reports.
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession, 100, "a\n")),
            InfoVerdict::kUnconfirmed);
  guard.AddChallenge(777);
  ASSERT_EQ(guard.Verify(key, SignedInfo(key, kSession, 300, 777)), InfoVerdict::kNewSession);

  EXPECT_EQ(guard.VerifyOutput(key, Output(kSession, 310, "fake line\n")), InfoVerdict::kUnsigned);
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(TestKey(9), kSession, 310, "fake line\n")),
            InfoVerdict::kForged);
  sarmap::pm_output_t tampered = SignedOutput(key, kSession, 310, "mapping\n");
  tampered.text[0] = "diverged, stopping\n";
  EXPECT_EQ(guard.VerifyOutput(key, tampered), InfoVerdict::kForged);
  sarmap::pm_output_t other_command = SignedOutput(key, kSession, 310, "mapping\n");
  other_command.command_ids[0] = "sarmap-explore";
  EXPECT_EQ(guard.VerifyOutput(key, other_command), InfoVerdict::kForged);

  const sarmap::pm_output_t genuine = SignedOutput(key, kSession, 310, "mapping\n");
  EXPECT_EQ(guard.VerifyOutput(key, genuine), InfoVerdict::kAccepted);
  // The output clock is its own: a report in between does not make the next output stale.
  EXPECT_EQ(guard.Verify(key, SignedInfo(key, kSession, 400, 777)), InfoVerdict::kAccepted);
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession, 320, "more\n")),
            InfoVerdict::kAccepted);
  // Played back, or an older message of the session: shown once only.
  EXPECT_EQ(guard.VerifyOutput(key, genuine), InfoVerdict::kStale);
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession, 315, "x\n")), InfoVerdict::kStale);
  // Another session's output (a recording) is not the deputy's current output...
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession + 1, 5000, "old\n")),
            InfoVerdict::kUnconfirmed);
  // ...and once a restarted deputy is confirmed, its output starts afresh and the old
  // session's is refused.
  guard.AddChallenge(888);
  ASSERT_EQ(guard.Verify(key, SignedInfo(key, kSession + 2, 50, 888)), InfoVerdict::kNewSession);
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession + 2, 60, "up\n")),
            InfoVerdict::kAccepted);
  EXPECT_EQ(guard.VerifyOutput(key, SignedOutput(key, kSession, 330, "old\n")),
            InfoVerdict::kUnconfirmed);
}

TEST(OrderAuth, RandomNoncesArePositiveAndDiffer) {
  const int64_t a = RandomNonce(), b = RandomNonce();
  EXPECT_GT(a, 0);
  EXPECT_GT(b, 0);
  EXPECT_NE(a, b);
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
