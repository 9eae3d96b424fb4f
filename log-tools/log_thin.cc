// sarmap-log thin LOG -o OUT --profile FILE: a recorded log thinned as `sarmap-log record
// --profile FILE` thins it live (log-tools/record_profile.h), with the recording rate it gives
// and the hours that fit in 10 GB.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/record_profile.h"

namespace {

int Thin(int argc, char** argv) {
  sarmap::common::ArgParser parser(
      "sarmap-log thin",
      "Writes LOG thinned by a recording profile (camera frames at a low rate except around the\n"
      "people seen, grids every few seconds, everything else whole), exactly as\n"
      "`sarmap-log record --profile` records it live, and prints what it kept and how many\n"
      "hours of such a mission fit in 10 GB.");
  std::string log, output, profile = "config/record_long.yaml";
  std::vector<std::string> overrides;
  bool force = false;
  parser.AddPositional("LOG", &log, "LCM log to thin");
  parser.AddFlag("-o", &output, "log to write");
  parser.AddFlag("--profile", &profile, "recording profile");
  parser.AddRepeated("--set", &overrides, "override a profile option, e.g. --set frames.rate_hz=2");
  parser.AddSwitch("--force", &force, "overwrite an existing output");
  if (!parser.Parse(argc, argv)) return 0;
  if (output.empty()) throw sarmap::common::ArgError("-o OUT is required");
  if (output == log) throw sarmap::common::ArgError("-o must differ from LOG");
  const auto options = sarmap::common::LoadOptions<sarmap::logtools::RecordProfileOptions>(
      sarmap::common::ResolveConfigPath(profile), overrides);
  if (FILE* existing = fopen(output.c_str(), "rb")) {
    fclose(existing);
    if (!force) throw sarmap::common::ArgError(output + " exists (--force to overwrite)");
  }

  sarmap::logtools::LcmLogReader reader(log);
  sarmap::logtools::RecordThinner thinner(options);
  sarmap::logtools::LcmLogWriter out(output);
  int64_t written = 0, bytes_in = 0, bytes_out = 0, first_us = -1, last_us = -1;
  std::vector<sarmap::logtools::LogEvent> released;
  auto write = [&] {
    for (auto& e : released) {
      out.WriteBytes(e.channel, e.data, e.timestamp_us);
      ++written;
      bytes_out += 28 + static_cast<int64_t>(e.channel.size() + e.data.size());
    }
    released.clear();
  };
  int last_percent = -1;
  sarmap::logtools::LogEvent event;
  while (reader.Next(&event)) {
    bytes_in += 28 + static_cast<int64_t>(event.channel.size() + event.data.size());
    if (first_us < 0) first_us = event.timestamp_us;
    last_us = std::max(last_us, event.timestamp_us);
    const int64_t now_us = event.timestamp_us;
    thinner.Add(std::move(event));
    thinner.Release(now_us, &released);
    write();
    const int percent =
        reader.file_size() > 0 ? static_cast<int>(100 * reader.offset() / reader.file_size()) : 100;
    if (percent / 10 != last_percent / 10) {
      fprintf(stderr, "\rthin: %3d %%", percent);
      last_percent = percent;
    }
  }
  thinner.Finish(&released);
  write();
  out.Flush();
  fprintf(stderr, "\n");
  for (const auto& p : reader.problems()) {
    fprintf(stderr, "thin: %s: damaged at byte %lld (%s); read on from the next event\n",
            log.c_str(), static_cast<long long>(p.file_offset), p.what.c_str());
  }
  const double span_s = first_us < 0 ? 0 : (last_us - first_us) * 1e-6;
  printf("%s -> %s: %lld events, %.1f -> %.1f MB over %.1f s\n", log.c_str(), output.c_str(),
         static_cast<long long>(written), bytes_in / 1e6, bytes_out / 1e6, span_s);
  printf("%s", sarmap::logtools::ThinSummary(thinner).c_str());
  if (span_s > 0 && bytes_out > 0) {
    const double in_rate = bytes_in / span_s, out_rate = bytes_out / span_s;
    printf("recording rate %.2f MB/s (whole: %.2f MB/s): 10 GB hold %.1f h (whole: %.1f h)\n",
           out_rate / 1e6, in_rate / 1e6, 1e10 / out_rate / 3600, 1e10 / in_rate / 3600);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log thin", [&] { return Thin(argc, argv); });
}
