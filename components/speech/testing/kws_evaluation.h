#pragma once
// Keyword-spotting evaluation on simulated calls for help (no LCM): positives are calls
// ("help", "help me", "please help", ...) rendered by espeak-ng with varied voices, rates and
// pitches, placed in noise and other talkers; negatives are a long stream of other speech
// (real recordings from the shared data, plus espeak-ng sentences without keywords) in
// noise. Both go through the VAD and PocketSphinx exactly as in the node (mono path).

#include <cstdint>
#include <string>
#include <vector>

#include "speech/enhancer.h"
#include "speech/keyword_spotter.h"
#include "speech/speech_processor.h"

namespace sarmap {
namespace speech {

// Renders `text` with espeak-ng at 16 kHz (empty if espeak-ng is unavailable).
std::vector<float> RenderEspeak(const std::string& text, const std::string& voice,
                                int words_per_minute, int pitch);
bool EspeakAvailable();
// Renders `text` with flite (voice kal16, awb, rms or slt; duration_stretch > 1 is slower) at
// 16 kHz (empty if flite is unavailable). flite's voices are built from recorded speech, and the
// en-us acoustic model recognises them, unlike espeak-ng's formant synthesis (README).
std::vector<float> RenderFlite(const std::string& text, const std::string& voice,
                               double duration_stretch);
bool FliteAvailable();

struct KwsEvalOptions {
  int num_calls = 40;
  double negative_minutes = 10.0;
  double call_snr_db = 10.0;  // call vs background (noise + babble)
  double babble_db = -6.0;    // other talkers relative to the call, positives
  uint32_t seed = 1;
  std::string data_dir;  // shared data (real negative speech)
  std::string target = "help";
  // Fit the keyword verifier (keyword_verifier.h) on the TUNING half's hits with these features
  // (empty: use keywords.verifier as given): calls = "help" hits inside the call window of tuning
  // scenes whose call is at most fit_max_call_s long (at the last call join); other speech = every
  // "help" hit of the tuning half of the negative stream (any length: far more examples than the
  // few that pass the call-shape rule).
  std::vector<std::string> fit_verifier_features;
  // Short synthetic confusers: this many scenes built like the calls (same espeak-ng voices,
  // rates, pitches, noise and SNR) but saying a short phrase WITHOUT "help" ("hello", "hold on",
  // "well done"...). "help" detections there are false alarms on synthetic speech of a call's
  // shape: the test of a verifier that might only have learnt "synthetic voice".
  int num_confusers = 0;
  // Synthesiser of the calls, the confusers and the synthetic negative sentences: "espeak"
  // (espeak-ng) or "flite".
  std::string tts = "espeak";
  double fit_l2 = 0.01;
  double fit_max_call_s = 1.8;
  // Diagnostics. features_csv: one CSV row per hit with its features (hit_features.h), its half
  // (tune / held) and, in the negative stream, the recording it fell in. dump: "" (none),
  // "hits" (every utterance and hit on stderr) or "llr" (also the slow acoustic verification of
  // every hit). segment_dir: each utterance with a hit (at most 2 s), as raw s16le, named by its
  // label and time.
  std::string features_csv;
  std::string dump;
  std::string segment_dir;
};

struct KwsEvalResult {
  double threshold = 0;
  double min_confidence = 0;
  double max_utterance_s = 0;  // post-filter: hits in longer utterances dropped (0: none)
  double call_join_s = 0;      // utterances closer than this are one call for max_utterance_s
  int calls = 0, hits = 0;
  double recall = 0;
  int target_false_alarms = 0;  // target keyword in the negative stream
  int other_false_alarms = 0;   // any other keyword in the negative stream
  double negative_minutes = 0;
  double false_alarms_per_10_min = 0;
  double decode_seconds = 0;  // CPU time spent (for the curve's cost)
  // The same on two disjoint halves: "tune" (calls 0-7, 16-23, ...: every phrasing; first half
  // of the negative stream) to choose an operating point, "held" (calls 8-15, 24-31, ...;
  // second half) to report it.
  int tune_calls = 0, tune_hits = 0, tune_false_alarms = 0;
  int held_calls = 0, held_hits = 0, held_false_alarms = 0;
  double tune_recall = 0, tune_fa_per_10_min = 0, held_recall = 0, held_fa_per_10_min = 0;
  // Keyword verifier (-1: none). False alarms split by the kind of negative recording (real
  // recordings vs espeak-ng sentences), and the verifier's pass rate alone (no call-shape rule)
  // on every "help" hit of each kind: a verifier that only learnt "synthetic voice" would pass
  // the synthetic negatives like the calls.
  double verifier_min_probability = -1;
  int tune_fa_real = 0, tune_fa_synthetic = 0, held_fa_real = 0, held_fa_synthetic = 0;
  double verifier_pass_calls = 0, verifier_pass_real = 0, verifier_pass_synthetic = 0;
  int confuser_scenes = 0, confuser_false_alarms = 0;  // scenes with a passing "help" / scenes
  VerifierOptions verifier;  // the verifier used (fitted when fit_verifier_features was given)
};

struct KwsEvalData {
  std::vector<std::vector<float>> positives;  // 16 kHz scenes, call at call_start_s
  std::vector<double> call_start_s, call_end_s;
  std::vector<std::vector<float>> confusers;  // short synthetic non-calls (num_confusers)
  std::vector<float> negatives;               // one long 16 kHz stream
  // What the negative stream is made of: each recording's span (samples, without the noise gap
  // before it), its name, and whether it is an espeak-ng sentence (synthetic) or a real recording.
  struct NegativeSource {
    int64_t start_sample = 0, end_sample = 0;
    std::string name;
    bool synthetic = false;
  };
  std::vector<NegativeSource> negative_sources;
  // Label of the negative source at stream time t (s): "real:<file>" / "espeak:<n>", "gap" between.
  std::string NegativeSourceAt(double t_s, bool* synthetic = nullptr) const;
  // The parts of each positive scene (summed in `positives`): the call (placed), other talker,
  // noise.
  std::vector<std::vector<float>> positive_call, positive_babble, positive_noise;
};

// Recall of the multichannel path (SpeechProcessor: per-track MVDR beam -> VAD -> keywords, with
// its call-shape rule) on the positive scenes rendered on `array` in an anechoic room: the call
// from azimuth call_azimuth_deg, the other talker from babble_azimuth_deg, the noise from a third
// direction; both talkers given as tracks (as the localiser would), a call counts when "help" is
// heard on the caller's track within its window.
struct KwsArrayResult {
  int hits = 0;   // calls heard
  int calls = 0;  // scenes
  // "help" results outside the call windows, on any track (the warm-up's noise alone, the other
  // talker, the noise around each call), except in each fresh processor's first second, its cold
  // start; and the seconds of beam output they were counted over.
  int false_hits = 0;
  double false_hit_seconds = 0;
};
KwsArrayResult KwsArrayRecall(const KwsEvalData& data, const std::string& array_yaml,
                              const KeywordOptions& keywords, double call_azimuth_deg,
                              double babble_azimuth_deg, const VadOptions& vad = VadOptions(),
                              bool post_filter = true);

KwsEvalData MakeKwsEvalData(const KwsEvalOptions& options);
KwsEvalResult EvaluateKws(const KwsEvalData& data, const KeywordOptions& keywords,
                          const VadOptions& vad, const KwsEvalOptions& options);
// One decoding pass, results for each confidence cut (the cut is a pure post-filter).
std::vector<KwsEvalResult> EvaluateKwsSweep(
    const KwsEvalData& data, const KeywordOptions& keywords, const VadOptions& vad,
    const KwsEvalOptions& options, const std::vector<double>& min_confidences,
    const std::vector<double>& max_utterances_s = {0.0},
    const std::vector<double>& call_joins_s = {0.0},
    const std::vector<double>& verifier_min_probabilities = {});

}  // namespace speech
}  // namespace sarmap
