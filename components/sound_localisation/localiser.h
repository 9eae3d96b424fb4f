#pragma once
// Streaming sound localisation: multichannel samples -> STFT -> activity detection ->
// per-block spatial covariances -> DOA estimator -> sensor model -> multi-source tracker.
// No LCM; the node and the offline tools drive it.

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sound_localisation/array_geometry.h"
#include "sound_localisation/doa_estimators.h"
#include "sound_localisation/sensor_model.h"
#include "sound_localisation/stft.h"
#include "sound_localisation/tracker.h"

namespace sarmap {
namespace sound {

struct LocaliserOptions {
  std::string method = "srp_phat";  // gcc_phat | srp_phat | music | gevd_music | esprit
  std::string search = "auto";      // auto | 1d | azimuth | azimuth_elevation
  int fft_size = 512;
  int hop_size = 256;
  double min_frequency_hz = 1000;
  double max_frequency_hz = 7000;
  double block_s = 0.128;
  int window_blocks = 2;
  double coarse_step_deg = 5;
  double fine_step_deg = 0.25;
  double min_elevation_deg = 0;
  double max_elevation_deg = 90;
  int max_sources = 2;
  double min_separation_deg = 20;
  double min_peak_ratio = 0.6;
  int music_num_sources = 1;
  double activity_snr_db = 6;
  double min_active_fraction = 0.3;
  double noise_rise_db_per_s = 3;
  double noise_average_s = 1.0;
  double min_confidence = 0.05;
  double direct_path_threshold = 0.0;
  double direct_path_smoothing = 0.5;
  // Precedence effect: a reflection repeats the direct sound a few ms later, so while a bin's
  // power is rising the direct path dominates it. With onset_rise_db > 0 a time-frequency bin
  // enters the statistics only when its power exceeds its own recent level (exponential
  // average over onset_memory_s) by that many dB. Needs short frames (fft/hop of a few ms) to
  // separate early reflections.
  double onset_rise_db = 0.0;
  double onset_memory_s = 0.01;
  // Narrowband sources (srp_phat): besides the broadband peaks, each band of band_hz reports
  // its own power-weighted SRP-PHAT peak (BandSrpPhat) when its coherence reaches
  // band_min_coherence and it is min_separation_deg from every direction already reported;
  // at most band_max_sources such peaks per block. band_hz 0: broadband only.
  double band_hz = 0.0;
  double band_min_coherence = 0.6;
  int band_max_sources = 2;
  double band_min_tonality = 0.0;  // a band peak needs this share of its band's power in 3 bins
  // srp_phat: remove this share (0..1) of the noise covariance's cross-spectra before steering
  // (SubtractNoiseCrossSpectra); 0 off.
  double noise_subtraction = 0.0;
  // Detection (srp_phat): "activity" estimates in blocks with enough loud frames (energy gate);
  // "cfar" tests every block. SRP-PHAT through the pairs' correlations (CorrelationSrp), every
  // frame's bins weighted by their power above the noise; each grid direction's value is
  // standardised by its own noise mean and variance (over blocks without a detection, time
  // constant noise_map_s) and a source declared where it exceeds the threshold that gives
  // false_alarm_probability per block (Bonferroni over the grid, Gaussian values). Among the
  // directions that pass, the strongest is taken, refined, removed from every pair's
  // correlation (suppression), and the next searched, up to max_sources; a further source must
  // be a local maximum of the block's map (secondary_local_max). With band_hz > 0, band peaks
  // of the block's loud frames (energy gate) follow the detected directions.
  std::string detection = "activity";
  double false_alarm_probability = 0.01;
  double noise_map_s = 10.0;
  // Blocks with a detection also teach the noise statistics, with this (slower) time constant:
  // a sound heard without pause for much longer than anyone talks becomes background. 0: never.
  double steady_s = 0.0;
  // Half-width of the lag neighbourhood removed around a found source (samples); 0: the main
  // lobe of the band's PHAT correlation, fs / (2 (min_frequency + max_frequency)).
  double suppression_samples = 0.0;
  // "clean": subtract the found source's whole correlation (CorrelationSrp::Subtract), side and
  // grating lobes included; "zero": zero its lag neighbourhood (suppression_samples).
  std::string suppression = "clean";
  // A further source must be a local maximum of the block's map before suppression.
  bool secondary_local_max = true;
  TrackerOptions tracker;

  template <class V>
  void Visit(V& v) {
    v("method", method, "gcc_phat, srp_phat, music, gevd_music or esprit (uniform linear arrays)",
      OneOf({"gcc_phat", "srp_phat", "music", "gevd_music", "esprit"}));
    v("search", search,
      "auto (1d for linear arrays, else azimuth_elevation), 1d, azimuth, azimuth_elevation",
      OneOf({"auto", "1d", "azimuth", "azimuth_elevation"}));
    v("fft_size", fft_size, "STFT frame length (samples)");
    v("hop_size", hop_size, "STFT hop (samples)");
    v("min_frequency_hz", min_frequency_hz, "lowest analysed frequency", Positive());
    v("max_frequency_hz", max_frequency_hz, "highest analysed frequency");
    v("block_s", block_s, "one DOA output per block of this length", Positive());
    v("window_blocks", window_blocks, "covariances are summed over this many blocks", AtLeast(1));
    v("coarse_step_deg", coarse_step_deg, "coarse direction grid step", Positive());
    v("fine_step_deg", fine_step_deg, "refinement stops at this step", Positive());
    v("min_elevation_deg", min_elevation_deg, "elevation search range (azimuth_elevation)",
      InRange(-90, 90));
    v("max_elevation_deg", max_elevation_deg, "elevation search range (azimuth_elevation)",
      InRange(min_elevation_deg, 90));
    v("max_sources", max_sources, "most simultaneous sources reported per block", AtLeast(1));
    v("min_separation_deg", min_separation_deg, "closer peaks are suppressed", NonNegative());
    v("min_peak_ratio", min_peak_ratio,
      "secondary peaks must reach this fraction of the best (0..1)", InRange(0, 1));
    v("music_num_sources", music_num_sources, "MUSIC/ESPRIT signal-subspace dimension", AtLeast(1));
    v("activity_snr_db", activity_snr_db,
      "frames this far above the noise floor are active (sound)");
    v("min_active_fraction", min_active_fraction, "a block needs this fraction of active frames",
      InRange(0, 1));
    v("noise_rise_db_per_s", noise_rise_db_per_s, "noise-floor tracker rise rate");
    v("noise_average_s", noise_average_s, "time constant of the noise covariance (GEVD)",
      Positive());
    v("min_confidence", min_confidence, "weaker estimates are dropped", InRange(0, 1));
    v("direct_path_threshold", direct_path_threshold,
      "use a time-frequency bin only when its short-time covariance is this close to rank 1 "
      "(|R|_F^2 / tr(R)^2, 1/M diffuse .. 1 one plane wave); 0 uses every bin",
      InRange(0, 1));
    v("direct_path_smoothing", direct_path_smoothing,
      "weight of the past in that short-time covariance (0..1)", InRange(0, 0.99));
    v("onset_rise_db", onset_rise_db,
      "precedence effect: use a bin only when its power rose this many dB above its recent level "
      "(0: all)",
      NonNegative());
    v("onset_memory_s", onset_memory_s, "time constant of that recent level", Positive());
    v("band_hz", band_hz,
      "srp_phat: also report each band's (this wide) power-weighted peak, so a narrowband source "
      "that "
      "dominates its own band is heard beside broadband ones (0: broadband only)",
      NonNegative());
    v("band_min_coherence", band_min_coherence,
      "a band's peak needs this weighted PHAT coherence (0..1)", InRange(0, 1));
    v("band_max_sources", band_max_sources, "most band peaks added per block", AtLeast(0));
    v("band_min_tonality", band_min_tonality,
      "a band peak needs this share of its band's power in its 3 strongest bins (tones ~1; noise "
      "and "
      "voiced speech lower); 0: any band",
      InRange(0, 1));
    v("noise_subtraction", noise_subtraction,
      "srp_phat: remove this share (0..1) of the steady noise's cross-spectra (learnt between "
      "sounds) "
      "before steering, so a steady interferer does not bend a voice's bearing; 0: off",
      InRange(0, 1));
    v("detection", detection,
      "activity (energy gate) or cfar (srp_phat: every block, standardised against learnt noise "
      "statistics per "
      "direction, calibrated false-alarm rate, several sources by suppression)",
      OneOf({"activity", "cfar"}));
    v("false_alarm_probability", false_alarm_probability,
      "cfar: chance per block that noise alone gives a detection");
    v("noise_map_s", noise_map_s, "cfar: time constant of the per-direction noise statistics",
      Positive());
    v("steady_s", steady_s,
      "cfar: blocks with a detection also teach the noise statistics with this time constant, so "
      "an "
      "unceasing sound becomes background (0: never)",
      NonNegative());
    v("suppression", suppression,
      "cfar: clean (subtract a found source's whole correlation) or zero (its lag neighbourhood)",
      OneOf({"clean", "zero"}));
    v("secondary_local_max", secondary_local_max,
      "cfar: a further source must be a local maximum of the block's map");
    v("suppression_samples", suppression_samples,
      "cfar: half-width of the lag neighbourhood removed around a found source (0: band's main "
      "lobe)",
      NonNegative());
    v("tracker", tracker, "multi-source tracker");
  }
  void Validate(common::Validator& check) const {
    check.That(fft_size >= 64 && (fft_size & (fft_size - 1)) == 0, "fft_size",
               "must be a power of two >= 64");
    check.That(hop_size >= 1 && hop_size <= fft_size, "hop_size", "must be in [1, fft_size]");
    check.That(max_frequency_hz > min_frequency_hz, "max_frequency_hz",
               "must exceed min_frequency_hz");
    check.That(detection != "cfar" || method == "srp_phat", "detection",
               "cfar needs method srp_phat");
    check.That(false_alarm_probability > 0 && false_alarm_probability < 1,
               "false_alarm_probability", "must be in (0, 1)");
  }
};

struct LocalisedDirection {
  Direction direction;         // after the sensor model
  Eigen::Matrix2d covariance;  // rad^2
  double power = 0, confidence = 0;
  int band = -1;       // band peak (BandSrpPhat band index); -1 broadband
  double band_hz = 0;  // that band's centre
};

struct LocaliserOutput {
  int64_t end_sample = 0;     // stream sample one past the window
  int64_t centre_sample = 0;  // centre of the analysed window
  bool active = false;        // activity: enough sound to estimate; cfar: a source detected
  std::vector<LocalisedDirection> directions;  // this block, best first
  std::vector<Track> tracks;                   // confirmed tracks after this block
};

DoaKind ResolveKind(const ArrayGeometry& geometry, const std::string& search);
// t with Q(t) = p for a standard normal variable (upper tail).
double InverseNormalTail(double p);

class Localiser {
 public:
  // Throws std::invalid_argument for a method the array cannot use (ESPRIT on a non-ULA).
  Localiser(ArrayGeometry geometry, LocaliserOptions options,
            std::unique_ptr<SensorModel> sensor_model);
  const ArrayGeometry& geometry() const { return geometry_; }
  const LocaliserOptions& options() const { return options_; }
  DoaKind kind() const { return kind_; }

  // Feeds interleaved int16 samples (block_channels per frame, mics taken through the
  // array's channel_map). Appends one output per completed block.
  void Push(const int16_t* data, int frames, int block_channels, std::vector<LocaliserOutput>* out);
  void PushFloat(const std::vector<std::vector<float>>& mic_channels, size_t begin, size_t count,
                 std::vector<LocaliserOutput>* out);
  // Forget the signal (after a discontinuity); the noise model and tracks stay.
  void ResetStream();
  // A short gap of `samples` lost samples: the next samples are analysed as if they followed
  // on, the stream's sample count (and so every later output's position) advanced by the gap.
  // On one clock all channels jump together, so the frames across the join keep the right
  // inter-channel delays.
  void SkipSamples(int64_t samples);

  // One estimate from given statistics (offline use, tests).
  std::vector<DoaEstimate> Estimate(const BlockStatistics& stats) const;
  // srp_phat with band peaks (band_hz > 0): broadband peaks first, then band peaks.
  std::vector<DoaEstimate> EstimateWithBands(const BlockStatistics& stats) const;
  // Empty statistics shaped for this localiser's band.
  BlockStatistics MakeStatistics() const;
  // Adds one frame of spectra (num_bins x mics) to `stats` (as active).
  // `mask` (optional, one per band bin) selects the bins to add.
  void Accumulate(const Eigen::MatrixXcf& spectra, BlockStatistics* stats,
                  const std::vector<char>* mask = nullptr) const;
  // Marks the bins of this frame dominated by one plane wave (direct-path dominance test on
  // the smoothed covariance `state`, updated in place).
  void DirectPathMask(const Eigen::MatrixXcf& spectra, std::vector<Eigen::MatrixXcd>* state,
                      std::vector<char>* mask) const;
  // Precedence effect: clears the mask of the bins whose power did not rise onset_rise_db
  // above their recent level `level` (updated in place).
  void OnsetMask(const Eigen::MatrixXcf& spectra, std::vector<double>* level,
                 std::vector<char>* mask) const;
  int64_t samples_seen() const { return samples_seen_; }
  // cfar: the standardised threshold (from false_alarm_probability and the grid size).
  double detection_threshold() const { return detection_threshold_; }

 private:
  void OnFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample,
               std::vector<LocaliserOutput>* out);
  // cfar detection on one window's statistics.
  std::vector<DoaEstimate> Detect(const BlockStatistics& stats);
  bool IsGridLocalMax(const std::vector<double>& values, size_t index) const;
  // Band peaks (band_hz > 0) of `stats` appended to `out` when far from every direction in it.
  void AddBandPeaks(const BlockStatistics& stats, std::vector<DoaEstimate>* out) const;
  void AddBandPeaks(const BandSrpPhat& bands, const std::vector<std::vector<double>>& band_values,
                    std::vector<DoaEstimate>* out) const;
  void AccumulateWeighted(const Eigen::MatrixXcf& spectra, BlockStatistics* stats,
                          const std::vector<char>* mask, BlockStatistics* plain = nullptr) const;

  ArrayGeometry geometry_;
  LocaliserOptions options_;
  std::unique_ptr<SensorModel> sensor_model_;
  DoaKind kind_;
  SearchOptions search_;
  MultichannelStft stft_;
  DoaTracker tracker_;
  int bin_lo_, bin_hi_, block_frames_;
  BlockStatistics current_;
  int current_frames_ = 0;
  std::deque<BlockStatistics> window_;
  // cfar with band peaks: the loud frames' unweighted statistics, for the band peaks.
  BlockStatistics current_band_;
  std::deque<BlockStatistics> window_band_;
  std::vector<Eigen::Vector3d> band_grid_units_;
  std::deque<int> window_total_frames_;
  int current_active_ = 0;  // frames the energy gate calls active (cfar accumulates all)
  std::deque<int> window_active_;
  std::vector<Eigen::MatrixXcd> noise_;
  std::vector<Eigen::MatrixXcd> smoothed_;
  std::vector<char> mask_;
  std::vector<double> onset_level_;
  int64_t noise_frames_ = 0;
  double noise_floor_ = -1;
  int64_t samples_seen_ = 0;
  // cfar
  std::unique_ptr<CorrelationSrp> correlation_;
  std::vector<Eigen::Vector3d> grid_units_;
  std::vector<double> noise_mean_, noise_var_;
  int64_t noise_map_blocks_ = 0;
  double detection_threshold_ = 0;  // standardised value
  int64_t stream_offset_ = 0;       // samples before the last ResetStream
};

}  // namespace sound
}  // namespace sarmap
