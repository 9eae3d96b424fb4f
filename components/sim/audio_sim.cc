#include "sim/audio_sim.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace sarmap {
namespace sim {
namespace {
constexpr int kPhases = 1024;
constexpr int kInterpHalf = 16;
double DbToPa(double db) { return 20e-6 * std::pow(10.0, db / 20.0); }
// The diffuse tail changes little over a few decimetres; the early reflections do not.
constexpr double kLateUpdateDistance_m = 0.25;
}  // namespace

struct AudioSim::Source {
  std::unique_ptr<SourceSignal> signal;
  std::unique_ptr<MultiConvolver> convolver;
  std::vector<Eigen::Vector3d> filter_mics;  // mic positions the filters were made for
  Eigen::Vector3d filter_source;
  // The late (diffuse) part per mic and where it was computed: refreshed only after larger
  // moves, while the early part follows every few centimetres.
  std::vector<std::vector<float>> late;
  std::vector<Eigen::Vector3d> late_mics;
  double pressure_pa = 1;
};

struct AudioSim::Device {
  std::string name;
  std::vector<int> mics;  // microphones on this device
  double offset_s = 0;    // tau
  double drift = 0;       // delta
  int64_t next_index = 0;
  bool asynchronous = false;
};

AudioSim::AudioSim(const AudioOptions& options, const common::MicArrayOptions& array,
                   const common::Rigid3d& base_from_array, const World& world,
                   std::vector<std::unique_ptr<SourceSignal>> signals, uint64_t seed)
    : options_(options), array_(array), base_from_array_(base_from_array),
      rate_(array.sample_rate_hz), mics_(array.num_mics()), rng_(seed) {
  pa_to_counts_ = 23170.0 / DbToPa(options.full_scale_db_spl);
  ambient_pa_ = DbToPa(world.acoustics.ambient_noise_db_spl);
  sensor_pa_ = DbToPa(options.sensor_noise_db_spl);
  motor_pa_ = DbToPa(options.motor_noise_db_spl);
  world.AcousticRoom(&room_.min, &room_.max);
  const bool reverb = options.reverb && world.acoustics.reverb;
  double rt60 = 0;
  if (world.acoustics.rt60_s > 0 && world.acoustics.absorption.empty()) {
    SetUniformRt60(&room_, world.acoustics.rt60_s, rate_, array.speed_of_sound_mps);
    rt60 = world.acoustics.rt60_s;
  } else if (!world.acoustics.absorption.empty()) {
    SetAbsorption(&room_, world.acoustics.absorption);
    double mean = 0;
    for (double b : room_.beta) mean += (1 - b * b) / 6;
    rt60 = EyringRt60(room_.Volume(), room_.Surface(), mean);
  }
  const double diag = (room_.max - room_.min).norm();
  rir_options_.sample_rate_hz = rate_;
  rir_options_.speed_of_sound_mps = array.speed_of_sound_mps;
  rir_options_.exact_order = options.exact_order;
  rir_options_.sinc_half_width = options.sinc_half_width;
  rir_options_.reverb = reverb;
  rir_options_.max_length_s =
      reverb ? std::min(options.rir_max_length_s, std::max(diag / array.speed_of_sound_mps + 0.02, 1.1 * rt60))
             : diag / array.speed_of_sound_mps + 0.02;
  const int max_filter = static_cast<int>(std::ceil(rir_options_.max_length_s * rate_)) + options.sinc_half_width + 2;
  for (auto& signal : signals) {
    auto src = std::make_unique<Source>();
    src->pressure_pa = DbToPa(signal->source().level_db_spl);
    src->signal = std::move(signal);
    src->convolver = std::make_unique<MultiConvolver>(options.convolve_block_samples, max_filter, mics_);
    sources_.push_back(std::move(src));
  }
  // The motors sit low in the base, fixed relative to the array: one short FIR per mic.
  const Eigen::Vector3d motor_in_array = base_from_array.inverse() * Eigen::Vector3d(0.0, 0.0, 0.15);
  double mean_r = 0;
  for (int m = 0; m < mics_; ++m) mean_r += (array.mic_position(m) - motor_in_array).norm() / mics_;
  for (int m = 0; m < mics_; ++m) {
    std::vector<float> fir;
    const double r = (array.mic_position(m) - motor_in_array).norm();
    AddFractionalDelay(&fir, r / array.speed_of_sound_mps * rate_, mean_r / std::max(r, 0.02), options.sinc_half_width);
    motor_fir_.push_back(fir);
  }
  size_t longest = 0;
  for (const auto& f : motor_fir_) longest = std::max(longest, f.size());
  motor_state_.assign(longest, 0.0f);
  ambient_lowpass_.assign(mics_, 0.0);
  history_.assign(mics_, {});
  // Devices.
  if (options.asynchronous) {
    for (int m = 0; m < mics_; ++m) {
      Device d;
      d.name = array.name + std::to_string(m);
      for (char& c : d.name) c = std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::toupper(c)) : '_';
      d.mics = {m};
      d.offset_s = array.start_offsets_s.empty() ? 0.0 : array.start_offsets_s[m];
      d.drift = array.clock_drift.empty() ? 0.0 : array.clock_drift[m];
      d.asynchronous = true;
      devices_.push_back(d);
    }
  } else {
    Device d;
    d.name = array.name;
    for (int m = 0; m < mics_; ++m) {
      // channel_map: device channel of each mic.
      d.mics.push_back(m);
    }
    devices_.push_back(d);
  }
  sinc_table_.resize(static_cast<size_t>(kPhases + 1) * 2 * kInterpHalf);
  for (int ph = 0; ph <= kPhases; ++ph) {
    const double frac = static_cast<double>(ph) / kPhases;
    for (int t = -kInterpHalf + 1; t <= kInterpHalf; ++t) {
      const double x = t - frac;
      const double sinc = std::abs(x) < 1e-9 ? 1.0 : std::sin(M_PI * x) / (M_PI * x);
      const double window = 0.5 * (1 + std::cos(M_PI * x / (kInterpHalf + 1)));
      sinc_table_[static_cast<size_t>(ph) * 2 * kInterpHalf + (t + kInterpHalf - 1)] = static_cast<float>(sinc * window);
    }
  }
}

AudioSim::~AudioSim() = default;

const std::vector<SourceSignal*> AudioSim::signals() const {
  std::vector<SourceSignal*> out;
  for (const auto& s : sources_) out.push_back(s->signal.get());
  return out;
}

std::vector<std::string> AudioSim::device_names() const {
  std::vector<std::string> out;
  for (const auto& d : devices_) out.push_back(d.name);
  return out;
}

void AudioSim::GenerateBlock(const common::Rigid2d& map_from_base, double speed_mps, double turn_radps) {
  const int B = options_.convolve_block_samples;
  std::vector<std::vector<float>> block(mics_, std::vector<float>(B, 0.0f));
  std::vector<float*> outs;
  for (auto& b : block) outs.push_back(b.data());
  const common::Rigid3d map_from_array = common::Rigid3d::FromRigid2d(map_from_base) * base_from_array_;
  std::vector<Eigen::Vector3d> mic_pos(mics_);
  for (int m = 0; m < mics_; ++m) mic_pos[m] = map_from_array * array_.mic_position(m);

  std::vector<float> signal(B);
  for (auto& src : sources_) {
    if (src->signal->Render(generated_, B, signal.data())) {
      bool update = !src->convolver->has_filters() ||
                    (src->filter_source - src->signal->source().position).norm() > 1e-6;
      for (int m = 0; m < mics_ && !update; ++m) {
        update = (src->filter_mics[m] - mic_pos[m]).norm() > options_.rir_update_distance_m;
      }
      if (update) {
        const Eigen::Vector3d& source_pos = src->signal->source().position;
        bool late_stale = src->late.empty() || (src->filter_source - source_pos).norm() > 1e-6;
        for (int m = 0; m < mics_ && !late_stale; ++m) {
          late_stale = (src->late_mics[m] - mic_pos[m]).norm() > kLateUpdateDistance_m;
        }
        if (late_stale) {
          RirOptions late = rir_options_;
          late.min_order = rir_options_.exact_order + 1;
          src->late.assign(mics_, {});
          for (int m = 0; m < mics_; ++m) src->late[m] = ImageSourceRir(room_, source_pos, mic_pos[m], late);
          src->late_mics = mic_pos;
        }
        RirOptions early = rir_options_;
        early.max_order = rir_options_.exact_order;
        std::vector<std::vector<float>> filters(mics_);
        for (int m = 0; m < mics_; ++m) {
          filters[m] = ImageSourceRir(room_, source_pos, mic_pos[m], early);
          filters[m].resize(std::max(filters[m].size(), src->late[m].size()), 0.0f);
          for (size_t k = 0; k < src->late[m].size(); ++k) filters[m][k] += src->late[m][k];
        }
        src->convolver->SetFilters(filters);
        src->filter_mics = mic_pos;
        src->filter_source = src->signal->source().position;
        ++rir_updates_;
      }
      for (float& v : signal) v = static_cast<float>(v * src->pressure_pa);
      src->convolver->Process(signal.data(), outs);
    } else {
      src->convolver->ProcessSilence(outs);
    }
  }

  // Motor noise: brown noise plus a whine rising with speed, louder the faster the robot moves.
  const double effort = std::min(2.0, (std::abs(speed_mps) + 0.3 * std::abs(turn_radps)) / 0.5);
  if (effort > 1e-3 && motor_pa_ > 0) {
    const size_t L = motor_state_.size();
    std::vector<float> motor(L + B, 0.0f);
    std::copy(motor_state_.begin(), motor_state_.end(), motor.begin());
    const double whine_hz = 180.0 + 400.0 * std::abs(speed_mps);
    for (int k = 0; k < B; ++k) {
      motor_lowpass_ = 0.95 * motor_lowpass_ + 0.05 * normal_(rng_);
      motor_phase_ += 2 * M_PI * whine_hz / rate_;
      const double v = 0.8 * motor_lowpass_ / std::sqrt(0.05 / 1.95) + 0.5 * std::sin(motor_phase_) + 0.3 * normal_(rng_);
      motor[L + k] = static_cast<float>(v * motor_pa_ * effort / 1.02);
    }
    for (int m = 0; m < mics_; ++m) {
      const std::vector<float>& fir = motor_fir_[m];
      for (int k = 0; k < B; ++k) {
        double acc = 0;
        for (size_t t = 0; t < fir.size(); ++t) acc += fir[t] * motor[L + k - t];
        block[m][k] += static_cast<float>(acc);
      }
    }
    std::copy(motor.end() - L, motor.end(), motor_state_.begin());
  } else {
    std::fill(motor_state_.begin(), motor_state_.end(), 0.0f);
  }
  // Diffuse ambient noise (independent per mic, pinkish) and each mic's self noise.
  for (int m = 0; m < mics_; ++m) {
    for (int k = 0; k < B; ++k) {
      ambient_lowpass_[m] = 0.9 * ambient_lowpass_[m] + 0.1 * normal_(rng_);
      const double ambient = ambient_lowpass_[m] / std::sqrt(0.1 / 1.9);
      block[m][k] += static_cast<float>(ambient_pa_ * ambient + sensor_pa_ * normal_(rng_));
    }
    history_[m].insert(history_[m].end(), block[m].begin(), block[m].end());
  }
  generated_ += B;
  // Keep two seconds of history (asynchronous devices read behind the newest sample).
  const int64_t keep = 2 * static_cast<int64_t>(rate_);
  if (!keep_all_history_ && static_cast<int64_t>(history_[0].size()) > 2 * keep) {
    const int64_t drop = static_cast<int64_t>(history_[0].size()) - keep;
    for (auto& h : history_) h.erase(h.begin(), h.begin() + drop);
    history_start_ += drop;
  }
}

void AudioSim::CollectFrames(double t_s, int64_t start_utime, std::vector<AudioFrameOut>* frames) {
  const int n = options_.block_samples;
  auto to_counts = [&](double pa) {
    return static_cast<int16_t>(std::clamp(std::lround(pa * pa_to_counts_), -32768L, 32767L));
  };
  for (Device& d : devices_) {
    const int channels = static_cast<int>(d.mics.size());
    while (true) {
      const int64_t last = d.next_index + n - 1;
      double last_true_s, first_true_s;
      if (d.asynchronous) {
        first_true_s = d.offset_s + d.next_index / (rate_ * (1 + d.drift));
        last_true_s = d.offset_s + last / (rate_ * (1 + d.drift));
        if (last_true_s * rate_ + kInterpHalf >= generated_) break;
      } else {
        first_true_s = static_cast<double>(d.next_index) / rate_;
        last_true_s = static_cast<double>(last) / rate_;
        if (last >= generated_) break;
      }
      if (last_true_s > t_s) break;
      AudioFrameOut out;
      out.channel_suffix = d.asynchronous ? d.name : "";
      sarmap::audio_frame_t& f = out.frame;
      f.device_id = d.name;
      f.sample_rate_hz = rate_;
      f.num_channels = static_cast<int16_t>(channels);
      f.num_samples = n;
      f.first_sample_index = d.next_index;
      f.overrun_samples = 0;
      f.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
      f.num_values = n * channels;
      f.samples.resize(static_cast<size_t>(n) * channels);
      f.header.frame = "mic_array";
      double stamp_s = first_true_s;
      if (d.asynchronous) {
        std::uniform_real_distribution<double> jitter(-options_.timestamp_jitter_s, options_.timestamp_jitter_s);
        stamp_s += jitter(rng_);
        for (int k = 0; k < n; ++k) {
          const double pos = (d.offset_s + (d.next_index + k) / (rate_ * (1 + d.drift))) * rate_;
          f.samples[k] = to_counts(Read(d.mics[0], pos));
        }
      } else {
        for (int c = 0; c < channels; ++c) {
          const int mic = d.mics[c];
          const int dev_channel = array_.channel_map.empty() ? c : array_.channel_map[mic];
          const std::vector<float>& h = history_[mic];
          for (int k = 0; k < n; ++k) {
            const int64_t idx = d.next_index + k - history_start_;
            const double v = idx >= 0 && idx < static_cast<int64_t>(h.size()) ? h[idx] : 0.0;
            f.samples[static_cast<size_t>(k) * channels + std::min(dev_channel, channels - 1)] = to_counts(v);
          }
        }
      }
      f.header.utime = start_utime + static_cast<int64_t>(std::llround(stamp_s * 1e6));
      frames->push_back(std::move(out));
      d.next_index += n;
    }
  }
}

float AudioSim::Read(int mic, double pos) const {
  const std::vector<float>& h = history_[mic];
  const int64_t n0 = static_cast<int64_t>(std::floor(pos));
  int phase = static_cast<int>(std::lround((pos - n0) * kPhases));
  const float* kernel = &sinc_table_[static_cast<size_t>(phase) * 2 * kInterpHalf];
  double acc = 0;
  for (int t = -kInterpHalf + 1; t <= kInterpHalf; ++t) {
    const int64_t idx = n0 + t - history_start_;
    if (idx < 0 || idx >= static_cast<int64_t>(h.size())) continue;
    acc += kernel[t + kInterpHalf - 1] * h[idx];
  }
  return static_cast<float>(acc);
}

}  // namespace sim
}  // namespace sarmap
