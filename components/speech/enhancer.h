#pragma once
// Speech enhancement toward tracked directions (no LCM): per source an MVDR beamformer
// (delay-and-sum until the noise is known or when it is ill-conditioned), a spectral-gain
// post-filter, overlap-add back to a mono 16-bit stream; and an energy voice-activity
// detector that cuts the stream into utterances.
//
// MVDR, per bin k:  w = Phi_n^-1 d / (d^H Phi_n^-1 d),  d_m = exp(-j w_k tau_m(u)),
//   Phi_n = noise covariance averaged over non-speech frames (+ diagonal loading);
//   distortionless toward u, minimum output noise power. Delay-and-sum: w = d / M.
// Post-filter: output noise PSD  lambda(k) = w^H Phi_n w; decision-directed a-priori SNR
//   xi = a G_prev^2 |Y_prev|^2 / lambda + (1 - a) max(|Y|^2 / lambda - 1, 0);
//   Wiener gain G = max(xi / (1 + xi), G_min).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sound_localisation/array_geometry.h"
#include "sound_localisation/stft.h"

namespace sarmap {
namespace speech {

struct EnhancerOptions {
  std::string beamformer = "mvdr";  // mvdr | delay_and_sum
  int fft_size = 512;
  int hop_size = 256;
  double noise_average_s = 2.0;
  double activity_snr_db = 6.0;
  double noise_rise_db_per_s = 3.0;
  int min_noise_frames = 30;
  double diagonal_loading = 0.01;   // fraction of the mean noise power per mic
  double post_filter_floor_db = -12.0;
  double decision_directed_alpha = 0.96;
  bool post_filter = true;
  template <class V>
  void Visit(V& v) {
    v("beamformer", beamformer, "mvdr or delay_and_sum", OneOf({"mvdr", "delay_and_sum"}));
    v("fft_size", fft_size, "STFT frame");
    v("hop_size", hop_size, "STFT hop (fft_size/2 or fft_size/4)");
    v("noise_average_s", noise_average_s, "noise covariance time constant", Positive());
    v("activity_snr_db", activity_snr_db, "frames this far above the noise floor are not used for noise");
    v("noise_rise_db_per_s", noise_rise_db_per_s, "noise-floor tracker rise rate");
    v("min_noise_frames", min_noise_frames, "delay-and-sum until this many noise frames were seen");
    v("diagonal_loading", diagonal_loading, "MVDR robustness: loading as a fraction of noise power",
      NonNegative());
    v("post_filter_floor_db", post_filter_floor_db, "lowest post-filter gain");
    v("decision_directed_alpha", decision_directed_alpha, "a-priori SNR smoothing", InRange(0, 1));
    v("post_filter", post_filter, "apply the spectral-gain post-filter");
  }
  void Validate(common::Validator& check) const {
    check.That(fft_size >= 64 && (fft_size & (fft_size - 1)) == 0, "fft_size", "power of two >= 64");
    check.That(hop_size == fft_size / 2 || hop_size == fft_size / 4, "hop_size",
               "fft_size/2 or fft_size/4");
  }
};

// One beam request: a tracked source and its direction (unit vector, mic_array frame).
struct Beam {
  int64_t id = -1;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
};

class MultiBeamEnhancer {
 public:
  MultiBeamEnhancer(sound::ArrayGeometry geometry, EnhancerOptions options);
  // Feeds interleaved int16 audio; for each beam, appends enhanced samples (hop_size per
  // frame) to out[beam.id]. Beams not requested any more are dropped.
  void Push(const int16_t* data, int frames, int block_channels, const std::vector<Beam>& beams,
            std::map<int64_t, std::vector<float>>* out);
  // Where beam `id`'s output starts in the enhanced-stream numbering that every beam shares (a
  // beam present from the first frame has its n-th sample at n): a beam that appears when a track
  // is born mid-stream starts later. -1 for an unknown beam.
  int64_t FirstOutputIndex(int64_t id) const;
  bool using_mvdr() const { return noise_frames_ >= options_.min_noise_frames && options_.beamformer == "mvdr"; }
  const EnhancerOptions& options() const { return options_; }

 private:
  struct BeamState {
    Eigen::Vector3d direction;
    Eigen::MatrixXcd weights;  // bins x mics
    std::vector<double> noise_psd;
    std::vector<double> prev_clean;
    int frames_since_weights = 1 << 20;
    int64_t first_output_index = 0;
    std::unique_ptr<sound::OverlapAdd> ola;
  };
  void OnFrame(const Eigen::MatrixXcf& X, int64_t end_sample, const std::vector<Beam>& beams,
               std::map<int64_t, std::vector<float>>* out);
  void ComputeWeights(BeamState* s);

  sound::ArrayGeometry geometry_;
  EnhancerOptions options_;
  sound::MultichannelStft stft_;
  std::vector<Eigen::MatrixXcd> noise_;  // per bin
  int64_t noise_frames_ = 0;
  double noise_floor_ = -1;
  std::map<int64_t, BeamState> beams_;
  std::vector<sound::ComplexF> out_spec_;
};

struct VadOptions {
  double frame_s = 0.016;
  double threshold_db = 8.0;        // above the tracked floor
  // The threshold is at least fluctuation_factor times the mean frame-to-frame change of the
  // level below the threshold (0: off), learnt over fluctuation_time_s. The floor is the level's
  // minimum, and a beam whose MVDR nulled a point noise and whose post-filter removed the rest
  // leaves a residual that jumps 4-5 dB per frame on average: against its minimum, half its
  // frames read as speech and utterances ran to max_utterance_s. Steady noise changes by
  // 0.4 (white) to 1.4 dB (the evaluation's pinkish noise) per frame: the threshold stays 8 dB.
  double fluctuation_factor = 5.0;
  double fluctuation_time_s = 2.0;
  double floor_rise_db_per_s = 2.0;
  double hangover_s = 0.3;
  double min_speech_s = 0.12;
  double max_utterance_s = 6.0;
  double pre_roll_s = 0.25;
  template <class V>
  void Visit(V& v) {
    v("frame_s", frame_s, "analysis frame", Positive());
    v("threshold_db", threshold_db, "speech when the frame energy is this far above the noise floor");
    v("fluctuation_factor", fluctuation_factor,
      "threshold at least this times the mean frame-to-frame level change below it (0: off)",
      NonNegative());
    v("fluctuation_time_s", fluctuation_time_s, "time constant of that mean", Positive());
    v("floor_rise_db_per_s", floor_rise_db_per_s, "noise-floor tracker rise rate");
    v("hangover_s", hangover_s, "speech continues this long after the last loud frame",
      NonNegative());
    v("min_speech_s", min_speech_s, "shorter bursts are ignored");
    v("max_utterance_s", max_utterance_s, "longer utterances are cut", Positive());
    v("pre_roll_s", pre_roll_s, "audio kept before the detected onset", NonNegative());
  }
};

struct Utterance {
  int64_t start_sample = 0, end_sample = 0;  // stream indices (end exclusive)
  std::vector<int16_t> samples;              // includes the pre-roll
  int64_t samples_start = 0;                 // stream index of samples[0]
};

// Energy VAD with an adaptive floor (fast down, slow up), a threshold that rises with the
// noise's own frame-to-frame fluctuation, and hangover.
class VoiceActivityDetector {
 public:
  VoiceActivityDetector(int sample_rate_hz, VadOptions options);
  void Push(const float* samples, size_t count, std::vector<Utterance>* done);
  void Flush(std::vector<Utterance>* done);
  bool in_speech() const { return in_speech_; }
  int64_t position() const { return position_; }  // stream samples analysed so far

 private:
  void Close(std::vector<Utterance>* done);
  int rate_;
  VadOptions options_;
  int frame_len_;
  std::vector<float> frame_;
  std::vector<int16_t> history_;  // recent audio for the pre-roll / utterance
  int64_t history_start_ = 0, position_ = 0;
  double floor_ = 0;
  bool floor_init_ = false;
  double previous_db_ = 0;  // the last frame's level (valid when floor_init_)
  bool previous_loud_ = false;
  // Weighted sum of |level change| per frame below the threshold, its weight and frame count;
  // each frame's weight decays by change_decay_ = exp(-frame_s / fluctuation_time_s).
  double change_decay_;
  double change_sum_db_ = 0, change_weight_ = 0;
  int64_t change_frames_ = 0;
  bool in_speech_ = false;
  int64_t speech_start_ = 0, last_loud_ = 0;
};

// Linear-phase windowed-sinc resampling (for test voices and odd-rate files).
std::vector<float> Resample(const std::vector<float>& x, int from_hz, int to_hz);

}  // namespace speech
}  // namespace sarmap
