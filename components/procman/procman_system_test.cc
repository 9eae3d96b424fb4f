// Multi-process tests of sheriff and deputy: real processes, real LCM (udpm multicast inside
// a private network namespace, see tests/harness/sarmap-netns). Run through CTest
// (procman_system) or by hand: tests/harness/sarmap-netns build/bin/procman_system_test
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include "procman/order_auth.h"
#include "procman/orders_test_util.h"
#include "procman/test_support.h"
#include "sarmap/pm_command_status_t.hpp"
#include "sarmap/pm_output_t.hpp"

namespace sarmap {
namespace procman {
namespace {

using namespace sarmap::procman::testing;
using Status = sarmap::pm_command_status_t;

class ProcmanSystem : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    deputy_id_ = std::string("d") + std::to_string(getpid()) + "-" + info->name();
    // Unique sleep lengths mark this run's (and this test's) processes in /proc.
    static int test_index = 0;
    base_ = getpid() * 100 + 10 * test_index++;
  }
  std::string Marker(int i) const { return std::to_string(base_ + i); }
  std::string SleepCmd(int i) const { return "sleep " + Marker(i); }

  std::unique_ptr<Child> StartDeputy(const std::string& id,
                                     const std::string& log_name = "deputy.log") {
    watch_.Forget(id);
    auto d = std::make_unique<Child>(std::vector<std::string>{BinDir() + "/sarmap-procman-deputy",
                                                              "--id", id, "--key", scratch_.key()},
                                     scratch_.dir() + "/" + log_name);
    EXPECT_TRUE(watch_.WaitFor([&] { return watch_.Heard(id); }))
        << "deputy " << id << " not heard";
    return d;
  }
  CliResult Sheriff(const std::string& pmd, std::vector<std::string> args) {
    std::vector<std::string> argv = {BinDir() + "/sarmap-procman", pmd, "--key", scratch_.key()};
    argv.insert(argv.end(), args.begin(), args.end());
    const CliResult r = testing::Run(argv, scratch_.dir() + "/sheriff-cli.log");
    std::string joined;
    for (const auto& a : args) joined += " " + a;
    printf("$ sarmap-procman CONFIG%s -> exit %d\n%s", joined.c_str(), r.exit_code,
           r.output.c_str());
    return r;
  }
  std::string Pmd(const std::string& body) { return scratch_.Write("test.pmd", body); }
  // A pmd line `cmd "name" { exec = "exec"; deputy = "<this test's deputy>";settings }`.
  std::string Cmd(const std::string& name, const std::string& exec,
                  const std::string& settings = "") const {
    return "cmd \"" + name + "\" { exec = \"" + exec + "\"; deputy = \"" + deputy_id_ + "\";" +
           settings + " }";
  }

  Scratch scratch_;
  Watcher watch_;
  std::string deputy_id_;
  long base_ = 0;
};

// Orders as an attacker without the key sends them: unsigned, from sheriff "mallory".
sarmap::pm_orders_t EvilOrders(const std::string& deputy, const std::string& exec,
                               int64_t counter) {
  return testing_util::OrdersToRun("mallory", deputy, "evil", exec, counter);
}

TEST_F(ProcmanSystem, GroupStartStopRestart) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd("group \"g\" {\n  " + Cmd("a", SleepCmd(1)) + "\n  group \"inner\" { " +
          Cmd("b", SleepCmd(2)) + " }\n}\n" + Cmd("c", SleepCmd(3)) + "\n");
  auto deputy = StartDeputy(d);
  ASSERT_EQ(Sheriff(pmd, {"start", "g"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsRunning(d, "a") && watch_.IsRunning(d, "b"); }));
  EXPECT_TRUE(watch_.IsStopped(d, "c"));
  const int a1 = watch_.Pid(d, "a"), b1 = watch_.Pid(d, "b");
  const std::vector<ProcInfo> first = Snapshot({a1, b1});
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(ProcessesWithCmdline(SleepCmd(1)), std::vector<int>{a1});
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(3)).empty());

  ASSERT_EQ(Sheriff(pmd, {"restart", "g"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] {
    return watch_.IsRunning(d, "a") && watch_.IsRunning(d, "b") && watch_.Pid(d, "a") != a1 &&
           watch_.Pid(d, "b") != b1;
  }));
  for (const ProcInfo& p : first) EXPECT_FALSE(StillRunning(p)) << p.pid;
  EXPECT_EQ(watch_.Command(d, "a")->actual_runid, 2);

  ASSERT_EQ(Sheriff(pmd, {"stop", "g"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsStopped(d, "a") && watch_.IsStopped(d, "b"); }));
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(1)).empty());
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(2)).empty());

  const CliResult status = Sheriff(pmd, {"status"});
  EXPECT_EQ(status.exit_code, 0);
  EXPECT_NE(status.output.find(d), std::string::npos);
  // Bad use is one clear line and exit code 2.
  const CliResult bad = Sheriff(pmd, {"start", "nonexistent"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("no command or group \"nonexistent\""), std::string::npos);
}

TEST_F(ProcmanSystem, OutputAndEnvironmentReachTheSheriff) {
  const std::string d = deputy_id_;
  setenv("PROCMAN_TEST_VALUE", Marker(5).c_str(), 1);  // the deputy inherits it
  const std::string pmd = Pmd(Cmd("talker",
                                  "GREETING=hello-$PROCMAN_TEST_VALUE sh -c "
                                  "'echo $GREETING; echo to-stderr >&2; exec " +
                                      SleepCmd(1) + "'") +
                              "\n");
  auto deputy = StartDeputy(d);
  std::string output;
  lcm::Subscription* sub = watch_.lcm().subscribeFunction(
      "^PM_OUTPUT$",
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, std::string* out) {
        sarmap::pm_output_t msg;
        if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
        for (const auto& t : msg.text) *out += t;
      },
      &output);
  ASSERT_EQ(Sheriff(pmd, {"start", "talker"}).exit_code, 0);
  EXPECT_TRUE(watch_.WaitFor([&] { return output.find("to-stderr\n") != std::string::npos; }))
      << output;
  EXPECT_NE(output.find("hello-" + Marker(5) + "\n"), std::string::npos) << output;
  // Started without a shell of ours: the command's own process is the sh we asked for.
  const int pid = watch_.Pid(d, "talker");
  EXPECT_EQ(ProcessesWithCmdline(SleepCmd(1)), std::vector<int>{pid});  // sh exec'd the sleep
  ASSERT_EQ(Sheriff(pmd, {"stop", "talker"}).exit_code, 0);
  watch_.lcm().unsubscribe(sub);
}

TEST_F(ProcmanSystem, CrashingCommandIsRespawned) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd(Cmd("crasher", "sh -c 'sleep 0.3; exit 3'", " auto_respawn = true;") + "\n");
  auto deputy = StartDeputy(d);
  Sheriff(pmd, {"start", "crasher"});  // may or may not catch it running: not asserted
  ASSERT_TRUE(watch_.WaitFor([&] {
    const auto* c = watch_.Command(d, "crasher");
    return c && c->restart_count >= 4;
  }));
  EXPECT_EQ(watch_.Command(d, "crasher")->exit_code, 3);
  // Respawn delays from the deputy's own stamps: crash reported -> running with a new pid.
  double worst_s = 0;
  int respawns = 0;
  std::string delays;
  int64_t crash_utime = -1;
  int crashed_pid = 0;
  for (const auto& info : watch_.History(d)) {
    for (const auto& c : info.commands) {
      if (c.command_id != "crasher") continue;
      if (c.state == Status::STATE_RESPAWN_WAIT && crash_utime < 0) {
        crash_utime = info.header.utime;
      } else if (c.state == Status::STATE_RUNNING && crash_utime >= 0 && c.pid != crashed_pid) {
        const double delay_s = (info.header.utime - crash_utime) * 1e-6;
        worst_s = std::max(worst_s, delay_s);
        char buf[32];
        snprintf(buf, sizeof(buf), "%s%.3f", delays.empty() ? "" : ", ", delay_s);
        delays += buf;
        ++respawns;
        crash_utime = -1;
        crashed_pid = c.pid;
      }
    }
  }
  printf(
      "FIGURE crash -> running again (s), consecutive quick crashes: %s; longest %.3f s "
      "(back-off 0.1 s doubling)\n",
      delays.c_str(), worst_s);
  EXPECT_GE(respawns, 3);
  ASSERT_EQ(Sheriff(pmd, {"stop", "crasher"}).exit_code, 0);
}

TEST_F(ProcmanSystem, CommandIgnoringSigintIsKilledAfterStopTimeAllowed) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd("cmd \"stubborn\" { exec = \"trap '' INT; exec " + SleepCmd(1) +
          "\"; use_shell = true; deputy = \"" + d + "\"; stop_time_allowed = 1.0; }\n");
  auto deputy = StartDeputy(d);
  ASSERT_EQ(Sheriff(pmd, {"start", "stubborn"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return ProcessesWithCmdline(SleepCmd(1)).size() == 1; }, 5));
  ASSERT_EQ(Sheriff(pmd, {"stop", "stubborn"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsStopped(d, "stubborn"); }));
  ASSERT_NE(watch_.Command(d, "stubborn"), nullptr);
  EXPECT_EQ(watch_.Command(d, "stubborn")->exit_code, 128 + SIGKILL);
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(1)).empty());
  int64_t stopping = -1, stopped = -1;
  for (const auto& info : watch_.History(d)) {
    for (const auto& c : info.commands) {
      if (c.state == Status::STATE_STOPPING && stopping < 0) stopping = info.header.utime;
      if (c.state == Status::STATE_STOPPED && stopping >= 0 && stopped < 0)
        stopped = info.header.utime;
    }
  }
  printf("FIGURE SIGINT ignored: stopping -> stopped (SIGKILL) %.3f s, stop_time_allowed 1.0 s\n",
         (stopped - stopping) * 1e-6);
}

TEST_F(ProcmanSystem, NoDescendantSurvivesAStop) {
  const std::string d = deputy_id_;
  // Background children of sh ignore SIGINT; one leaves the process group with setsid.
  const std::string s = SleepCmd(1);
  const std::string pmd =
      Pmd(Cmd("family", "sh -c '" + s + " & " + s + " & setsid " + s + " & " + s + "'",
              " stop_time_allowed = 1;") +
          "\n");
  auto deputy = StartDeputy(d);
  ASSERT_EQ(Sheriff(pmd, {"start", "family"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return ProcessesWithCmdline(s).size() == 4; }, 5));
  const std::vector<ProcInfo> before = Snapshot(ProcessesWithCmdline(s));
  ASSERT_EQ(Sheriff(pmd, {"stop", "family"}).exit_code, 0);
  EXPECT_TRUE(ProcessesWithCmdline(s).empty());
  for (const ProcInfo& p : before) EXPECT_FALSE(StillRunning(p)) << p.pid;
}

TEST_F(ProcmanSystem, RefusesUnsignedForgedAndReplayedOrders) {
  const std::string d = deputy_id_;
  const std::string evil = SleepCmd(9);
  const std::string pmd = Pmd(Cmd("victim", SleepCmd(1)) + "\n");
  auto deputy = StartDeputy(d);
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  // 1. Unsigned.
  sarmap::pm_orders_t unsigned_orders = EvilOrders(d, evil, now_us + 1000000000);
  watch_.lcm().publish("PM_ORDERS", &unsigned_orders);
  // 2. Signed with another key.
  const std::string other_key = scratch_.dir() + "/other.key";
  Scratch::WriteKey(other_key, 2);
  sarmap::pm_orders_t forged = EvilOrders(d, evil, now_us + 1000000001);
  SignOrders(LoadKeyFile(other_key), &forged);
  watch_.lcm().publish("PM_ORDERS", &forged);
  // 3. Signed with the right key, then tampered with.
  sarmap::pm_orders_t tampered = EvilOrders(d, "true", now_us + 1000000002);
  SignOrders(LoadKeyFile(scratch_.key()), &tampered);
  tampered.commands[0].exec = evil;
  watch_.lcm().publish("PM_ORDERS", &tampered);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Info(d).refused_orders == 3; }));
  // Nothing at all was ordered: the deputy knows no command.
  watch_.Spin(0.5);
  EXPECT_EQ(watch_.Command(d, "evil"), nullptr);
  EXPECT_TRUE(ProcessesWithCmdline(evil).empty());

  // 4. Replay: a genuine "start victim" order, re-sent after the sheriff stopped it.
  ASSERT_EQ(Sheriff(pmd, {"start", "victim"}).exit_code, 0);
  std::vector<uint8_t> start_order;
  ASSERT_TRUE(watch_.WaitFor([&] {
    for (size_t i = 0; i < watch_.Orders().size(); ++i) {
      const auto& o = watch_.Orders()[i];
      if (o.deputy_id == d && o.sheriff_id != "mallory" && o.num_commands == 1 &&
          o.commands[0].desired_running) {
        start_order = watch_.RawOrders()[i];
      }
    }
    return !start_order.empty();
  }));
  ASSERT_EQ(Sheriff(pmd, {"stop", "victim"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsStopped(d, "victim"); }));
  watch_.lcm().publish("PM_ORDERS", start_order.data(), static_cast<unsigned>(start_order.size()));
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Info(d).refused_orders == 4; }));
  watch_.Spin(1.0);
  EXPECT_TRUE(watch_.IsStopped(d, "victim"))
      << "state " << (watch_.Command(d, "victim") ? watch_.Command(d, "victim")->state : -1);
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(1)).empty());

  // 5. The same replay after a deputy restart (nothing kept on disk): another session.
  deputy->Signal(SIGTERM);
  ASSERT_NE(deputy->Wait(10), -1);
  const std::string log1 = deputy->Log();
  deputy.reset();
  watch_.Spin(0.2);
  auto restarted = StartDeputy(d, "deputy2.log");
  watch_.lcm().publish("PM_ORDERS", start_order.data(), static_cast<unsigned>(start_order.size()));
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Info(d).refused_orders == 1; }));
  watch_.Spin(1.0);
  EXPECT_EQ(watch_.Command(d, "victim"), nullptr);  // a fresh deputy: ordered nothing
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(1)).empty());

  // Each refusal is logged with its reason.
  EXPECT_NE(log1.find("REFUSED orders claiming sheriff 'mallory'"), std::string::npos) << log1;
  EXPECT_NE(log1.find(": unsigned;"), std::string::npos) << log1;
  EXPECT_NE(log1.find(": forged"), std::string::npos) << log1;
  EXPECT_NE(log1.find(": replayed"), std::string::npos) << log1;
  EXPECT_NE(restarted->Log().find(": for another deputy session"), std::string::npos)
      << restarted->Log();
}

TEST_F(ProcmanSystem, StaleResendOfAnotherSheriffDoesNotUndoAChange) {
  const std::string d = deputy_id_;
  const std::string pmd = Pmd(Cmd("x", SleepCmd(1)) + "\n");
  auto deputy = StartDeputy(d);
  ASSERT_EQ(Sheriff(pmd, {"start", "x"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsRunning(d, "x"); }));
  const int pid = watch_.Pid(d, "x");
  const int32_t runid = watch_.Command(d, "x")->actual_runid;
  // A genuine, newer (by counter) re-send from a sheriff that has not seen the start yet.
  const int64_t now_us = watch_.DeputyClockUs(d);
  sarmap::pm_orders_t stale = EvilOrders(d, SleepCmd(1), now_us);
  stale.deputy_session = watch_.Info(d).session;
  stale.sheriff_id = "other-sheriff/1";
  stale.commands[0].command_id = "x";
  stale.commands[0].desired_running = false;
  stale.commands[0].desired_runid = runid - 1;
  SignOrders(LoadKeyFile(scratch_.key()), &stale);
  watch_.lcm().publish("PM_ORDERS", &stale);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Info(d).last_order_counter == now_us; }));
  watch_.Spin(1.0);
  EXPECT_TRUE(watch_.IsRunning(d, "x"));
  EXPECT_EQ(watch_.Pid(d, "x"), pid);
  EXPECT_EQ(watch_.Info(d).refused_orders, 0);
}

TEST_F(ProcmanSystem, RestartingTheSheriffDisturbsNoRunningProcess) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd("group \"g\" {\n  " + Cmd("a", SleepCmd(1)) + "\n  " +
          Cmd("b", SleepCmd(2), " auto_respawn = true;") + "\n}\n" + Cmd("c", SleepCmd(3)) + "\n");
  auto deputy = StartDeputy(d);
  const std::vector<std::string> live_argv = {BinDir() + "/sarmap-procman", pmd, "--key",
                                              scratch_.key()};
  auto sheriff_a = std::make_unique<Child>(live_argv, scratch_.dir() + "/sheriff-a.log");
  ASSERT_EQ(Sheriff(pmd, {"start", "g"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsRunning(d, "a") && watch_.IsRunning(d, "b"); }));
  const int pid_a = watch_.Pid(d, "a");
  int pid_b = watch_.Pid(d, "b");
  // The live sheriff follows the one-shot command's orders and keeps re-sending them.
  watch_.Spin(2.5);
  EXPECT_EQ(watch_.Pid(d, "a"), pid_a);
  EXPECT_EQ(watch_.Pid(d, "b"), pid_b);

  // Sheriff gone: the deputy carries on, and still respawns what crashes.
  sheriff_a->Signal(SIGINT);
  ASSERT_NE(sheriff_a->Wait(10), -1);
  kill(pid_b, SIGKILL);
  ASSERT_TRUE(
      watch_.WaitFor([&] { return watch_.IsRunning(d, "b") && watch_.Pid(d, "b") != pid_b; }));
  EXPECT_EQ(watch_.Command(d, "b")->restart_count, 1);
  pid_b = watch_.Pid(d, "b");
  watch_.Spin(2.0);
  EXPECT_EQ(watch_.Pid(d, "a"), pid_a);
  EXPECT_EQ(watch_.Pid(d, "b"), pid_b);

  // A new sheriff adopts the running state and re-sends it: nothing is touched.
  const size_t orders_before = watch_.Orders().size();
  auto sheriff_b = std::make_unique<Child>(live_argv, scratch_.dir() + "/sheriff-b.log");
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Orders().size() >= orders_before + 3; }));
  int64_t counter_b = -1;  // of the new sheriff's latest orders to d (not a probe)
  for (const auto& o : watch_.Orders()) {
    if (o.deputy_id == d) counter_b = o.counter;
  }
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.Info(d).last_order_counter >= counter_b; }));
  watch_.Spin(1.0);
  for (const char* id : {"a", "b"}) {
    const auto* c = watch_.Command(d, id);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(+c->state, +Status::STATE_RUNNING) << id;
    EXPECT_EQ(c->restart_count, id[0] == 'b' ? 1 : 0) << id;  // b: the respawn above only
    EXPECT_EQ(c->actual_runid, 1) << id;
  }
  EXPECT_EQ(watch_.Pid(d, "a"), pid_a);
  EXPECT_EQ(watch_.Pid(d, "b"), pid_b);
  EXPECT_TRUE(Alive(pid_a));
  EXPECT_TRUE(Alive(pid_b));
  EXPECT_TRUE(watch_.IsStopped(d, "c"));
  EXPECT_EQ(watch_.Info(d).refused_orders, 0);
  printf("FIGURE sheriff restart: pids %d %d unchanged after %zu orders from the new sheriff\n",
         pid_a, pid_b, watch_.Orders().size() - orders_before);

  // And the live sheriff follows a one-shot stop instead of undoing it.
  ASSERT_EQ(Sheriff(pmd, {"stop", "everything"}).exit_code, 0);
  watch_.Spin(2.5);
  EXPECT_TRUE(watch_.IsStopped(d, "a"));
  EXPECT_TRUE(watch_.IsStopped(d, "b"));
  sheriff_b->Signal(SIGINT);
  EXPECT_NE(sheriff_b->Wait(10), -1);
}

TEST_F(ProcmanSystem, LoneRangerBringsUpAndTearsDownOneComputer) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd("group \"all\" {\n  " + Cmd("a", SleepCmd(1)) + "\n  " +
          Cmd("b", "sh -c '" + SleepCmd(2) + " & " + SleepCmd(2) + "'", " stop_time_allowed = 1;") +
          "\n}\n"
          "script \"up\" { start group \"all\" wait \"running\" timeout 10; }\n");
  Child lone(
      {BinDir() + "/sarmap-procman", pmd, "--key", scratch_.key(), "--lone-ranger", "run", "up"},
      scratch_.dir() + "/lone.log");
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsRunning(d, "a") && watch_.IsRunning(d, "b"); }))
      << lone.Log();
  ASSERT_TRUE(watch_.WaitFor([&] { return ProcessesWithCmdline(SleepCmd(2)).size() == 2; }, 5));
  lone.Signal(SIGINT);
  const int status = lone.Wait(15);
  ASSERT_NE(status, -1);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << lone.Log();
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(1)).empty());
  EXPECT_TRUE(ProcessesWithCmdline(SleepCmd(2)).empty());
}

// A killed deputy takes its commands along (they must not run on, unsupervised), and the
// sheriff's script fails instead of waiting for its whole timeout.
TEST_F(ProcmanSystem, KilledDeputyTakesItsCommandsAlongAndTheScriptFails) {
  const std::string d = deputy_id_;
  const std::string pmd = Pmd("group \"g\" {\n  " + Cmd("a", SleepCmd(1)) + "\n  " +
                              Cmd("b", SleepCmd(2), " auto_respawn = true;") + "\n}\n" +
                              "script \"mission\" {\n"
                              "  start group \"g\" wait \"running\" timeout 10;\n"
                              "  wait cmd \"a\" status \"stopped\" timeout 1800;\n"
                              "}\n");
  auto deputy = StartDeputy(d);
  Child sheriff({BinDir() + "/sarmap-procman", pmd, "--key", scratch_.key(), "--set",
                 "deputy_gone_after_s=3", "run", "mission"},
                scratch_.dir() + "/sheriff-mission.log");
  ASSERT_TRUE(watch_.WaitFor([&] { return watch_.IsRunning(d, "a") && watch_.IsRunning(d, "b"); }));
  const std::vector<ProcInfo> before = Snapshot({watch_.Pid(d, "a"), watch_.Pid(d, "b")});
  deputy->Signal(SIGKILL);
  ASSERT_NE(deputy->Wait(10), -1);
  // Its commands die with it...
  EXPECT_TRUE(watch_.WaitFor(
      [&] {
        return ProcessesWithCmdline(SleepCmd(1)).empty() &&
               ProcessesWithCmdline(SleepCmd(2)).empty();
      },
      10));
  for (const ProcInfo& p : before) EXPECT_FALSE(StillRunning(p)) << p.pid;
  // ...and the script ends at once with a clear reason, not after 1800 s.
  const int status = sheriff.Wait(60);
  ASSERT_NE(status, -1) << sheriff.Log();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << sheriff.Log();
  EXPECT_NE(sheriff.Log().find("wait cmd \"a\" status \"stopped\": deputy '" + d + "' silent for"),
            std::string::npos)
      << sheriff.Log();
}

// What a command forked (a shell's jobs, in the command's process group) dies with a killed
// deputy too: its group guardian kills the group. Before, only the command itself died
// (PR_SET_PDEATHSIG) and the three sleeps below ran on.
TEST_F(ProcmanSystem, KilledDeputyTakesWhatItsCommandsForkedAlong) {
  const std::string d = deputy_id_;
  const std::string s = SleepCmd(3);
  const std::string pmd = Pmd(Cmd("family", "sh -c '" + s + " & " + s + " & " + s + "'") + "\n");
  auto deputy = StartDeputy(d);
  ASSERT_EQ(Sheriff(pmd, {"start", "family"}).exit_code, 0);
  ASSERT_TRUE(watch_.WaitFor([&] { return ProcessesWithCmdline(s).size() == 3; }, 5));
  const std::vector<ProcInfo> before = Snapshot(ProcessesWithCmdline(s));
  deputy->Signal(SIGKILL);
  ASSERT_NE(deputy->Wait(10), -1);
  EXPECT_TRUE(watch_.WaitFor([&] { return ProcessesWithCmdline(s).empty(); }, 10))
      << ProcessesWithCmdline(s).size() << " still running";
  for (const ProcInfo& p : before) EXPECT_FALSE(StillRunning(p)) << p.pid;
}

TEST_F(ProcmanSystem, ScriptWaitTimesOutWithLocation) {
  const std::string d = deputy_id_;
  const std::string pmd =
      Pmd(Cmd("dies", "no-such-program-xyz") +
          "\n"
          "script \"s\" {\n  start cmd \"dies\" wait \"running\" timeout 2;\n}\n");
  auto deputy = StartDeputy(d);
  const CliResult r = Sheriff(pmd, {"run", "s"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("test.pmd:3:3: start cmd \"dies\" wait \"running\": timed out after 2 s: "
                          "'dies' is failed "
                          "(last exit code 127)"),
            std::string::npos);
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
