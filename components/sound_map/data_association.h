#pragma once
// Data association of DOA observations to mapped sources:
//   1. a DOA track id already tied to a source keeps its source;
//   2. an unknown track (a new track, or a source that fell silent and speaks again) is
//      compared with every source by the chi-square of its bearing against the source's
//      prediction (gate) and, when both carry one, by the cosine distance of their spectral
//      signatures (e.g. mean MFCC vectors); the best source passing both gates takes it;
//   3. otherwise it starts a new source.
// Signatures are running means over the observations associated to a source.

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/binary_io.h"

namespace sarmap {
namespace sound_map {

class SourceAssociator {
 public:
  struct Options {
    double gate_chi2 = 6.63;              // 99 % for one angle
    double max_signature_distance = 0.2;  // cosine distance 1 - cos
  };
  explicit SourceAssociator(const Options& options) : options_(options) {}

  struct Decision {
    int64_t source = -1;  // -1: start a new source
    bool by_track = false;
    bool reassociated = false;  // an unknown track joined an existing source
  };
  // chi2(source): the observation's chi-square against that source (infinite if unusable).
  Decision Associate(const std::string& device, int64_t track_id, const std::vector<double>& signature,
                     const std::vector<int64_t>& sources, const std::function<double(int64_t)>& chi2) const;
  // Records the outcome (track -> source, signature running mean).
  void Commit(const std::string& device, int64_t track_id, int64_t source, const std::vector<double>& signature);
  // Sources a track was tied to (for PEOPLE_AUDIO, which names DOA track ids).
  int64_t SourceOfTrack(const std::string& device, int64_t track_id) const;
  static double CosineDistance(const std::vector<double>& a, const std::vector<double>& b);
  // What it has learnt (tracks, signatures), for a restart from a state file.
  void Save(common::BinaryWriter* w) const;
  void Load(common::BinaryReader* r);

 private:
  Options options_;
  std::map<std::pair<std::string, int64_t>, int64_t> track_to_source_;
  struct Signature {
    std::vector<double> mean;
    int count = 0;
  };
  std::map<int64_t, Signature> signatures_;
};

}  // namespace sound_map
}  // namespace sarmap
