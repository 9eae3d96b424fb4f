// Deputy and sheriff in-process over memq://: hostile datagrams on their channels are
// counted and dropped, and both go on; forged reports never drive a script; a script
// waiting on a deputy that went silent fails.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "procman/deputy.h"
#include "procman/event_loop.h"
#include "procman/pmd_config.h"
#include "procman/sheriff.h"

namespace sarmap {
namespace procman {
namespace {

const Key kKey(32, 0x42);

// Orders for deputy `deputy_id` whose one command line holds a NUL byte ("sleep\0 1"): LCM's
// encoders never write that, so it comes only from a hostile sender. Its HMAC re-encoding
// throws; the process must go on.
std::vector<uint8_t> OrdersWithNul(const std::string& deputy_id, uint8_t hmac_byte) {
  sarmap::pm_orders_t orders;
  orders.header.utime = 1;
  orders.header.seq = 0;
  orders.sheriff_id = "attacker";
  orders.deputy_id = deputy_id;
  orders.counter = 1;
  sarmap::pm_command_order_t c;
  c.command_id = "x";
  c.exec = "sleep_1";
  c.stop_signal = 2;
  c.stop_time_allowed_s = 1;
  orders.commands.push_back(c);
  orders.num_commands = 1;
  std::fill(std::begin(orders.hmac_sha256), std::end(orders.hmac_sha256), hmac_byte);
  std::vector<uint8_t> wire(static_cast<size_t>(orders.getEncodedSize()));
  EXPECT_EQ(orders.encode(wire.data(), 0, static_cast<int>(wire.size())),
            static_cast<int>(wire.size()));
  const char exec[] = "sleep_1";
  auto at = std::search(wire.begin(), wire.end(), exec, exec + strlen(exec));
  EXPECT_NE(at, wire.end());
  at[5] = 0;
  return wire;
}

// Publishes each datagram and handles it.
void Deliver(lcm::LCM* lcm, const std::vector<std::vector<uint8_t>>& datagrams) {
  for (const auto& wire : datagrams) {
    lcm->publish("PM_ORDERS", wire.data(), static_cast<unsigned int>(wire.size()));
    ASSERT_GT(lcm->handleTimeout(1000), 0);
  }
}

TEST(ProcmanNodeTest, DeputyDropsOrdersWithANulByteAndGoesOn) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  ProcmanOptions options;
  Deputy deputy(&lcm, options, "d1", kKey);
  Deliver(&lcm, {OrdersWithNul("d1", 0x55), OrdersWithNul("d1", 0)});
  EXPECT_EQ(deputy.malformed_orders(), 2);
  EXPECT_EQ(deputy.refused_orders(), 0);  // never got as far as the signature
}

TEST(ProcmanNodeTest, SheriffDropsOrdersWithANulByteAndGoesOn) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  ProcmanOptions options;
  const Config config = ParseConfig(R"(cmd "x" { exec = "sleep 1"; deputy = "d1"; })", "test");
  Sheriff sheriff(&lcm, options, config, &kKey, "sheriff/1");
  ASSERT_GT(lcm.handleTimeout(1000), 0);  // its own probe
  Deliver(&lcm, {OrdersWithNul("d1", 0x55), OrdersWithNul("d1", 0)});
  EXPECT_EQ(sheriff.malformed_messages(), 2);
}

// Names from the bus reach the deputy's log and the sheriff's terminal escaped: a newline or an
// ANSI escape in them cannot forge a log line or clear the operator's screen.
TEST(ProcmanNodeTest, BusStringsAreEscapedInLogsAndOutput) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  ProcmanOptions options;
  Deputy deputy(&lcm, options, "d1", kKey);
  sarmap::pm_orders_t orders{};
  orders.sheriff_id = "x'\nE 10:00:00.000 sarmap-procman-deputy] \x1b[2Jall commands stopped";
  orders.deputy_id = "d1";
  orders.counter = 1;
  testing::internal::CaptureStderr();
  lcm.publish("PM_ORDERS", &orders);
  ASSERT_GT(lcm.handleTimeout(1000), 0);
  const std::string logged = testing::internal::GetCapturedStderr();
  EXPECT_EQ(deputy.refused_orders(), 1);
  ASSERT_NE(logged.find("REFUSED"), std::string::npos) << logged;
  EXPECT_EQ(logged.find('\n'), logged.size() - 1) << logged;  // one line
  EXPECT_EQ(logged.find('\x1b'), std::string::npos) << logged;

  // An observer (no key) shows output unverified, but never raw.
  const Config config = ParseConfig(R"(cmd "x" { exec = "sleep 1"; deputy = "d1"; })", "test");
  Sheriff observer(&lcm, options, config, nullptr, "observer/1");
  sarmap::pm_output_t out{};
  out.deputy_id = "d1";
  out.num_commands = 1;
  out.command_ids = {"x"};
  out.text = {
      "ok \x1b[2J\x1b]0;owned\x07"
      "done\n"};
  lcm.publish("PM_OUTPUT", &out);
  while (lcm.handleTimeout(50) > 0) {
  }
  const std::string tail = observer.OutputTail(10);
  EXPECT_EQ(tail, "[x] ok \\x1b[2J\\x1b]0;owned\\x07done\n");
}

// The signature check itself never throws, whatever the orders hold.
TEST(ProcmanNodeTest, SignatureOfUnencodableOrdersIsInvalidNotAnException) {
  sarmap::pm_orders_t orders;
  orders.header.frame = "";
  orders.sheriff_id = std::string("a\0b", 3);
  orders.deputy_id = "d1";
  orders.num_commands = 0;
  std::fill(std::begin(orders.hmac_sha256), std::end(orders.hmac_sha256), 1);
  bool valid = true;
  EXPECT_NO_THROW(valid = SignatureValid(kKey, orders));
  EXPECT_FALSE(valid);
  ReplayGuard guard(1);
  Verdict verdict = Verdict::kAccepted;
  EXPECT_NO_THROW(verdict = VerifyOrders(kKey, orders, &guard, 0));
  EXPECT_EQ(verdict, Verdict::kForged);
}

// A deputy, a sheriff and a script in one process: handles messages and wakes everyone up
// until `done` or `limit_s`; returns the script's last result.
class Rig {
 public:
  explicit Rig(const std::string& pmd, ProcmanOptions options = ProcmanOptions())
      : lcm_("memq://"),
        config_(ParseConfig(pmd, "test.pmd")),
        deputy_(std::make_unique<Deputy>(&lcm_, options, "d1", kKey)),
        sheriff_(&lcm_, options, config_, &kKey, "sheriff/1"),
        runner_(&sheriff_, config_.FindScript("mission")) {
    lcm_.subscribe("PM_INFO", &Rig::OnInfo, this);
  }
  ~Rig() {
    if (deputy_) {
      deputy_->Shutdown();
      Pump([&] { return deputy_->Finished(); }, 10);
    }
  }
  bool Pump(const std::function<bool()>& done, double limit_s) {
    const double end = Now() + limit_s;
    while (Now() < end) {
      while (lcm_.handleTimeout(1) > 0) {
      }
      const double now = Now();
      if (deputy_) deputy_->OnWake({}, now);
      sheriff_.OnWake({}, now);
      if (result_ == ScriptRunner::kRunning) result_ = runner_.Step(now);
      if (done()) return true;
      usleep(2000);
    }
    return false;
  }
  lcm::LCM& lcm() { return lcm_; }
  Sheriff& sheriff() { return sheriff_; }
  ScriptRunner& runner() { return runner_; }
  ScriptRunner::Result result() const { return result_; }
  void KillDeputy() { deputy_.reset(); }  // stops reporting (its commands are killed)
  const std::vector<sarmap::pm_info_t>& reports() const { return reports_; }

 private:
  void OnInfo(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    sarmap::pm_info_t info;
    if (info.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) reports_.push_back(info);
  }
  lcm::LCM lcm_;
  Config config_;
  std::unique_ptr<Deputy> deputy_;
  Sheriff sheriff_;
  ScriptRunner runner_;
  ScriptRunner::Result result_ = ScriptRunner::kRunning;
  std::vector<sarmap::pm_info_t> reports_;
};

const char* kMissionPmd = R"(
cmd "sim" { exec = "sleep 600"; deputy = "d1"; }
script "mission" {
  start cmd "sim" wait "running" timeout 20;
  wait cmd "sim" status "stopped" timeout 1800;
}
)";

// Five fake "simulator stopped" reports must not end the mission (the script would go on to
// sign real stop orders): only signed, live reports count.
TEST(ProcmanNodeTest, ForgedStoppedReportsDoNotAdvanceTheScript) {
  Rig rig(kMissionPmd);
  ASSERT_TRUE(rig.Pump(
      [&] {
        return rig.runner().Describe().find("status \"stopped\"") != std::string::npos &&
               rig.sheriff().CommandState("sim") == sarmap::pm_command_status_t::STATE_RUNNING;
      },
      20));
  const int sim_pid = rig.sheriff().CommandPid("sim");
  ASSERT_GT(sim_pid, 0);
  ASSERT_FALSE(rig.reports().empty());
  // A genuine report from before the start (the deputy ran nothing: "sim" not there)...
  const sarmap::pm_info_t early = rig.reports().front();
  // ...and the latest one turned into "sim stopped", with a newer clock.
  sarmap::pm_info_t stopped = rig.reports().back();
  for (auto& c : stopped.commands) {
    c.state = sarmap::pm_command_status_t::STATE_STOPPED;
    c.pid = 0;
  }
  stopped.session_clock_us += 10000000;
  stopped.last_order_counter += 10000000;
  const Key wrong_key(32, 0x43);
  std::vector<sarmap::pm_info_t> forged;
  for (int i = 0; i < 5; ++i) {
    sarmap::pm_info_t f = stopped;
    f.header.seq += i + 1;
    f.session_clock_us += i;
    std::fill(std::begin(f.hmac_sha256), std::end(f.hmac_sha256), 0);
    if (i >= 3) SignInfo(wrong_key, &f);  // two signed with another key
    forged.push_back(f);
  }
  forged.push_back(early);  // a genuine report played back
  const int ignored_before = rig.sheriff().ignored_info();
  for (const auto& f : forged) {
    rig.lcm().publish("PM_INFO", &f);
    rig.Pump([] { return false; }, 0.05);
  }
  rig.Pump([] { return false; }, 0.5);
  EXPECT_EQ(rig.result(), ScriptRunner::kRunning) << rig.runner().error();
  EXPECT_EQ(rig.sheriff().CommandState("sim"), +sarmap::pm_command_status_t::STATE_RUNNING);
  EXPECT_EQ(rig.sheriff().ignored_info() - ignored_before, 6);
  EXPECT_NE(rig.sheriff().Table(Now()).find("6 unsigned, forged or played-back PM_INFO"),
            std::string::npos);
  // The simulator really stopping ends the wait.
  kill(sim_pid, SIGTERM);
  EXPECT_TRUE(rig.Pump([&] { return rig.result() != ScriptRunner::kRunning; }, 20));
  EXPECT_EQ(rig.result(), ScriptRunner::kDone) << rig.runner().error();
}

// Unsigned PM_OUTPUT would let anyone put lines into a command's output on the sheriff's
// screen: only the deputy's own signed output of its current session shows.
TEST(ProcmanNodeTest, ForgedAndPlayedBackOutputNeverReachesTheSheriffsView) {
  Rig rig(R"(
cmd "talker" { exec = "sh -c 'echo hello-from-talker; exec sleep 600'"; deputy = "d1"; }
script "mission" { start cmd "talker" wait "running" timeout 20; }
)");
  std::vector<sarmap::pm_output_t> genuine;
  rig.lcm().subscribeFunction(
      "^PM_OUTPUT$",
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&,
          std::vector<sarmap::pm_output_t>* out) {
        sarmap::pm_output_t msg;
        if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) out->push_back(msg);
      },
      &genuine);
  ASSERT_TRUE(rig.Pump(
      [&] { return rig.sheriff().OutputTail(10).find("hello-from-talker") != std::string::npos; },
      20))
      << rig.sheriff().OutputTail(10);
  ASSERT_FALSE(genuine.empty());
  const sarmap::pm_output_t real = genuine.back();
  EXPECT_FALSE(IsUnsigned(real.hmac_sha256));
  EXPECT_TRUE(SignatureValid(kKey, real));

  std::vector<sarmap::pm_output_t> forged;
  sarmap::pm_output_t f = real;
  f.text = {"FORGED-unsigned: all commands stopped\n"};
  f.session_clock_us += 1000000;
  std::fill(std::begin(f.hmac_sha256), std::end(f.hmac_sha256), 0);
  forged.push_back(f);
  f.text = {"FORGED-other-key\n"};
  SignOutput(Key(32, 0x43), &f);
  forged.push_back(f);
  sarmap::pm_output_t tampered = real;
  tampered.text = {"FORGED-tampered\n"};
  tampered.session_clock_us += 2000000;
  forged.push_back(tampered);
  forged.push_back(real);  // the genuine message played back
  const int ignored_before = rig.sheriff().ignored_output();
  for (const auto& m : forged) {
    rig.lcm().publish("PM_OUTPUT", &m);
    rig.Pump([] { return false; }, 0.05);
  }
  const std::string tail = rig.sheriff().OutputTail(50);
  EXPECT_EQ(tail.find("FORGED"), std::string::npos) << tail;
  EXPECT_EQ(tail.find("hello-from-talker"), tail.rfind("hello-from-talker")) << tail;  // once
  EXPECT_EQ(rig.sheriff().ignored_output() - ignored_before, 4);
  EXPECT_NE(rig.sheriff().Table(Now()).find("4 unsigned, forged or played-back PM_OUTPUT"),
            std::string::npos);
}

// A killed deputy must not leave the script waiting for its whole timeout (30 min in the demo).
TEST(ProcmanNodeTest, ScriptWaitingOnASilentDeputyFails) {
  ProcmanOptions options;
  options.deputy_gone_after_s = 2.0;
  Rig rig(kMissionPmd, options);
  ASSERT_TRUE(rig.Pump(
      [&] { return rig.runner().Describe().find("status \"stopped\"") != std::string::npos; }, 20));
  rig.KillDeputy();
  EXPECT_TRUE(rig.Pump([&] { return rig.result() != ScriptRunner::kRunning; }, 30));
  EXPECT_EQ(rig.result(), ScriptRunner::kFailed);
  EXPECT_NE(rig.runner().error().find("test.pmd:5:3: wait cmd \"sim\" status \"stopped\": "
                                      "deputy 'd1' silent for"),
            std::string::npos)
      << rig.runner().error();
}

// Order counters are on each deputy's own clock: a live sheriff follows another sheriff's
// orders to every deputy, however far apart the deputies' clocks are.
TEST(ProcmanNodeTest, LiveSheriffFollowsAnotherSheriffOnDeputiesWithDifferentClocks) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  const ProcmanOptions options;
  const Config config = ParseConfig(R"(
cmd "x" { exec = "sleep 600"; deputy = "d1"; }
cmd "y" { exec = "sleep 600"; deputy = "d2"; }
)",
                                    "test.pmd");
  std::vector<std::unique_ptr<Deputy>> deputies;
  std::vector<std::unique_ptr<Sheriff>> sheriffs;
  const auto pump = [&](double seconds, const std::function<bool()>& done) {
    const double end = Now() + seconds;
    while (Now() < end) {
      while (lcm.handleTimeout(1) > 0) {
      }
      for (auto& d : deputies) d->OnWake({}, Now());
      for (auto& s : sheriffs) s->OnWake({}, Now());
      if (done && done()) return true;
      usleep(2000);
    }
    return false;
  };
  deputies.push_back(std::make_unique<Deputy>(&lcm, options, "d1", kKey));
  pump(2.0, nullptr);  // d1's clock is 2 s ahead of d2's
  deputies.push_back(std::make_unique<Deputy>(&lcm, options, "d2", kKey));
  sheriffs.push_back(std::make_unique<Sheriff>(&lcm, options, config, &kKey, "live/1"));
  sheriffs.push_back(std::make_unique<Sheriff>(&lcm, options, config, &kKey, "one-shot/2"));
  Sheriff& live = *sheriffs[0];
  Sheriff& one_shot = *sheriffs[1];
  ASSERT_TRUE(pump(5, [&] { return live.AllDeputiesHeard() && one_shot.AllDeputiesHeard(); }));
  one_shot.Apply(Sheriff::Verb::kStart, config.ResolveTarget("x"));
  one_shot.Apply(Sheriff::Verb::kStart, config.ResolveTarget("y"));
  ASSERT_TRUE(pump(10, [&] {
    return live.CommandState("x") == +sarmap::pm_command_status_t::STATE_RUNNING &&
           live.CommandState("y") == +sarmap::pm_command_status_t::STATE_RUNNING;
  }));
  // The live sheriff now wants both running: its table says "run" for each.
  const std::string table = live.Table(Now());
  for (const char* id : {"x ", "y "}) {
    const size_t at = table.find(std::string("\n") + id);
    ASSERT_NE(at, std::string::npos) << table;
    const std::string line = table.substr(at + 1, table.find('\n', at + 1) - at - 1);
    EXPECT_NE(line.find(" run "), std::string::npos) << line;
  }
  for (auto& d : deputies) d->Shutdown();
  pump(10, [&] { return deputies[0]->Finished() && deputies[1]->Finished(); });
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
