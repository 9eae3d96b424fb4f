#pragma once
// Per-detection features of a keyword hit, measured on the hit's voice-activity utterance
// (no PocketSphinx here): for the keyword verifier (keyword_verifier.h) and the evaluation's
// feature dump (kws_eval --features-csv).

#include <cstdint>
#include <string>
#include <vector>


namespace sarmap {
namespace speech {

struct HitFeatures {
  double log_ratio = 0;        // kws keyphrase / phone-loop log-likelihood ratio (nats)
  double duration_s = 0;       // hit length (kws segment)
  double ratio_per_s = 0;      // log_ratio / duration_s
  double utterance_s = 0;      // voice-activity segment (with pre-roll and hangover)
  double lead_s = 0;           // hit start - speech onset (s; < 0 when it starts in the pre-roll)
  double trail_s = 0;          // speech end - hit end (s)
  double snr_db = 0;           // utterance: 95th - 10th percentile of 10 ms frame energies (dB)
  double hit_level_db = 0;     // hit's mean frame energy - utterance's 95th percentile (dB)
  double voiced_fraction = 0;  // hit frames with a normalised autocorrelation peak > 0.6 at 60-400 Hz
  double pitch_hz = 0;         // median pitch of voiced hit frames (0: none)
  double pitch_range_st = 0;   // 90th - 10th percentile of their pitch (semitones)
  double tilt_db = 0;          // hit: energy of the first difference over energy (dB): spectral tilt
  double phone_distance = -1;  // phone-loop string vs the keyword's phones: edit distance / keyword phones (-1: not computed)
  std::string phones;          // that phone string
};

// `samples` is the utterance (16 kHz); speech_onset_s / speech_end_s are its speech part within
// it; the hit spans hit_start_s..hit_end_s of the utterance with the kws log ratio log_ratio.
// phone_distance / phones are left for the caller (they need the decoder's phone loop).
HitFeatures ComputeHitFeatures(const int16_t* samples, size_t count, double speech_onset_s, double speech_end_s,
                               double hit_start_s, double hit_end_s, double log_ratio);

// Levenshtein distance between two phone strings.
int PhoneEditDistance(const std::vector<std::string>& a, const std::vector<std::string>& b);

}  // namespace speech
}  // namespace sarmap
