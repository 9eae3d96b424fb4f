#include "sound_map/data_association.h"

#include <cmath>
#include <limits>

namespace sarmap {
namespace sound_map {

double SourceAssociator::CosineDistance(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || a.size() != b.size()) return std::numeric_limits<double>::quiet_NaN();
  double ab = 0, aa = 0, bb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ab += a[i] * b[i];
    aa += a[i] * a[i];
    bb += b[i] * b[i];
  }
  if (aa <= 0 || bb <= 0) return std::numeric_limits<double>::quiet_NaN();
  return 1.0 - ab / std::sqrt(aa * bb);
}

SourceAssociator::Decision SourceAssociator::Associate(const std::string& device, int64_t track_id,
                                                       const std::vector<double>& signature,
                                                       const std::vector<int64_t>& sources,
                                                       const std::function<double(int64_t)>& chi2) const {
  Decision d;
  if (track_id >= 0) {
    auto it = track_to_source_.find({device, track_id});
    if (it != track_to_source_.end()) {
      d.source = it->second;
      d.by_track = true;
      return d;
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (int64_t s : sources) {
    const double c = chi2(s);
    if (!(c <= options_.gate_chi2)) continue;
    auto sig = signatures_.find(s);
    double score = c;
    if (!signature.empty() && sig != signatures_.end() && !sig->second.mean.empty()) {
      const double dist = CosineDistance(signature, sig->second.mean);
      if (std::isfinite(dist) && dist > options_.max_signature_distance) continue;  // a different voice
      if (std::isfinite(dist)) score += options_.gate_chi2 * dist / options_.max_signature_distance;
    }
    if (score < best) {
      best = score;
      d.source = s;
    }
  }
  d.reassociated = d.source >= 0;
  return d;
}

void SourceAssociator::Commit(const std::string& device, int64_t track_id, int64_t source,
                              const std::vector<double>& signature) {
  if (track_id >= 0) track_to_source_[{device, track_id}] = source;
  if (signature.empty()) return;
  Signature& s = signatures_[source];
  if (s.mean.size() != signature.size()) {
    s.mean = signature;
    s.count = 1;
    return;
  }
  ++s.count;
  for (size_t i = 0; i < signature.size(); ++i) s.mean[i] += (signature[i] - s.mean[i]) / s.count;
}

int64_t SourceAssociator::SourceOfTrack(const std::string& device, int64_t track_id) const {
  auto it = track_to_source_.find({device, track_id});
  return it == track_to_source_.end() ? -1 : it->second;
}

}  // namespace sound_map
}  // namespace sarmap
