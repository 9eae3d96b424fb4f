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

void SourceAssociator::Save(common::BinaryWriter* w) const {
  w->Pod<int64_t>(static_cast<int64_t>(track_to_source_.size()));
  for (const auto& [key, source] : track_to_source_) {
    w->String(key.first);
    w->Pod<int64_t>(key.second), w->Pod<int64_t>(source);
  }
  w->Pod<int64_t>(static_cast<int64_t>(signatures_.size()));
  for (const auto& [source, sig] : signatures_) {
    w->Pod<int64_t>(source), w->Pod<int32_t>(sig.count);
    w->Matrix(Eigen::Map<const Eigen::VectorXd>(sig.mean.data(),
                                                static_cast<Eigen::Index>(sig.mean.size())));
  }
}

void SourceAssociator::Load(common::BinaryReader* r) {
  std::map<std::pair<std::string, int64_t>, int64_t> tracks;
  const int64_t num_tracks = r->Count(10000000);
  for (int64_t k = 0; k < num_tracks; ++k) {
    std::string device = r->String();
    const int64_t track = r->Pod<int64_t>();
    tracks[{std::move(device), track}] = r->Pod<int64_t>();
  }
  std::map<int64_t, Signature> signatures;
  const int64_t num_signatures = r->Count(10000000);
  for (int64_t k = 0; k < num_signatures; ++k) {
    const int64_t source = r->Pod<int64_t>();
    Signature& sig = signatures[source];
    sig.count = r->Pod<int32_t>();
    const Eigen::MatrixXd mean = r->Matrix(1 << 16);
    if (mean.cols() > 1) r->Corrupt("signature shape");
    sig.mean.assign(mean.data(), mean.data() + mean.size());
  }
  track_to_source_ = std::move(tracks);
  signatures_ = std::move(signatures);
}

}  // namespace sound_map
}  // namespace sarmap
