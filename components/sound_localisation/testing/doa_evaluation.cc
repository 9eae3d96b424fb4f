#include "sound_localisation/testing/doa_evaluation.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "audio_capture/audio_file.h"
#include "sound_localisation/testing/room_simulation.h"

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
                                " Hz differs from the array's " +
                                std::to_string(geometry.sample_rate_hz) + " Hz");
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
    if (kind == DoaKind::kAngle1d)
      az_err.push_back(std::abs(RadToDeg(d.azimuth_rad - truth.azimuth_rad)));
    else
      az_err.push_back(std::abs(RadToDeg(WrapAngle(d.azimuth_rad - truth.azimuth_rad))));
    if (kind == DoaKind::kAzimuthElevation)
      el_err.push_back(std::abs(RadToDeg(d.elevation_rad - truth.elevation_rad)));
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

namespace sarmap {
namespace sound {

namespace {

// Speech frames (hop-sized) of a talker's own signal: 10 dB above its 10th-percentile frame
// energy and within 30 dB of its loudest frame.
std::vector<char> SpeechFrames(const std::vector<float>& x, int hop) {
  std::vector<double> e;
  for (size_t i = 0; i + hop <= x.size(); i += hop) {
    double s = 0;
    for (int k = 0; k < hop; ++k) s += static_cast<double>(x[i + k]) * x[i + k];
    e.push_back(s);
  }
  std::vector<char> active(e.size(), 0);
  if (e.empty()) return active;
  std::vector<double> sorted = e;
  std::sort(sorted.begin(), sorted.end());
  const double threshold = std::max(sorted[sorted.size() / 10] * 10.0, sorted.back() * 1e-3);
  for (size_t i = 0; i < e.size(); ++i) active[i] = e[i] > threshold && e[i] > 0;
  return active;
}

double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

}  // namespace

SceneScore ScoreScene(const Scene& scene, const ArrayGeometry& geometry,
                      const LocaliserOptions& options, const ScoreOptions& so) {
  if (scene.mics.size() != static_cast<size_t>(geometry.num_mics()))
    throw std::invalid_argument(scene.name + ": " + std::to_string(scene.mics.size()) +
                                " channels for " + std::to_string(geometry.num_mics()) +
                                " microphones");
  SceneScore r;
  r.name = scene.name;
  r.talkers = static_cast<int>(scene.talkers.size());
  const size_t n = scene.mics.empty() ? 0 : scene.mics[0].size();
  const int fs = geometry.sample_rate_hz;
  r.audio_s = static_cast<double>(n) / fs;

  Localiser localiser(geometry, options, SensorModel::Constant(3.0));
  std::vector<LocaliserOutput> outs;
  const double cpu0 = ThreadCpuSeconds();
  const size_t chunk = 512;  // as the node receives it
  for (size_t b = 0; b < n; b += chunk)
    localiser.PushFloat(scene.mics, b, std::min(chunk, n - b), &outs);
  r.cpu_s = ThreadCpuSeconds() - cpu0;

  const DoaKind kind = localiser.kind();
  const int hop = options.hop_size;
  std::vector<std::vector<char>> speech;
  std::vector<int64_t> onset;
  for (const auto& t : scene.talkers) {
    speech.push_back(SpeechFrames(t.signal, hop));
    int64_t first = -1;
    for (size_t i = 0; i < speech.back().size() && first < 0; ++i)
      if (speech.back()[i]) first = static_cast<int64_t>(i) * hop;
    onset.push_back(first);
  }
  // Azimuth only (1-D arrays: the angle to the axis): a planar array's elevation is scored apart.
  auto dist_deg = [&](const Direction& a, const Direction& b) {
    if (kind == DoaKind::kAngle1d) return std::abs(RadToDeg(a.azimuth_rad - b.azimuth_rad));
    return std::abs(RadToDeg(WrapAngle(a.azimuth_rad - b.azimuth_rad)));
  };
  std::vector<double> elevation_errors;
  // Talker directions as the localiser reports them (linear arrays: the angle to the axis).
  std::vector<Direction> truths;
  for (const auto& t : scene.talkers)
    truths.push_back(
        geometry.FromUnit(kind, geometry.Unit(DoaKind::kAzimuthElevation, t.direction)));
  r.onset_latency_s.assign(scene.talkers.size(), NAN);
  std::map<int64_t, std::vector<double>> track_distances;  // id -> distance to the nearest talker
  std::map<int64_t, std::vector<Direction>> track_directions;
  for (const auto& o : outs) {
    const int64_t start = std::max<int64_t>(0, 2 * o.centre_sample - o.end_sample);
    for (size_t t = 0; t < scene.talkers.size(); ++t) {
      const Direction& truth = truths[t];
      int frames = 0, on = 0;
      for (int64_t f = start / hop;
           f * hop < o.end_sample && f < static_cast<int64_t>(speech[t].size()); ++f) {
        ++frames;
        on += speech[t][f];
      }
      bool has_track_10 = false;
      for (const Track& tr : o.tracks)
        if (dist_deg(tr.direction, truth) <= so.onset_deg) has_track_10 = true;
      if (has_track_10 && onset[t] >= 0 && std::isnan(r.onset_latency_s[t]) &&
          o.end_sample > onset[t])
        r.onset_latency_s[t] = static_cast<double>(o.end_sample - onset[t]) / fs;
      if (frames == 0 || 2 * on < frames) continue;
      ++r.speech_pairs;
      bool found = false, covered = false, tracked = false;
      double best = 1e9, best_el = NAN;
      for (const auto& d : o.directions) {
        const double e = dist_deg(d.direction, truth);
        if (e <= so.found_deg) found = true;
        if (e < best) {
          best = e;
          best_el = std::abs(RadToDeg(d.direction.elevation_rad - truth.elevation_rad));
        }
      }
      if (found && kind == DoaKind::kAzimuthElevation) elevation_errors.push_back(best_el);
      for (const Track& tr : o.tracks)
        if (dist_deg(tr.direction, truth) <= so.found_deg) {
          covered = true;
          if (tr.updated) tracked = true;
        }
      r.found += found;
      r.covered += covered;
      r.tracked += tracked;
    }
    for (const Track& tr : o.tracks) {
      if (!tr.updated) continue;
      double nearest = 1e9;
      for (const Direction& t : truths) nearest = std::min(nearest, dist_deg(tr.direction, t));
      track_distances[tr.id].push_back(nearest);
      track_directions[tr.id].push_back(tr.direction);
    }
  }
  r.median_elevation_error_deg = Median(elevation_errors);
  for (const auto& [id, d] : track_distances) {
    ++r.confirmed_tracks;
    if (Median(d) > so.spurious_deg) {
      ++r.spurious_tracks;
      const auto& dirs = track_directions[id];
      r.spurious_directions.push_back(dirs[dirs.size() / 2]);
    }
  }
  return r;
}

Scene LoadRecordedScene(const std::string& path, const ArrayGeometry& geometry,
                        const Direction& truth) {
  const audio::AudioBuffer audio = audio::ReadAudioFile(path);
  if (audio.sample_rate_hz != geometry.sample_rate_hz)
    throw std::invalid_argument(path + ": sample rate " + std::to_string(audio.sample_rate_hz) +
                                " Hz differs from the array's " +
                                std::to_string(geometry.sample_rate_hz) + " Hz");
  Scene s;
  s.name = path;
  for (int c : geometry.channel_map) {
    if (c >= audio.num_channels())
      throw std::invalid_argument(path + ": has " + std::to_string(audio.num_channels()) +
                                  " channels, the array needs channel " + std::to_string(c));
    s.mics.push_back(audio.channels[c]);
  }
  s.talkers.push_back({truth, s.mics.front()});
  return s;
}

Scene SimulateTalkerScene(const std::string& name, const ArrayGeometry& geometry,
                          const std::vector<std::vector<float>>& talker_signals,
                          const std::vector<Direction>& directions, double distance_m,
                          double rt60_s, double noise_std, uint32_t seed) {
  if (talker_signals.size() != directions.size())
    throw std::invalid_argument("one direction per talker");
  Room room;
  room.size_m = {6.0, 5.0, 3.0};
  room.rt60_s = rt60_s;
  room.max_rir_s = std::clamp(rt60_s, 0.05, 0.4);
  room.sample_rate_hz = geometry.sample_rate_hz;
  room.speed_of_sound_mps = geometry.speed_of_sound_mps;
  const Eigen::Vector3d centre(3.0, 2.5, 0.8);
  size_t n = 0;
  Scene scene;
  scene.name = name;
  std::vector<SimSource> sources;
  for (size_t i = 0; i < directions.size(); ++i) {
    const Eigen::Vector3d u = geometry.Unit(DoaKind::kAzimuthElevation, directions[i]);
    sources.push_back({centre + distance_m * u, talker_signals[i]});
    scene.talkers.push_back({directions[i], talker_signals[i]});
    n = std::max(n, talker_signals[i].size());
  }
  const Eigen::Matrix3Xd mics = geometry.positions_m.colwise() + centre;
  scene.mics = SimulateRoom(room, mics, sources, n, noise_std, seed);
  return scene;
}

std::vector<Scene> SimulatedBenchmarkScenes(const ArrayGeometry& geometry,
                                            const std::string& speech_dir, int num_talkers) {
  static const char* files[] = {
      "cmu_arctic_us_aew_a0001.wav", "cmu_arctic_us_axb_a0004.wav", "arctic_a0010.wav",
      "cmu_arctic_us_aew_a0002.wav", "cmu_arctic_us_axb_a0005.wav", "cmu_arctic_us_aew_a0003.wav",
      "cmu_arctic_us_axb_a0006.wav"};
  std::vector<std::vector<float>> utterances;
  for (const char* f : files) {
    const std::string path = speech_dir + "/" + f;
    if (!std::filesystem::exists(path)) return {};
    auto buf = audio::ReadAudioFile(path);
    if (buf.sample_rate_hz != geometry.sample_rate_hz)
      throw std::invalid_argument(path + ": sample rate differs from the array's");
    std::vector<float> x = buf.channels[0];
    double e = 0;
    for (float v : x) e += static_cast<double>(v) * v;
    const float g = static_cast<float>(1.0 / std::sqrt(e / std::max<size_t>(1, x.size()) + 1e-12));
    for (float& v : x) v *= g;  // unit RMS
    utterances.push_back(std::move(x));
  }
  const int fs = geometry.sample_rate_hz;
  const size_t length = static_cast<size_t>(7.0 * fs);
  // Talker i starts at 0.2 + 0.7 i s and says two utterances 0.3 s apart.
  auto talker = [&](int i, int variant) {
    std::vector<float> x(length, 0.0f);
    size_t at = static_cast<size_t>((0.2 + 0.7 * i) * fs);
    for (int k = 0; k < 2 && at < length; ++k) {
      const auto& u = utterances[(2 * i + k + 3 * variant) % utterances.size()];
      for (size_t j = 0; j < u.size() && at + j < length; ++j) x[at + j] = u[j];
      at += u.size() + static_cast<size_t>(0.3 * fs);
    }
    return x;
  };
  struct Layout {
    double rt60_s, distance_m;
    std::vector<std::pair<double, double>> az_el_deg;
  };
  const std::vector<Layout> layouts =
      num_talkers == 2 ? std::vector<Layout>{{0.3, 1.5, {{30, 20}, {150, 10}}},
                                             {0.5, 2.0, {{-60, 30}, {60, 15}}},
                                             {0.3, 1.0, {{100, 25}, {-170, 40}}}}
                       : std::vector<Layout>{{0.3, 1.5, {{30, 20}, {150, 10}, {-90, 30}}},
                                             {0.5, 2.0, {{0, 15}, {120, 35}, {-120, 20}}},
                                             {0.3, 1.0, {{45, 25}, {180, 20}, {-60, 45}}}};
  std::vector<Scene> scenes;
  for (size_t v = 0; v < layouts.size(); ++v) {
    const Layout& l = layouts[v];
    std::vector<std::vector<float>> signals;
    std::vector<Direction> dirs;
    std::string name = "sim" + std::to_string(num_talkers) + "_rt" +
                       std::to_string(static_cast<int>(l.rt60_s * 100)) + "_d" +
                       std::to_string(static_cast<int>(l.distance_m * 10));
    for (int i = 0; i < num_talkers; ++i) {
      signals.push_back(talker(i, static_cast<int>(v)));
      dirs.push_back({DegToRad(l.az_el_deg[i].first), DegToRad(l.az_el_deg[i].second)});
    }
    scenes.push_back(SimulateTalkerScene(name, geometry, signals, dirs, l.distance_m, l.rt60_s,
                                         0.003, static_cast<uint32_t>(11 + v)));
  }
  return scenes;
}

}  // namespace sound
}  // namespace sarmap
