// sarmap-log: front end of the offline log tools. `sarmap-log SUB ARGS` runs the executable
// `sarmap-log-SUB` that sits beside it, so components add tools without touching this file.
#include <dirent.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <set>
#include <string>
#include <vector>

namespace {

std::string SelfDir() {
  char path[4096];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  path[n] = 0;
  std::string s(path);
  return s.substr(0, s.rfind('/'));
}

std::set<std::string> SubCommands(const std::string& dir) {
  std::set<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.rfind("sarmap-log-", 0) == 0) out.insert(name.substr(11));
    }
    closedir(d);
  }
  return out;
}

void Usage(const std::string& dir) {
  printf("usage: sarmap-log SUBCOMMAND [ARGS...]\n\nOffline tools for sarmap LCM logs. Subcommands "
         "found here (each has --help):\n");
  for (const auto& s : SubCommands(dir)) printf("  %s\n", s.c_str());
  printf("\nExamples:\n  sarmap-log record -o mission.lcmlog\n  sarmap-log info mission.lcmlog\n"
         "  sarmap-log replay mission.lcmlog --speed 2\n"
         "  sarmap-log echo mission.lcmlog --channel PEOPLE_VISUAL\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = SelfDir();
  if (argc < 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") || !strcmp(argv[1], "help")) {
    Usage(dir);
    return argc < 2 ? 2 : 0;
  }
  const std::string tool = dir + "/sarmap-log-" + argv[1];
  if (access(tool.c_str(), X_OK) != 0) {
    fprintf(stderr, "sarmap-log: unknown subcommand '%s'\n\n", argv[1]);
    Usage(dir);
    return 2;
  }
  std::vector<char*> args;
  std::string name = std::string("sarmap-log ") + argv[1];
  args.push_back(name.data());
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(tool.c_str(), args.data());
  perror(("sarmap-log: cannot run " + tool).c_str());
  return 1;
}
