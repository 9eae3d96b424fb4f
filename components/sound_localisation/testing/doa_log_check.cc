// doa_log_check LOGFILE AZ_DEG EL_DEG TOL_DEG MIN_MESSAGES [DOA_CHANNEL]: reads an LCM log, decodes
// every doa_t on DOA (or DOA_CHANNEL), and checks that the median direction of the strongest source
// is within TOL of the truth. Used by the multi-process test; prints what it found. The log is read
// past damage (log-tools/lcm_log_reader.h); where it breaks is printed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/decode.h"
#include "log-tools/lcm_log_reader.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr,
                 "usage: doa_log_check LOG AZ_DEG EL_DEG TOL_DEG MIN_MESSAGES [DOA_CHANNEL]\n");
    return 2;
  }
  std::unique_ptr<sarmap::logtools::LcmLogReader> log;
  try {
    log = std::make_unique<sarmap::logtools::LcmLogReader>(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  const double az = std::stod(argv[2]), el = std::stod(argv[3]), tol = std::stod(argv[4]);
  const int min_messages = std::stoi(argv[5]);
  const std::string doa_channel = argc > 6 ? argv[6] : "DOA";
  std::vector<double> azs, els;
  int doa_messages = 0, audio_messages = 0, tracked = 0;
  int64_t last_audio_utime = 0;
  sarmap::logtools::LogEvent event;
  while (log->Next(&event)) {
    const sarmap::logtools::LogEvent* e = &event;
    if (e->channel.rfind("AUDIO", 0) == 0) {
      sarmap::audio_frame_t a;
      if (sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &a)) {
        ++audio_messages;
        last_audio_utime = a.header.utime;
      }
    }
    if (e->channel != doa_channel) continue;
    sarmap::doa_t d;
    if (!sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &d)) continue;
    ++doa_messages;
    if (d.sources.empty()) continue;
    const auto& s = d.sources.front();
    tracked += s.track_id >= 0;
    azs.push_back(s.azimuth_rad * 180 / M_PI);
    els.push_back(s.elevation_rad * 180 / M_PI);
  }
  for (const auto& p : log->problems())
    std::printf("warning: %s\n", sarmap::logtools::DescribeProblem(p).c_str());
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[v.size() / 2];
  };
  std::vector<double> az_err;
  for (double a : azs) az_err.push_back(std::abs(std::remainder(a - az, 360.0)));
  const double maz = median(az_err), mel = median(els);
  std::printf(
      "AUDIO messages %d, DOA messages %d, with sources %zu (tracked %d); median |az err| %.2f "
      "deg, median "
      "el %.2f deg (last audio utime %lld)\n",
      audio_messages, doa_messages, azs.size(), tracked, maz, mel,
      static_cast<long long>(last_audio_utime));
  const bool ok =
      doa_messages >= min_messages && maz <= tol && std::abs(mel - el) <= tol && tracked > 0;
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
