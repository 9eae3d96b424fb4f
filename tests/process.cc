#include "tests/process.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace sarmap {
namespace testing {

std::string BinDir() { return SARMAP_BIN_DIR; }

Process::Process(std::vector<std::string> args, const std::string& output_path)
    : output_path_(output_path) {
  if (args.empty()) throw std::invalid_argument("empty command");
  if (args[0].find('/') == std::string::npos && access((BinDir() + "/" + args[0]).c_str(), X_OK) == 0) {
    args[0] = BinDir() + "/" + args[0];
  }
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    if (!output_path.empty()) {
      const int fd = open(output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
      }
    }
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
}

Process::~Process() {
  if (Running()) {
    kill(pid_, SIGKILL);
    Wait(5);
  }
}

bool Process::Running() {
  if (exited_ || pid_ <= 0) return false;
  int status;
  const pid_t r = waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    exited_ = true;
    status_ = status;
    return false;
  }
  return r == 0;
}

void Process::Signal(int sig) {
  if (!exited_ && pid_ > 0) kill(pid_, sig);
}

int Process::Wait(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (Running()) {
    if (std::chrono::steady_clock::now() > deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (WIFEXITED(status_)) return WEXITSTATUS(status_);
  if (WIFSIGNALED(status_)) return 128 + WTERMSIG(status_);
  return -1;
}

std::string Process::Output() const {
  std::ifstream in(output_path_);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int RunCapture(const std::vector<std::string>& args, std::string* out, double timeout_s) {
  char tmpl[] = "/tmp/sarmap-run-XXXXXX";
  const int fd = mkstemp(tmpl);
  if (fd >= 0) close(fd);
  int code;
  {
    Process p(args, tmpl);
    code = p.Wait(timeout_s);
    if (out) *out = p.Output();
  }
  unlink(tmpl);
  return code;
}

}  // namespace testing
}  // namespace sarmap
