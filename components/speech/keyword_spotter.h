#pragma once
// PocketSphinx (5prealpha API) keyword spotting and full decoding of 16 kHz mono speech.
//
// Keyword spotting uses PocketSphinx's "kws" search: each keyphrase is an HMM chain matched
// against a phone loop; a detection fires when the keyphrase's score beats the phone loop's
// by the phrase's threshold (a likelihood ratio, e.g. 1e-20). Full decoding uses the n-gram
// language model ("lm" search) of the en-us model.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "speech/keyword_verifier.h"

namespace sarmap {
namespace speech {

struct KeywordOptions {
  std::string model_dir = "/usr/share/pocketsphinx/model/en-us";  // holds en-us/, en-us.lm.bin, cmudict-en-us.dict
  std::vector<std::string> keywords{"help", "rescue", "assist", "here"};
  // Per keyword (same order) or one for all: detection threshold (likelihood ratio).
  std::vector<double> thresholds{1e-40};
  double min_confidence = 0.6;  // detections below are not published as keywords
  bool full_decoding = false;   // also decode each utterance with the language model (loads it)
  // Second stage: an utterance with a keyword detection is decoded with the n-gram language
  // model; the detection stands only if the keyword is in that hypothesis, and its confidence
  // becomes the keyword's lattice posterior probability.
  bool verify_with_lm = false;
  // Cheaper second stage: decode the utterance with a free-loop grammar over a general
  // vocabulary (and the keywords' sound-alikes); the keyword must be in that hypothesis.
  bool verify_with_grammar = false;
  std::string cmn = "current";   // PocketSphinx cepstral mean normalisation: current, prior or none
  bool full_utterance = false;   // hand PocketSphinx each utterance as one block
  // Acoustic verification of each kws detection (classic keyword verification): the hit's
  // segment (padded) is force-aligned to the keyphrase and decoded with an unconstrained phone
  // loop (allphone search, en-us phonetic LM); the per-frame log-likelihood ratio
  //   llr = (log p(X | keyphrase) - log p(X | best phone string)) / frames   (<= ~0)
  // must be at least verify_min_llr. Close to 0: nothing explains the sound better than the keyphrase.
  // Units: natural log of PocketSphinx's acoustic scores, which 5prealpha keeps scaled down
  // (SENSCR_SHIFT), so values are small (calls and other speech both -0.004..0, see README).
  bool verify_acoustic = false;
  double verify_min_llr = -0.002;
  double verify_pad_s = 0.1;
  bool verify_phone_lm = false;  // phone loop weighted by the en-us phonetic LM (else a free loop)     // segment = hit widened by this on each side
  // Shape of a call: the hit lasts min..max duration, and covers at least this fraction of its
  // voice-activity segment (a call is a short shouted utterance, not a word inside a sentence).
  double min_duration_s = 0.0;
  double max_duration_s = 10.0;
  double min_utterance_fraction = 0.0;
  // > 0: the hit's voice-activity segment is at most this long (and longer ones are not decoded).
  // 1.8 s with 1e-40 (README): the tuning half of sarmap-log kws-eval reaches recall 0.9 from
  // 1.4 s, but reverberation lengthens a call's segment (a "help me" in RT60 0.3 s: 1.4-1.8 s).
  double max_utterance_s = 1.8;
  // The call-shape rule applies to a call: voice-activity segments separated by less than this
  // much non-speech (s, after the VAD's hangover) are one call, and the whole call must be at
  // most max_utterance_s long (a "help" that starts or ends a longer stretch of talk is dropped;
  // results wait this long after the segment's end). 0: each segment on its own. 0.5 s (README):
  // bridges pauses up to ~0.8 s of silence (with the VAD's 0.3 s hangover), the scale of pauses
  // inside a sentence; longer values only look better on sarmap-log kws-eval because its stream
  // of other speech has 0.3-1.5 s gaps (>= ~1.2 s joins all of it).
  double call_join_s = 0.5;
  // Verifier of each detection that passed the call-shape rule (keyword_verifier.h; README:
  // what it learns on the evaluation set, and why it is off by default).
  VerifierOptions verifier;
  template <class V>
  void Visit(V& v) {
    v("model_dir", model_dir, "PocketSphinx model directory (en-us/, en-us.lm.bin, cmudict-en-us.dict)");
    v("keywords", keywords, "keyphrases to spot (words must be in the dictionary)");
    v("thresholds", thresholds, "detection thresholds per keyword (or one for all), e.g. 1e-20");
    v("min_confidence", min_confidence, "keywords below this confidence (0..1) are ignored",
      InRange(0, 1));
    v("full_decoding", full_decoding, "also decode full text with the language model");
    v("verify_with_lm", verify_with_lm, "confirm detections with language-model decoding (confidence = posterior)");
    v("verify_with_grammar", verify_with_grammar, "confirm detections with a general-vocabulary word loop");
    v("cmn", cmn, "PocketSphinx cepstral mean normalisation: current, prior or none",
      OneOf({"current", "prior", "none"}));
    v("full_utterance", full_utterance, "process each utterance as one block (batch front end)");
    v("verify_acoustic", verify_acoustic, "verify detections: forced alignment vs phone loop, per-frame LLR");
    v("verify_min_llr", verify_min_llr, "minimum per-frame log-likelihood ratio of the verification (PocketSphinx scaled log units)");
    v("verify_phone_lm", verify_phone_lm, "weight the verification phone loop with the en-us phonetic LM");
    v("verify_pad_s", verify_pad_s, "seconds added to each side of the hit for the verification",
      InRange(0, 1));
    v("min_duration_s", min_duration_s, "shortest accepted detection (s)");
    v("max_duration_s", max_duration_s, "longest accepted detection (s)");
    v("min_utterance_fraction", min_utterance_fraction,
      "detection must cover at least this fraction of its voice-activity segment (0..1)",
      InRange(0, 1));
    v("max_utterance_s", max_utterance_s,
      "> 0: only utterances at most this long (s) can hold a call; 0: every utterance is "
      "decoded (safer where other people talk near a caller)",
      AtLeast(0));
    v("call_join_s", call_join_s,
      "with max_utterance_s: segments closer than this (s) count as one call for the length limit "
      "(0: off)",
      InRange(0, 5));
    v("verifier", verifier, "logistic-regression verifier over per-hit features (README)");
  }
  void Validate(common::Validator& check) const {
    check.That(!keywords.empty(), "keywords", "needs at least one keyword");
    check.That(thresholds.size() == 1 || thresholds.size() == keywords.size(), "thresholds",
               "one value, or one per keyword");
    for (double t : thresholds) check.That(t > 0 && t < 1, "thresholds", "must be in (0, 1)");
    check.That(min_duration_s >= 0 && max_duration_s > min_duration_s, "max_duration_s",
               "needs 0 <= min_duration_s < max_duration_s");
  }
};

struct KeywordHit {
  std::string keyword;
  double start_s = 0, end_s = 0;  // within the utterance
  double confidence = 0;          // 0..1
  double log_ratio = 0;           // natural log of the keyphrase/phone-loop likelihood ratio
  double kws_confidence = 0;      // from the likelihood ratio alone (first stage)
  double verify_llr = 0;          // per-frame LLR of the acoustic verification (nats), if computed
  bool verified = false;          // verify_llr was computed
  double utterance_s = 0;         // length of the decoded utterance
  double verifier_probability = -1;  // keyword verifier's probability (-1: not computed)
  HitFeatures features;           // set when the verifier ran (or features were asked for)
};

struct DecodeResult {
  std::vector<KeywordHit> keywords;
  std::string text;               // full hypothesis (full decoding), else ""
  double text_confidence = 0;     // posterior of the hypothesis (0..1)
};

class KeywordSpotter {
 public:
  // Throws std::runtime_error with the reason (missing model, word not in dictionary...).
  explicit KeywordSpotter(const KeywordOptions& options);
  ~KeywordSpotter();
  KeywordSpotter(const KeywordSpotter&) = delete;
  KeywordSpotter& operator=(const KeywordSpotter&) = delete;

  // Decodes one utterance of 16 kHz mono int16 samples. speech_onset_s / speech_end_s: where the
  // voice activity starts and ends within it (after the pre-roll, before the end; < 0: unknown,
  // taken as 0 and the utterance's end); used by the verifier's lead_s / trail_s features.
  DecodeResult Decode(const int16_t* samples, size_t count, bool full_decoding, double speech_onset_s = -1,
                      double speech_end_s = -1);
  DecodeResult Decode(const std::vector<int16_t>& s) { return Decode(s.data(), s.size(), options_.full_decoding); }
  // Language-model decoding only (text).
  std::string DecodeText(const std::vector<int16_t>& samples, double* confidence = nullptr);
  // Decoding with a named search (words with posteriors).
  std::vector<std::pair<std::string, double>> DecodeSearch(const std::string& search, const int16_t* samples,
                                                           size_t count);
  // LM decoding with per-word posterior probabilities.
  std::vector<std::pair<std::string, double>> DecodeWords(const int16_t* samples, size_t count, std::string* text,
                                                          double* confidence);
  const KeywordOptions& options() const { return options_; }
  // Per-frame log-likelihood ratio of `keyword` (forced alignment) against the phone loop over
  // samples[begin, end) (see verify_acoustic). -inf when the alignment fails.
  double VerificationLlr(const std::string& keyword, const int16_t* samples, size_t count);
  // Best phone string of an unconstrained phone loop (allphone search, context-independent
  // phones, SIL and fillers dropped) over the samples; needs en-us-phone.lm.bin.
  std::vector<std::string> PhoneLoop(const int16_t* samples, size_t count);
  // Dictionary phones of a keyphrase ("help" -> HH EH L P).
  std::vector<std::string> KeywordPhones(const std::string& keyword);
  // Features of a hit (hit_features.h), phone_distance included when with_phones.
  HitFeatures Features(const int16_t* samples, size_t count, const KeywordHit& hit, double speech_onset_s,
                       double speech_end_s, bool with_phones);
  // Always compute verify_llr (for evaluation) even when verify_acoustic is off.
  void set_compute_verification(bool on) { compute_verification_ = on; }

 private:
  KeywordOptions options_;
  KeywordVerifier verifier_;
  bool compute_verification_ = false;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace speech
}  // namespace sarmap
