// The supervisor against real processes (short-lived sleep/sh commands).
#include "procman/supervisor.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>

#include <chrono>
#include <functional>
#include <thread>

#include "procman/process_table.h"

namespace sarmap {
namespace procman {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

CommandSpec Spec(const std::string& id, const std::string& exec, bool run, int runid = 1) {
  CommandSpec s;
  s.id = id;
  s.exec = exec;
  s.desired_running = run;
  s.desired_runid = runid;
  s.stop_time_allowed_s = 2.0;
  return s;
}

// A command line in shell syntax, run through the shell, ordered to run, with
// `stop_time_allowed_s` between its stop signal and SIGKILL.
CommandSpec ShellSpec(const std::string& id, const std::string& script,
                      double stop_time_allowed_s) {
  CommandSpec s = Spec(id, script, true);
  s.use_shell = true;
  s.stop_time_allowed_s = stop_time_allowed_s;
  return s;
}

const CommandStatus* Find(const std::vector<CommandStatus>& all, const std::string& id) {
  for (const auto& s : all) {
    if (s.id == id) return &s;
  }
  return nullptr;
}

// Steps the supervisor (as the deputy's loop does) until `done` or `limit_s` passed; the
// limit only bounds a broken run, nothing is asserted on time.
bool StepUntil(Supervisor* sup, const std::function<bool()>& done, double limit_s = 10.0) {
  const double end = Now() + limit_s;
  while (Now() < end) {
    sup->Step(Now());
    if (done()) return true;
    std::vector<pollfd> fds;
    for (int fd : sup->OutputFds()) fds.push_back({fd, POLLIN, 0});
    poll(fds.data(), fds.size(), 10);
  }
  return false;
}

CommandState StateOf(Supervisor* sup, const std::string& id) {
  const auto all = sup->Status();
  const CommandStatus* s = Find(all, id);
  return s ? s->state : CommandState::kStopped;
}

std::string AllOutput(Supervisor* sup, std::string* acc) {
  for (auto& [id, text] : sup->TakeOutput(1 << 20)) *acc += text;
  return *acc;
}

TEST(Supervisor, CommandsStartWithTheGivenEnvironmentNotTheLaunchers) {
  // Only what the supervisor is given: a variable of this process's own is not passed on, and
  // ${NAME} in the exec line and PATH lookups use the given environment.
  setenv("SARMAP_SUPERVISOR_TEST_OWN", "leaked", 1);
  Supervisor sup(RespawnPolicy(), 65536,
                 Environment{{"PATH", "/usr/bin:/bin"}, {"MISSION", "site-7"}});
  unsetenv("SARMAP_SUPERVISOR_TEST_OWN");
  sup.SetDesired({Spec("env", "sh -c 'echo [$MISSION][$SARMAP_SUPERVISOR_TEST_OWN][$0]' ${MISSION}",
                       true)});
  std::string out;
  ASSERT_TRUE(StepUntil(&sup, [&] {
    return StateOf(&sup, "env") == CommandState::kStopped &&
           AllOutput(&sup, &out).find('\n') != std::string::npos;
  }));
  EXPECT_EQ(out.substr(0, out.find('\n') + 1), "[site-7][][site-7]\n") << out;
}

TEST(Supervisor, InheritedEnvironmentPutsTheLaunchersDirectoryFirstOnPath) {
  const Environment plain = InheritedEnvironment();
  const Environment with_bin = InheritedEnvironment("/opt/sarmap/bin");
  ASSERT_EQ(with_bin.count("PATH"), 1u);
  const std::string expected_rest =
      plain.count("PATH") ? plain.at("PATH") : std::string("/usr/local/bin:/usr/bin:/bin");
  EXPECT_EQ(with_bin.at("PATH"), "/opt/sarmap/bin:" + expected_rest);
  EXPECT_EQ(with_bin.size(), plain.size() + (plain.count("PATH") ? 0 : 1));
  EXPECT_FALSE(OwnDirectory().empty());
}

TEST(Supervisor, StartsStopsAndCapturesOutput) {
  Supervisor sup;
  sup.SetDesired(
      {Spec("hello", "GREETING=hi sh -c 'echo $GREETING $0 && echo err >&2' from-procman", true),
       Spec("sleeper", "sleep 100", true)});
  std::string out;
  ASSERT_TRUE(StepUntil(&sup, [&] {
    return StateOf(&sup, "hello") == CommandState::kStopped &&
           AllOutput(&sup, &out).find("err") != std::string::npos;
  }));
  EXPECT_NE(out.find("hi from-procman\n"), std::string::npos) << out;
  EXPECT_EQ(Find(sup.Status(), "hello")->exit_code, 0);
  const CommandStatus* s = Find(sup.Status(), "sleeper");
  ASSERT_EQ(s->state, CommandState::kRunning);
  const int pid = s->pid;
  ProcInfo info;
  ASSERT_TRUE(ReadProcInfo(pid, &info));
  EXPECT_EQ(info.pgid, pid);  // its own process group

  sup.SetDesired({Spec("hello", "true", false), Spec("sleeper", "sleep 100", false)});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "sleeper") == CommandState::kStopped; }));
  EXPECT_EQ(Find(sup.Status(), "sleeper")->exit_code, 128 + SIGINT);
  EXPECT_FALSE(ReadProcInfo(pid, &info) && info.state != 'Z');
}

// Several deputies in one process (--lone-ranger) each reap with waitpid(-1): an exit reaped
// by one Supervisor reaches the one that owns the command (lost, the owner would never see
// its command exit and a stop would never end).
TEST(Supervisor, TwoSupervisorsInOneProcessEachSeeTheirCommandsExit) {
  Supervisor a, b;
  a.SetDesired({Spec("a", "sh -c 'exit 3'", true)});
  b.SetDesired({Spec("b", "sleep 100", true)});
  ASSERT_TRUE(StepUntil(&b, [&] { return StateOf(&b, "b") == CommandState::kRunning; }));
  usleep(200000);  // "a" exits meanwhile...
  b.Step(Now());   // ...and b reaps it first
  ASSERT_TRUE(StepUntil(&a, [&] { return StateOf(&a, "a") == CommandState::kFailed; }));
  EXPECT_EQ(Find(a.Status(), "a")->exit_code, 3);
  // And the other way round, on a stop.
  b.SetDesired({Spec("b", "sleep 100", false)});
  b.Step(Now());  // sends SIGINT
  usleep(200000);
  a.Step(Now());  // a reaps b's command
  ASSERT_TRUE(StepUntil(&b, [&] { return StateOf(&b, "b") == CommandState::kStopped; }));
  EXPECT_EQ(Find(b.Status(), "b")->exit_code, 128 + SIGINT);
}

TEST(Supervisor, RestartOnNewRunId) {
  Supervisor sup;
  sup.SetDesired({Spec("s", "sleep 100", true, 1)});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "s") == CommandState::kRunning; }));
  const int first = Find(sup.Status(), "s")->pid;
  sup.SetDesired({Spec("s", "sleep 100", true, 2)});
  ASSERT_TRUE(StepUntil(&sup, [&] {
    const auto st = sup.Status();
    return st[0].state == CommandState::kRunning && st[0].pid != first;
  }));
  EXPECT_EQ(Find(sup.Status(), "s")->actual_runid, 2);
}

TEST(Supervisor, IgnoredStopSignalEscalatesToSigkill) {
  Supervisor sup;
  CommandSpec s = ShellSpec("stubborn", "trap '' INT; echo ready; exec sleep 100", 0.3);
  sup.SetDesired({s});
  std::string out;
  ASSERT_TRUE(
      StepUntil(&sup, [&] { return AllOutput(&sup, &out).find("ready") != std::string::npos; }));
  s.desired_running = false;
  sup.SetDesired({s});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "stubborn") == CommandState::kStopped; }));
  EXPECT_EQ(Find(sup.Status(), "stubborn")->exit_code, 128 + SIGKILL);
  EXPECT_NE(AllOutput(&sup, &out).find("sending SIGKILL"), std::string::npos) << out;
}

std::vector<int> LiveDescendantsWithMarker(const std::string& marker) {
  // Processes whose command line holds the marker.
  std::vector<int> out;
  const ProcessTable table = ProcessTable::Snapshot();
  for (const auto& [pid, info] : table.processes()) {
    if (info.state == 'Z') continue;
    FILE* f = fopen(("/proc/" + std::to_string(pid) + "/cmdline").c_str(), "r");
    if (!f) continue;
    char buf[512] = {0};
    const size_t n = fread(buf, 1, sizeof(buf) - 1, f);
    fclose(f);
    for (size_t i = 0; i < n; ++i) {
      if (buf[i] == 0) buf[i] = ' ';
    }
    if (n > 0 && std::string(buf, n - 1) == marker) out.push_back(pid);
  }
  return out;
}

TEST(Supervisor, NoDescendantSurvivesAStop) {
  ASSERT_TRUE(BecomeSubreaper());
  Supervisor sup;
  // Background children of a non-interactive sh ignore SIGINT; one even leaves the group.
  const std::string marker = "31" + std::to_string(getpid());  // unique sleep length
  CommandSpec s = ShellSpec(
      "family", "sleep " + marker + " & setsid sleep " + marker + " & sleep " + marker, 0.5);
  sup.SetDesired({s});
  ASSERT_TRUE(
      StepUntil(&sup, [&] { return LiveDescendantsWithMarker("sleep " + marker).size() == 3; }));
  sup.UpdateUsage(Now());  // the deputy samples the tree at 1 Hz; it also walks it at stop
  s.desired_running = false;
  sup.SetDesired({s});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "family") == CommandState::kStopped; }));
  EXPECT_TRUE(LiveDescendantsWithMarker("sleep " + marker).empty());
}

TEST(Supervisor, OutputBeyondTheBufferIsDroppedAndCounted) {
  Supervisor sup(RespawnPolicy(), 1000);
  sup.SetDesired({Spec("loud", "sh -c 'yes | head -c 5000; echo END'", true)});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "loud") == CommandState::kStopped; }));
  for (int i = 0; i < 5; ++i) sup.Step(Now());
  std::string out;
  auto first = sup.TakeOutput(300);
  ASSERT_EQ(first.size(), 1u);
  out = first[0].second;
  EXPECT_EQ(out.rfind("[procman] ", 0), 0u) << out;  // the note comes first
  EXPECT_NE(out.find("bytes of output dropped"), std::string::npos) << out;
  for (int i = 0; i < 10; ++i) {
    for (auto& [id, text] : sup.TakeOutput(300)) out += text;
  }
  EXPECT_NE(out.find("END\n"), std::string::npos);  // the newest output is kept
}

TEST(Supervisor, CrashingCommandIsRespawnedWithBackoff) {
  RespawnPolicy policy;
  // The first four respawns of a crash loop each come within a second (0.1, 0.2, 0.4, 0.8 s).
  for (int k = 0; k < 4; ++k) EXPECT_LT(policy.Delay(k), 1.0) << k;
  EXPECT_GT(policy.Delay(4), 1.0);
  EXPECT_DOUBLE_EQ(policy.Delay(20), policy.max_s);
  Supervisor sup(policy);
  CommandSpec s = Spec("crasher", "sh -c 'exit 3'", true);
  s.auto_respawn = true;
  sup.SetDesired({s});
  ASSERT_TRUE(StepUntil(&sup, [&] { return Find(sup.Status(), "crasher")->restart_count >= 2; }));
  EXPECT_EQ(Find(sup.Status(), "crasher")->exit_code, 3);
  s.desired_running = false;
  sup.SetDesired({s});
  ASSERT_TRUE(StepUntil(&sup, [&] {
    const auto st = StateOf(&sup, "crasher");
    return st == CommandState::kStopped || st == CommandState::kFailed;
  }));
}

TEST(Supervisor, CommandThatExitsIsNotRestartedForTheSameRun) {
  Supervisor sup;
  sup.SetDesired({Spec("once", "sh -c 'exit 4'", true, 1)});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "once") == CommandState::kFailed; }));
  for (int i = 0; i < 5; ++i) sup.Step(Now());
  EXPECT_EQ(StateOf(&sup, "once"), CommandState::kFailed);
  EXPECT_EQ(Find(sup.Status(), "once")->exit_code, 4);
}

TEST(Supervisor, MissingProgramFailsWithAReason) {
  Supervisor sup;
  sup.SetDesired({Spec("ghost", "no-such-program-xyz --flag", true), Spec("bad", "a | b", true)});
  std::string out;
  ASSERT_TRUE(StepUntil(&sup, [&] {
    return StateOf(&sup, "ghost") == CommandState::kFailed &&
           StateOf(&sup, "bad") == CommandState::kFailed;
  }));
  EXPECT_EQ(Find(sup.Status(), "ghost")->exit_code, 127);
  AllOutput(&sup, &out);
  EXPECT_NE(out.find("'no-such-program-xyz' not found"), std::string::npos) << out;
  EXPECT_NE(out.find("use_shell"), std::string::npos) << out;
}

TEST(Supervisor, ForgetsCommandsNoLongerOrderedAfterStoppingThem) {
  Supervisor sup;
  sup.SetDesired({Spec("a", "sleep 100", true)});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "a") == CommandState::kRunning; }));
  sup.SetDesired({});
  ASSERT_TRUE(StepUntil(&sup, [&] { return sup.Status().empty(); }));
}

TEST(Supervisor, CountsCpuAndMemoryOfChildren) {
  Supervisor sup;
  CommandSpec s = ShellSpec("busy", "while :; do :; done & sleep 100", 0.3);
  sup.SetDesired({s});
  ASSERT_TRUE(StepUntil(&sup, [&] { return StateOf(&sup, "busy") == CommandState::kRunning; }));
  sup.UpdateUsage(Now());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  sup.UpdateUsage(Now());
  const CommandStatus* st = Find(sup.Status(), "busy");
  // The busy loop is a child of the command's sh (which itself only waits): counted. The
  // share it gets depends on the machine's load, so only "clearly more than nothing".
  EXPECT_GT(st->cpu_percent, 2.0);
  EXPECT_GT(st->rss_bytes, 0);
  sup.Shutdown();
  ASSERT_TRUE(StepUntil(&sup, [&] { return sup.AllStopped(); }));
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
