#pragma once
// The procman launch configuration (.pmd), in libbot2 procman's syntax plus timeouts:
//
//   # comment
//   group "sensors" {
//     cmd "sarmap-depth" {
//       exec = "sarmap-depth --config $SARMAP_CONFIG/depth.yaml";
//       deputy = "sensors";            # or: host = "sensors"
//       auto_respawn = true;
//       stop_signal = SIGINT;          # name or number
//       stop_time_allowed = 5;         # seconds, then SIGKILL
//       use_shell = false;             # run through /bin/sh -c
//     }
//     group "nested" { cmd "x" { exec = "sleep 100"; } }
//   }
//   script "bring-up" {
//     start group "sensors" wait "running" timeout 10;
//     wait ms 500;
//     start cmd "sarmap-slam";
//     wait cmd "sarmap-slam" status "running";
//     restart everything;
//     run_script "other";
//   }
//
// Unlike procman, every wait has a timeout (`timeout SECONDS`, default 30 s) and every error
// names file:line:col.

#include <stdexcept>
#include <string>
#include <vector>

namespace sarmap {
namespace procman {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Location {
  std::string file;
  int line = 0;
  int col = 0;
  std::string ToString() const;
};

struct CommandConfig {
  std::string id;     // cmd "id"
  std::string group;  // "/"-separated path of enclosing groups, "" at top level
  std::string exec;
  std::string deputy = "localhost";
  bool auto_respawn = false;
  bool use_shell = false;
  int stop_signal = 2;  // SIGINT
  double stop_time_allowed_s = 7.0;
  Location where;
};

// What a script action applies to.
struct Target {
  enum Kind { kCommand, kGroup, kEverything } kind = kEverything;
  std::string name;  // command id or group path
  std::string ToString() const;
};

struct ScriptAction {
  enum Kind { kStart, kStop, kRestart, kWaitMs, kWaitStatus, kRunScript } kind = kStart;
  Target target;            // start/stop/restart/wait-status
  std::string wait_status;  // "" (no wait), "running" or "stopped"
  double timeout_s = 30.0;  // for any wait
  int wait_ms = 0;          // kWaitMs
  std::string script;       // kRunScript
  Location where;
};

struct Script {
  std::string name;
  std::vector<ScriptAction> actions;
  Location where;
};

struct Config {
  std::string source;  // file name
  std::vector<CommandConfig> commands;
  std::vector<Script> scripts;

  const CommandConfig* FindCommand(const std::string& id) const;
  const Script* FindScript(const std::string& name) const;
  // True when `path` names a group (exactly, or as an ancestor of some command's group).
  bool HasGroup(const std::string& path) const;
  // Commands a target selects, in config order.
  std::vector<const CommandConfig*> Select(const Target& target) const;
  // Deputies named in the config, in first-use order.
  std::vector<std::string> Deputies() const;
  // Resolves a name given on the command line: "everything"/"all", a command id, or a
  // group path (a command wins over a group of the same name; "group:NAME" forces a group).
  // Throws ConfigError when nothing matches.
  Target ResolveTarget(const std::string& name) const;
};

// Parses .pmd text; `source` names it in errors. Throws ConfigError("file:line:col: ...").
Config ParseConfig(const std::string& text, const std::string& source);
Config LoadConfigFile(const std::string& path);

// Signal names ("SIGINT", "INT", "15") to numbers; -1 when unknown.
int ParseSignal(const std::string& text);

}  // namespace procman
}  // namespace sarmap
