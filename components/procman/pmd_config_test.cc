#include "procman/pmd_config.h"

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>

namespace sarmap {
namespace procman {
namespace {

const char* kExample = R"(# two computers
group "sensors" {
  cmd "sarmap-depth" {
    exec = "sarmap-depth --device kinect";
    deputy = "sensors";
    auto_respawn = true;
    stop_signal = SIGTERM;
    stop_time_allowed = 2.5;
  }
  group "audio" {
    cmd "sarmap-audio-capture" { exec = "sarmap-audio-capture"; host = "sensors"; }
  }
}
cmd "sarmap-slam" {
  exec = "sarmap-slam";
  deputy = "compute";
  use_shell = "false";
}
script "bring-up" {
  start group "sensors" wait "running" timeout 5;
  wait ms 250;
  start cmd "sarmap-slam";
  wait cmd "sarmap-slam" status "running";
  run_script "down";
}
script "down" {
  stop everything wait "stopped";
  restart group "sensors/audio";
}
)";

TEST(PmdConfig, ParsesProcmanSyntax) {
  const Config c = ParseConfig(kExample, "two.pmd");
  ASSERT_EQ(c.commands.size(), 3u);
  const CommandConfig* depth = c.FindCommand("sarmap-depth");
  ASSERT_NE(depth, nullptr);
  EXPECT_EQ(depth->group, "sensors");
  EXPECT_EQ(depth->deputy, "sensors");
  EXPECT_TRUE(depth->auto_respawn);
  EXPECT_EQ(depth->stop_signal, SIGTERM);
  EXPECT_DOUBLE_EQ(depth->stop_time_allowed_s, 2.5);
  EXPECT_EQ(depth->where.ToString(), "two.pmd:3:3");
  const CommandConfig* audio = c.FindCommand("sarmap-audio-capture");
  ASSERT_NE(audio, nullptr);
  EXPECT_EQ(audio->group, "sensors/audio");
  EXPECT_EQ(audio->deputy, "sensors");
  EXPECT_FALSE(audio->auto_respawn);
  EXPECT_EQ(audio->stop_signal, SIGINT);
  const CommandConfig* slam = c.FindCommand("sarmap-slam");
  EXPECT_EQ(slam->group, "");
  EXPECT_EQ(slam->deputy, "compute");
  EXPECT_EQ(c.Deputies(), (std::vector<std::string>{"sensors", "compute"}));

  ASSERT_EQ(c.scripts.size(), 2u);
  const Script* up = c.FindScript("bring-up");
  ASSERT_EQ(up->actions.size(), 5u);
  EXPECT_EQ(up->actions[0].kind, ScriptAction::kStart);
  EXPECT_EQ(up->actions[0].target.kind, Target::kGroup);
  EXPECT_EQ(up->actions[0].wait_status, "running");
  EXPECT_DOUBLE_EQ(up->actions[0].timeout_s, 5.0);
  EXPECT_EQ(up->actions[1].kind, ScriptAction::kWaitMs);
  EXPECT_EQ(up->actions[1].wait_ms, 250);
  EXPECT_EQ(up->actions[2].wait_status, "");
  EXPECT_EQ(up->actions[3].kind, ScriptAction::kWaitStatus);
  EXPECT_DOUBLE_EQ(up->actions[3].timeout_s, 30.0);
  EXPECT_EQ(up->actions[4].kind, ScriptAction::kRunScript);
  EXPECT_EQ(up->actions[4].script, "down");
  EXPECT_EQ(c.FindScript("down")->actions[0].target.kind, Target::kEverything);
}

TEST(PmdConfig, SelectsGroupsRecursively) {
  const Config c = ParseConfig(kExample, "two.pmd");
  Target sensors{Target::kGroup, "sensors"};
  auto selected = c.Select(sensors);
  ASSERT_EQ(selected.size(), 2u);
  EXPECT_EQ(selected[1]->id, "sarmap-audio-capture");
  EXPECT_EQ(c.Select(Target{Target::kGroup, "sensors/audio"}).size(), 1u);
  EXPECT_EQ(c.Select(Target{}).size(), 3u);
  EXPECT_FALSE(c.HasGroup("sens"));  // a prefix of a name is not a group
  EXPECT_EQ(c.ResolveTarget("sarmap-slam").kind, Target::kCommand);
  EXPECT_EQ(c.ResolveTarget("sensors/audio").kind, Target::kGroup);
  EXPECT_EQ(c.ResolveTarget("everything").kind, Target::kEverything);
  EXPECT_THROW(c.ResolveTarget("nope"), ConfigError);
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseConfig(text, "bad.pmd");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PmdConfig, ErrorsNameFileLineAndColumn) {
  EXPECT_EQ(ErrorOf("cmd \"a\" {\n  exec = \"x\"\n}\n"),
            "bad.pmd:3:1: expected ';' after the value of 'exec', found '}'");
  EXPECT_EQ(ErrorOf("cmd \"a\" {\n  exec = \"x\";\n  colour = \"red\";\n}"),
            "bad.pmd:3:3: unknown attribute 'colour' (known: exec, deputy/host, auto_respawn, "
            "stop_signal, stop_time_allowed, use_shell)");
  EXPECT_EQ(ErrorOf("cmd \"a\" { exec = \"x\"; stop_signal = SIGFOO; }"),
            "bad.pmd:1:37: unknown signal 'SIGFOO' (e.g. SIGINT, SIGTERM, 15)");
  EXPECT_EQ(ErrorOf("cmd \"a\" { deputy = \"d\"; }"), "bad.pmd:1:25: command \"a\" has no exec");
  EXPECT_EQ(ErrorOf("cmd \"a\" { exec = \"x\"; }\ncmd \"a\" { exec = \"y\"; }"),
            "bad.pmd:2:5: duplicate command \"a\" (first defined at bad.pmd:1:1)");
  EXPECT_EQ(ErrorOf("script \"s\" {\n  start cmd \"ghost\";\n}"),
            "bad.pmd:2:13: no command \"ghost\"");
  EXPECT_EQ(ErrorOf("cmd \"a\" { exec = \"x\"; }\nscript \"s\" { wait cmd \"a\" status \"up\"; }"),
            "bad.pmd:2:34: status must be \"running\" or \"stopped\", is \"up\"");
  EXPECT_EQ(ErrorOf("script \"s\" { run_script \"t\"; }\nscript \"t\" { run_script \"s\"; }"),
            "bad.pmd:2:14: run_script \"s\" makes a cycle");
  EXPECT_EQ(ErrorOf("cmd \"a\" {\n  exec = \"a | b\";\n}"),
            "bad.pmd:2:10: exec \"a | b\": '|' is shell syntax; set use_shell = true to run "
            "through /bin/sh");
  EXPECT_EQ(ErrorOf("cmd \"a\" { exec = \"x;\n"),
            "bad.pmd:1:18: unterminated string (newline inside quotes)");
  EXPECT_EQ(ErrorOf("group \"g\" { cmd \"a\" { exec = \"x\"; }"),
            "bad.pmd:1:36: expected 'cmd', 'group' or '}' in group \"g\", found end of file");
  EXPECT_EQ(ErrorOf("cmd \"a\" { exec = \"x\"; }\nscript \"s\" { start cmd \"a\" wait \"running\" "
                    "timeout -1; }"),
            "bad.pmd:2:51: timeout must be a positive number of seconds, found '-1'");
}

TEST(PmdConfig, LaunchScriptsInTheRepositoryParse) {
  for (const char* name :
       {"sim-demo.pmd", "robot-one-computer.pmd", "robot-two-computers.pmd", "replay.pmd", "handheld.pmd"}) {
    const std::string path = std::string(SARMAP_SOURCE_DIR) + "/launch-scripts/" + name;
    SCOPED_TRACE(path);
    const Config c = LoadConfigFile(path);
    EXPECT_FALSE(c.commands.empty());
    EXPECT_FALSE(c.scripts.empty());
  }
  const Config two =
      LoadConfigFile(std::string(SARMAP_SOURCE_DIR) + "/launch-scripts/robot-two-computers.pmd");
  EXPECT_EQ(two.Deputies(), (std::vector<std::string>{"sensors", "compute"}));
}

TEST(PmdConfig, ParsesSignals) {
  EXPECT_EQ(ParseSignal("SIGINT"), SIGINT);
  EXPECT_EQ(ParseSignal("term"), SIGTERM);
  EXPECT_EQ(ParseSignal("9"), SIGKILL);
  EXPECT_EQ(ParseSignal("SIGWHAT"), -1);
  EXPECT_EQ(ParseSignal("99"), -1);
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
