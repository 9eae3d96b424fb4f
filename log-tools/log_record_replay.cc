// sarmap-log record / replay: lcm-logger and lcm-logplayer with sarmap's URL defaults.
// One source, two executables (the mode comes from the executable name).
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/node.h"

namespace {

int Exec(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  throw std::runtime_error("cannot run " + args[0] + " (install liblcm-bin)");
}

int Record(int argc, char** argv) {
  sarmap::common::ArgParser parser(
      "sarmap-log record", "Records sarmap channels to an LCM log with lcm-logger (until Ctrl-C).");
  std::string output, channels = ".*", url;
  bool force = false;
  parser.AddFlag("-o", &output, "output log (default: sarmap-YYYYmmdd-HHMMSS.lcmlog)");
  parser.AddFlag("--channels", &channels, "regular expression of channels to record");
  parser.AddFlag("--lcm-url", &url, "LCM URL (default: the sarmap default)");
  parser.AddSwitch("--force", &force, "overwrite an existing file");
  if (!parser.Parse(argc, argv)) return 0;
  if (output.empty()) {
    char name[64];
    const time_t now = time(nullptr);
    strftime(name, sizeof(name), "sarmap-%Y%m%d-%H%M%S.lcmlog", localtime(&now));
    output = name;
  }
  if (url.empty()) url = sarmap::common::DefaultLcmUrl();
  std::vector<std::string> args = {"lcm-logger", "--lcm-url=" + url, "--channel=" + channels,
                                   "--flush-interval=100"};
  if (force) args.push_back("--force");
  args.push_back(output);
  fprintf(stderr, "sarmap-log record: writing %s (Ctrl-C to stop)\n", output.c_str());
  return Exec(args);
}

int Replay(int argc, char** argv) {
  sarmap::common::ArgParser parser("sarmap-log replay",
                                   "Replays an LCM log onto the bus with lcm-logplayer.");
  std::string log, channels = ".*", url;
  double speed = 1.0;
  parser.AddPositional("LOG", &log, "LCM log file");
  parser.AddFlag("--speed", &speed, "playback speed multiplier");
  parser.AddFlag("--channels", &channels, "regular expression of channels to replay");
  parser.AddFlag("--lcm-url", &url, "LCM URL (default: the sarmap default)");
  if (!parser.Parse(argc, argv)) return 0;
  if (access(log.c_str(), R_OK) != 0) throw sarmap::common::ArgError(log + ": cannot read the log");
  if (!(speed > 0)) throw sarmap::common::ArgError("--speed must be > 0");
  if (url.empty()) url = sarmap::common::DefaultLcmUrl();
  return Exec({"lcm-logplayer", "--lcm-url=" + url, "--speed=" + std::to_string(speed),
               "--regexp=" + channels, log});
}

}  // namespace

int main(int argc, char** argv) {
  const std::string self = argv[0];
  const bool replay = self.find("replay") != std::string::npos;
  return sarmap::common::RunMain(replay ? "sarmap-log replay" : "sarmap-log record",
                                 [&] { return replay ? Replay(argc, argv) : Record(argc, argv); });
}
