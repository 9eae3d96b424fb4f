#pragma once
// TDOA extraction from a calibration recording (Su 2017 sec. 3.5.4.1): the source emits a
// short sound (chirp, clap) repeatedly while it moves; each emission is found on the
// reference channel, and its arrival on every other channel is measured against the
// reference by GCC-PHAT (or a plain matched filter with the reference snippet as template)
// after a high-pass filter, with parabolic sub-sample interpolation of the peak.
//
// Every channel may run on its own clock: channel c's sample i is at time
// channel_start_s[c] + i / sample_rate_hz on the reference clock as far as known (from the
// utimes of an LCM log; 0 for a WAV). What this alignment gets wrong is the start offset and
// drift the calibration estimates.

#include <string>
#include <vector>

#include "common/options.h"
#include "mic_calibrate/calibration.h"

namespace sarmap {
namespace mic_calibrate {

struct Recording {
  double sample_rate_hz = 0;
  std::vector<std::vector<float>> channels;  // one per microphone, mic order
  std::vector<double> channel_start_s;       // per channel (empty = all 0)
  std::vector<std::string> channel_names;    // for messages (device:channel)
  // Absolute time (us, e.g. LCM utime) of reference time 0; 0 = unknown (WAV). Lets the
  // emissions be matched with array poses (TdoaData::utimes).
  int64_t reference_start_utime = 0;
};

struct ExtractionOptions {
  double highpass_hz = 300;          // below the calibration sound (thesis: equiripple HP)
  std::string method = "gcc_phat";   // gcc_phat | matched
  double max_lag_s = 0.2;            // |TDOA| search range (start offsets included)
  double window_s = 0.04;            // correlation window from just before the onset
  double pre_onset_s = 0.003;
  double onset_threshold_db = 15;    // frame energy above the noise floor that starts an event
  double min_event_spacing_s = 0.25; // onsets closer than this belong to one emission
  double frame_s = 0.002;
  double min_peak_ratio = 2.0;       // peak / next-best peak outside +-1 ms; lower = missing
  template <class V>
  void Visit(V& v) {
    v("highpass_hz", highpass_hz, "high-pass cut-off before onset detection and correlation",
      NonNegative());
    v("method", method, "gcc_phat or matched (plain cross-correlation with the reference)",
      OneOf({"gcc_phat", "matched"}));
    v("max_lag_s", max_lag_s, "largest |TDOA| searched (must cover the start offsets)", Positive());
    v("window_s", window_s, "correlation window length from the onset", Positive());
    v("pre_onset_s", pre_onset_s, "window start before the detected onset", NonNegative());
    v("onset_threshold_db", onset_threshold_db, "onset: frame energy this far above the floor",
      Positive());
    v("min_event_spacing_s", min_event_spacing_s, "minimum time between two emissions", Positive());
    v("frame_s", frame_s, "energy frame for onset detection", Positive());
    v("min_peak_ratio", min_peak_ratio, "weaker correlation peaks give a missing TDOA (NaN)",
      AtLeast(1));
  }
};

struct ExtractionStats {
  int events = 0;
  int missing = 0;  // TDOAs left NaN (weak or ambiguous peak)
  std::vector<std::string> warnings;
};

// Emission times t_k (reference clock, s since the reference channel's first sample) and
// TDOAs of every channel against channel 0.
TdoaData ExtractTdoas(const Recording& rec, const ExtractionOptions& options,
                      ExtractionStats* stats);

// Reads a multichannel WAV (any libsndfile format); throws std::runtime_error.
Recording ReadWav(const std::string& path);
void WriteWav(const std::string& path, const Recording& rec);

// Simple 4th-order Butterworth high-pass (two cascaded biquads), in place.
void HighPass(std::vector<float>* x, double sample_rate_hz, double cutoff_hz);

// Synthetic recording for tests: every emission k is a Hann-windowed linear chirp
// (f0..f1 Hz, length chirp_s) at true time t_k = times_s[k], from source position s_k;
// channel n runs on a clock that reads t (1 + delta_n) + tau_n at true time t, so the
// measured TDOA follows the calibration model. White noise of noise_rms is added.
struct ChirpSynthesis {
  double sample_rate_hz = 44100;
  double chirp_s = 0.02, f0_hz = 1000, f1_hz = 8000;
  double noise_rms = 0.01;
  double speed_of_sound_mps = 340;
  double tail_s = 0.3;
};
Recording SynthesiseChirps(const std::vector<Eigen::Vector3d>& mics,
                           const std::vector<double>& start_offsets_s,
                           const std::vector<double>& clock_drift,
                           const std::vector<Eigen::Vector3d>& sources,
                           const std::vector<double>& times_s, const ChirpSynthesis& synth,
                           uint64_t seed);

}  // namespace mic_calibrate
}  // namespace sarmap
