#include "speech/keyword_verifier.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace sarmap {
namespace speech {

namespace {
const char* const kFeatureNames[] = {"log_ratio", "duration_s", "ratio_per_s", "utterance_s",
                                     "lead_s", "trail_s", "snr_db", "hit_level_db", "voiced_fraction",
                                     "pitch_hz", "pitch_range_st", "tilt_db", "phone_distance"};
}

bool IsKnownFeature(const std::string& name) {
  for (const char* n : kFeatureNames)
    if (name == n) return true;
  return false;
}

double FeatureValue(const HitFeatures& f, const std::string& name) {
  if (name == "log_ratio") return f.log_ratio;
  if (name == "duration_s") return f.duration_s;
  if (name == "ratio_per_s") return f.ratio_per_s;
  if (name == "utterance_s") return f.utterance_s;
  if (name == "lead_s") return f.lead_s;
  if (name == "trail_s") return f.trail_s;
  if (name == "snr_db") return f.snr_db;
  if (name == "hit_level_db") return f.hit_level_db;
  if (name == "voiced_fraction") return f.voiced_fraction;
  if (name == "pitch_hz") return f.pitch_hz;
  if (name == "pitch_range_st") return f.pitch_range_st;
  if (name == "tilt_db") return f.tilt_db;
  if (name == "phone_distance") return f.phone_distance;
  throw std::invalid_argument("unknown keyword-verifier feature: " + name);
}

bool NeedsPhoneLoop(const VerifierOptions& o) {
  for (const auto& n : o.features)
    if (n == "phone_distance") return true;
  return false;
}

void VerifierOptions::Validate(common::Validator& check) const {
  check.That(!features.empty(), "features", "needs at least one feature");
  for (const auto& n : features) check.That(IsKnownFeature(n), "features", "unknown feature '" + n + "'");
  check.That(means.size() == features.size() && scales.size() == features.size() &&
                 weights.size() == features.size(),
             "weights", "means, scales and weights need one value per feature");
  for (double s : scales) check.That(s > 0, "scales", "must be > 0");
}

double KeywordVerifier::Probability(const HitFeatures& f) const {
  double z = options_.bias;
  for (size_t i = 0; i < options_.features.size(); ++i)
    z += options_.weights[i] * (FeatureValue(f, options_.features[i]) - options_.means[i]) / options_.scales[i];
  return 1.0 / (1.0 + std::exp(-z));
}

VerifierOptions FitKeywordVerifier(const std::vector<HitFeatures>& hits, const std::vector<int>& labels,
                                   const std::vector<std::string>& features, double l2) {
  if (hits.size() != labels.size() || hits.empty()) throw std::invalid_argument("FitKeywordVerifier: bad data");
  const int n = static_cast<int>(hits.size()), d = static_cast<int>(features.size());
  Eigen::MatrixXd x(n, d + 1);
  Eigen::VectorXd y(n), c(n);
  int positives = 0;
  for (int i = 0; i < n; ++i) positives += labels[i] != 0;
  if (positives == 0 || positives == n) throw std::invalid_argument("FitKeywordVerifier: needs both classes");
  VerifierOptions o;
  o.enabled = true;
  o.features = features;
  o.means.assign(d, 0.0);
  o.scales.assign(d, 1.0);
  for (int j = 0; j < d; ++j) {
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
      const double v = FeatureValue(hits[i], features[j]);
      s += v;
      s2 += v * v;
    }
    o.means[j] = s / n;
    o.scales[j] = std::max(1e-6, std::sqrt(std::max(0.0, s2 / n - o.means[j] * o.means[j])));
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < d; ++j) x(i, j) = (FeatureValue(hits[i], features[j]) - o.means[j]) / o.scales[j];
    x(i, d) = 1.0;
    y(i) = labels[i] != 0;
    c(i) = labels[i] != 0 ? 0.5 / positives : 0.5 / (n - positives);  // both classes weigh the same
  }
  // Newton / IRLS: minimise sum_i c_i * logloss_i + l2/2 |w|^2 (bias not penalised).
  Eigen::VectorXd w = Eigen::VectorXd::Zero(d + 1);
  Eigen::MatrixXd penalty = Eigen::MatrixXd::Identity(d + 1, d + 1) * l2;
  penalty(d, d) = 0;
  for (int it = 0; it < 50; ++it) {
    const Eigen::VectorXd p = (1.0 + (-(x * w)).array().exp()).inverse().matrix();
    const Eigen::VectorXd g = x.transpose() * (c.array() * (p - y).array()).matrix() + penalty * w;
    const Eigen::VectorXd h_diag = c.array() * p.array() * (1.0 - p.array());
    const Eigen::MatrixXd h = x.transpose() * h_diag.asDiagonal() * x + penalty +
                              1e-9 * Eigen::MatrixXd::Identity(d + 1, d + 1);
    const Eigen::VectorXd step = h.ldlt().solve(g);
    w -= step;
    if (step.norm() < 1e-9) break;
  }
  o.weights.assign(w.data(), w.data() + d);
  o.bias = w(d);
  return o;
}

}  // namespace speech
}  // namespace sarmap
