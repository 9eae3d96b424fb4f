#pragma once
// Starting and stopping real processes from a test driver.

#include <signal.h>
#include <sys/types.h>

#include <string>
#include <vector>

namespace sarmap {
namespace testing {

// Directory of the built executables ($SARMAP_BIN_DIR, else the build's bin/).
std::string BinDir();

class Process {
 public:
  // Starts `args` (args[0] resolved in BinDir() when it has no '/'), stdout+stderr to
  // `output_path` ("" = inherit).
  Process(std::vector<std::string> args, const std::string& output_path = "");
  ~Process();  // SIGKILLs the process if still running
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  bool Running();
  void Signal(int sig);
  // Waits up to timeout_s; returns the exit code (128+N if killed by signal N), or -1 on
  // timeout.
  int Wait(double timeout_s);
  std::string Output() const;  // contents of output_path so far

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  bool exited_ = false;
  std::string output_path_;
};

// Runs a command to completion and returns its exit code; stdout into *out.
int RunCapture(const std::vector<std::string>& args, std::string* out, double timeout_s = 60);

}  // namespace testing
}  // namespace sarmap
