#pragma once
// Turns a command's exec line into what execve() needs, without a shell:
//
//   "LD_LIBRARY_PATH=/opt/x sarmap-slam --config '$HOME/my cfg.yaml' --set a=${N}"
//
// Words are separated by blanks; '...' quotes literally, "..." quotes with $VAR expansion,
// backslash escapes the next character. $NAME and ${NAME} expand from the deputy's
// environment (unset: empty; ${NAME:-default} gives a default). Leading NAME=VALUE words are
// environment assignments for the command (as in sh). Shell syntax that needs a real shell (| & ; <
// > ` $( ) outside quotes) is an error that says to set use_shell.

#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sarmap {
namespace procman {

struct ExecPlan {
  std::vector<std::pair<std::string, std::string>> env;  // assignments, in order
  std::vector<std::string> argv;                         // argv[0] = program
};

using EnvLookup = std::function<const char*(const std::string&)>;

// Throws std::invalid_argument with a one-line reason.
ExecPlan PlanExec(const std::string& exec, const EnvLookup& lookup);

// The full path of `program` searched in `path_list` (":"-separated), or "" if not found
// executable. A program containing '/' is returned as is when executable.
std::string FindExecutable(const std::string& program, const std::string& path_list);

}  // namespace procman
}  // namespace sarmap
