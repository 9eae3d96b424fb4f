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

namespace sarmap {
namespace speech {

struct KeywordOptions {
  std::string model_dir = "/usr/share/pocketsphinx/model/en-us";  // holds en-us/, en-us.lm.bin, cmudict-en-us.dict
  std::vector<std::string> keywords{"help", "rescue", "assist", "here"};
  // Per keyword (same order) or one for all: detection threshold (likelihood ratio).
  std::vector<double> thresholds{1e-20};
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
  template <class V>
  void Visit(V& v) {
    v("model_dir", model_dir, "PocketSphinx model directory (en-us/, en-us.lm.bin, cmudict-en-us.dict)");
    v("keywords", keywords, "keyphrases to spot (words must be in the dictionary)");
    v("thresholds", thresholds, "detection thresholds per keyword (or one for all), e.g. 1e-20");
    v("min_confidence", min_confidence, "keywords below this confidence (0..1) are ignored");
    v("full_decoding", full_decoding, "also decode full text with the language model");
    v("verify_with_lm", verify_with_lm, "confirm detections with language-model decoding (confidence = posterior)");
    v("verify_with_grammar", verify_with_grammar, "confirm detections with a general-vocabulary word loop");
    v("cmn", cmn, "PocketSphinx cepstral mean normalisation: current, prior or none");
    v("full_utterance", full_utterance, "process each utterance as one block (batch front end)");
  }
  void Validate(common::Validator& check) const {
    check.That(!keywords.empty(), "keywords", "needs at least one keyword");
    check.That(thresholds.size() == 1 || thresholds.size() == keywords.size(), "thresholds",
               "one value, or one per keyword");
    for (double t : thresholds) check.That(t > 0 && t < 1, "thresholds", "must be in (0, 1)");
    check.InRange("min_confidence", min_confidence, 0, 1);
    check.OneOf("cmn", cmn, {"current", "prior", "none"});
  }
};

struct KeywordHit {
  std::string keyword;
  double start_s = 0, end_s = 0;  // within the utterance
  double confidence = 0;          // 0..1
  double log_ratio = 0;           // natural log of the keyphrase/phone-loop likelihood ratio
  double kws_confidence = 0;      // from the likelihood ratio alone (first stage)
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

  // Decodes one utterance of 16 kHz mono int16 samples.
  DecodeResult Decode(const int16_t* samples, size_t count, bool full_decoding);
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

 private:
  KeywordOptions options_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace speech
}  // namespace sarmap
