// sarmap-mic-calibrate-doa-check: does a calibrated asynchronous array localise like the
// synchronous one? Offline, from two LCM logs of the same scene (simulator, same seed):
// one of the synchronous array (AUDIO, one device), one of the same geometry built from
// separate sound cards (AUDIO_<CARD>i). The asynchronous streams are put on the reference
// card's time line by the calibrated clock model of sarmap-mic-calibrate,
//
//   mic i heard at (reference time) t what its own stream holds at t + tau_i + delta_i t,
//
// (windowed-sinc interpolation), then the sound_localisation core (Localiser, SRP-PHAT by
// default) estimates the direction per block on both; the tool prints the per-block
// difference (degrees) in the window [--from-s, --to-s], also without the correction.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/robot_config.h"
#include "mic_calibrate/lcm_audio_log.h"
#include "sound_localisation/localiser.h"

using namespace sarmap;

namespace {

// x(u) for a stream starting at start_s, by a Hann-windowed sinc of half width 16 samples.
float SincAt(const std::vector<float>& x, double start_s, double rate, double u_s) {
  const double pos = (u_s - start_s) * rate;
  const int half = 16;
  const long centre = static_cast<long>(std::floor(pos));
  double acc = 0;
  for (long j = centre - half + 1; j <= centre + half; ++j) {
    if (j < 0 || j >= static_cast<long>(x.size())) continue;
    const double d = pos - j;
    const double sinc = std::abs(d) < 1e-9 ? 1.0 : std::sin(M_PI * d) / (M_PI * d);
    const double w = 0.5 * (1 + std::cos(M_PI * d / half));
    acc += x[j] * sinc * w;
  }
  return static_cast<float>(acc);
}

// Per block (keyed by centre sample): the best direction's angle in degrees.
std::map<int64_t, double> Localise(const common::MicArrayOptions& array,
                                   const std::vector<std::vector<float>>& channels) {
  sound::Localiser loc(sound::ArrayGeometry::FromOptions(array), sound::LocaliserOptions(),
                       sound::SensorModel::Constant(array.doa_sigma_deg));
  std::vector<sound::LocaliserOutput> out;
  const size_t n = channels[0].size(), step = 4096;
  for (size_t b = 0; b < n; b += step) loc.PushFloat(channels, b, std::min(step, n - b), &out);
  std::map<int64_t, double> doa;
  for (const auto& o : out) {
    if (o.active && !o.directions.empty()) {
      doa[o.centre_sample] = o.directions[0].direction.azimuth_rad * 180 / M_PI;
    }
  }
  return doa;
}

struct Stats {
  int blocks = 0;
  double mean = 0, median = 0, p95 = 0, max = 0;
};
Stats Compare(const std::map<int64_t, double>& a, const std::map<int64_t, double>& b) {
  std::vector<double> d;
  for (const auto& [k, v] : a) {
    auto it = b.find(k);
    if (it == b.end()) continue;
    double e = std::abs(v - it->second);
    if (e > 180) e = 360 - e;
    d.push_back(e);
  }
  Stats s;
  s.blocks = static_cast<int>(d.size());
  if (d.empty()) return s;
  std::sort(d.begin(), d.end());
  for (double e : d) s.mean += e / d.size();
  s.median = d[d.size() / 2];
  s.p95 = d[std::min(d.size() - 1, static_cast<size_t>(0.95 * d.size()))];
  s.max = d.back();
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-mic-calibrate-doa-check", [&]() -> int {
    std::string sync_log, async_log, calibrated, array_path = "config/arrays/kinect.yaml";
    double from_s = 0, to_s = 1e9;
    common::ArgParser args("sarmap-mic-calibrate-doa-check",
                           "DOA of a calibrated asynchronous array against the synchronous one");
    args.AddPositional("SYNC_LOG", &sync_log, "LCM log of the synchronous array (AUDIO)");
    args.AddPositional("ASYNC_LOG", &async_log, "LCM log of the separate cards (AUDIO_*)");
    args.AddPositional("CALIBRATED_YAML", &calibrated, "sarmap-mic-calibrate output (tau, delta)");
    args.AddFlag("--array", &array_path, "geometry of both arrays (array YAML)");
    args.AddFlag("--from-s", &from_s, "compare from this time (s, reference time line)");
    args.AddFlag("--to-s", &to_s, "compare up to this time");
    if (!args.Parse(argc, argv)) return 0;
    const common::MicArrayOptions array = common::LoadMicArray(array_path);
    const common::MicArrayOptions cal = common::LoadMicArray(calibrated);
    const int N = static_cast<int>(array.mic_positions_m.size() / 3);

    mic_calibrate::LcmAudioLogStats st;
    const mic_calibrate::Recording sync = mic_calibrate::ReadLcmAudioLog(sync_log, "AUDIO", &st);
    const mic_calibrate::Recording async = mic_calibrate::ReadLcmAudioLog(async_log, "AUDIO_", &st);
    if (static_cast<int>(sync.channels.size()) != N ||
        static_cast<int>(async.channels.size()) != N ||
        static_cast<int>(cal.start_offsets_s.size()) != N ||
        static_cast<int>(cal.clock_drift.size()) != N) {
      throw common::ArgError("need " + std::to_string(N) +
                             " channels in both logs and the calibration");
    }
    const double rate = sync.sample_rate_hz;
    const size_t k0 = static_cast<size_t>(std::max(0.0, from_s) * rate);
    const size_t len =
        std::min<size_t>(sync.channels[0].size(), static_cast<size_t>(to_s * rate)) - k0;
    std::vector<std::vector<float>> s(N), corrected(N), raw(N);
    for (int i = 0; i < N; ++i) {
      s[i].assign(sync.channels[i].begin() + k0, sync.channels[i].begin() + k0 + len);
      const double start = async.channel_start_s.empty() ? 0 : async.channel_start_s[i];
      corrected[i].resize(len);
      raw[i].resize(len);
      for (size_t k = 0; k < len; ++k) {
        const double t = (k0 + k) / rate;
        corrected[i][k] = SincAt(async.channels[i], start, rate,
                                 t + cal.start_offsets_s[i] + cal.clock_drift[i] * t);
        raw[i][k] = SincAt(async.channels[i], start, rate, t);
      }
    }
    const auto d_sync = Localise(array, s), d_cor = Localise(array, corrected),
               d_raw = Localise(array, raw);
    double mean_sync = 0;
    for (const auto& [k, v] : d_sync) mean_sync += v / std::max<size_t>(1, d_sync.size());
    printf("window %.1f-%.1f s: synchronous array %zu active blocks, mean angle %.2f deg\n",
           k0 / rate, (k0 + len) / rate, d_sync.size(), mean_sync);
    for (const auto& [name, d] :
         {std::pair<const char*, const std::map<int64_t, double>*>{"calibrated async", &d_cor},
          {"uncorrected async", &d_raw}}) {
      const Stats c = Compare(d_sync, *d);
      printf(
          "%-18s vs synchronous: %d common blocks, |difference| mean %.3f deg, median %.3f, "
          "95%% %.3f, max %.3f\n",
          name, c.blocks, c.mean, c.median, c.p95, c.max);
    }
    return 0;
  });
}
