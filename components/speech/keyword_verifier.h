#pragma once
// Keyword verifier: a logistic regression over per-hit features (hit_features.h), applied to
// each keyword detection that passed the call-shape rule:
//
//   p = 1 / (1 + exp(-(bias + sum_i weight_i * (x_i - mean_i) / scale_i)))
//
// and the detection stands when p >= min_probability. The weights are fitted offline on the
// TUNING half of `sarmap-log kws-eval` (--fit-verifier) and written to config/speech.yaml;
// README gives the curve (tune | held-out) and its limits (what the features learn).

#include <string>
#include <vector>

#include "common/options.h"
#include "speech/hit_features.h"

namespace sarmap {
namespace speech {

struct VerifierOptions {
  bool enabled = false;
  std::vector<std::string> features{"tilt_db"};  // names: see FeatureValue()
  std::vector<double> means{0.0};
  std::vector<double> scales{1.0};
  std::vector<double> weights{0.0};
  double bias = 0.0;
  double min_probability = 0.5;
  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "drop keyword detections whose verifier probability is below min_probability");
    v("features", features, "hit features (hit_features.h): duration_s ratio_per_s hit_level_db voiced_fraction "
      "pitch_hz pitch_range_st tilt_db phone_distance lead_s trail_s snr_db log_ratio utterance_s");
    v("means", means, "per feature: mean subtracted before the weight");
    v("scales", scales, "per feature: scale divided before the weight");
    v("weights", weights, "per feature: logistic-regression weight");
    v("bias", bias, "logistic-regression bias");
    v("min_probability", min_probability, "detections below this verifier probability are dropped",
      InRange(0, 1));
  }
  void Validate(common::Validator& check) const;
};

// Value of the named feature; throws std::invalid_argument for an unknown name.
double FeatureValue(const HitFeatures& f, const std::string& name);
bool IsKnownFeature(const std::string& name);
// Whether a feature needs the phone loop (phone_distance).
bool NeedsPhoneLoop(const VerifierOptions& options);

class KeywordVerifier {
 public:
  explicit KeywordVerifier(const VerifierOptions& options) : options_(options) {}
  double Probability(const HitFeatures& f) const;
  bool Accept(const HitFeatures& f) const { return !options_.enabled || Probability(f) >= options_.min_probability; }
  const VerifierOptions& options() const { return options_; }

 private:
  VerifierOptions options_;
};

// Fits the logistic regression (Newton's method, L2 penalty `l2` on the standardised weights,
// classes weighted equally). labels: 1 = a call, 0 = other speech. Means and scales are the
// training features' mean and standard deviation. The result has enabled = true and
// min_probability 0.5 (choose the operating point afterwards).
VerifierOptions FitKeywordVerifier(const std::vector<HitFeatures>& hits, const std::vector<int>& labels,
                                   const std::vector<std::string>& features, double l2 = 0.01);

}  // namespace speech
}  // namespace sarmap
