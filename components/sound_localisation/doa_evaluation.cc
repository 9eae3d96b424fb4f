#include "sound_localisation/doa_evaluation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "audio_capture/audio_file.h"

namespace sarmap {
namespace sound {

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

DoaFileResult EvaluateDoaFile(const std::string& path, const ArrayGeometry& geometry,
                              const LocaliserOptions& options, const Direction& truth) {
  const audio::AudioBuffer audio = audio::ReadAudioFile(path);
  if (audio.sample_rate_hz != geometry.sample_rate_hz)
    throw std::invalid_argument(path + ": sample rate " + std::to_string(audio.sample_rate_hz) +
                                " Hz differs from the array's " + std::to_string(geometry.sample_rate_hz) + " Hz");
  std::vector<std::vector<float>> mics;
  for (int c : geometry.channel_map) {
    if (c >= audio.num_channels())
      throw std::invalid_argument(path + ": has " + std::to_string(audio.num_channels()) +
                                  " channels, the array needs channel " + std::to_string(c));
    mics.push_back(audio.channels[c]);
  }
  DoaFileResult r;
  r.file = path;
  r.method = options.method;
  Localiser localiser(geometry, options, SensorModel::Constant(3.0));
  std::vector<LocaliserOutput> outs;
  localiser.PushFloat(mics, 0, audio.num_frames(), &outs);
  std::vector<double> az_err, el_err;
  const DoaKind kind = localiser.kind();
  for (const auto& o : outs) {
    if (o.directions.empty()) continue;
    const Direction& d = o.directions.front().direction;
    r.block_estimates.push_back(d);
    if (kind == DoaKind::kAngle1d) az_err.push_back(std::abs(RadToDeg(d.azimuth_rad - truth.azimuth_rad)));
    else az_err.push_back(std::abs(RadToDeg(WrapAngle(d.azimuth_rad - truth.azimuth_rad))));
    if (kind == DoaKind::kAzimuthElevation) el_err.push_back(std::abs(RadToDeg(d.elevation_rad - truth.elevation_rad)));
  }
  r.blocks = static_cast<int>(az_err.size());
  r.median_azimuth_error_deg = Median(az_err);
  r.median_elevation_error_deg = Median(el_err);
  if (!az_err.empty()) {
    double s = 0;
    for (double e : az_err) s += e;
    r.mean_azimuth_error_deg = s / az_err.size();
  }
  // Whole file: every frame whose band energy is within 20 dB of the loudest ones.
  MultichannelStft stft(geometry.num_mics(), options.fft_size, options.hop_size);
  std::vector<Eigen::MatrixXcf> frames;
  std::vector<double> energy;
  stft.PushFloat(mics, 0, audio.num_frames(), [&](const Eigen::MatrixXcf& s, int64_t) {
    frames.push_back(s);
    energy.push_back(s.squaredNorm());
  });
  if (!frames.empty()) {
    std::vector<double> sorted = energy;
    std::sort(sorted.begin(), sorted.end());
    const double loud = sorted[static_cast<size_t>(0.95 * (sorted.size() - 1))];
    BlockStatistics stats = localiser.MakeStatistics();
    std::vector<Eigen::MatrixXcd> state;
    std::vector<char> mask;
    for (size_t i = 0; i < frames.size(); ++i) {
      localiser.DirectPathMask(frames[i], &state, &mask);
      if (energy[i] > loud * 0.01) localiser.Accumulate(frames[i], &stats, &mask);
    }
    const auto est = localiser.Estimate(stats);
    if (!est.empty()) {
      r.whole_azimuth_deg = RadToDeg(est.front().direction.azimuth_rad);
      r.whole_elevation_deg = RadToDeg(est.front().direction.elevation_rad);
    }
  }
  return r;
}

}  // namespace sound
}  // namespace sarmap
