// sarmap-log replay: lcm-logplayer with sarmap's URL default.
#include <unistd.h>

#include <cstdio>
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
  return sarmap::common::RunMain("sarmap-log replay", [&] { return Replay(argc, argv); });
}
