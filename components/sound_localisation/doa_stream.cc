#include "sound_localisation/doa_stream.h"

#include <cmath>

#include "common/time.h"

namespace sarmap {
namespace sound {

int8_t MethodCode(const std::string& m) {
  if (m == "gcc_phat") return sarmap::doa_source_t::METHOD_GCC_PHAT;
  if (m == "music") return sarmap::doa_source_t::METHOD_MUSIC;
  if (m == "gevd_music") return sarmap::doa_source_t::METHOD_GEVD_MUSIC;
  if (m == "esprit") return sarmap::doa_source_t::METHOD_ESPRIT;
  return sarmap::doa_source_t::METHOD_SRP_PHAT;
}

DoaStream::DoaStream(const SoundLocalisationOptions& options, const common::MicArrayOptions& array,
                     const std::string& array_dir)
    : options_(options), device_(options.device_id) {
  geometry_ = ArrayGeometry::FromOptions(array);
  localiser_ = std::make_unique<Localiser>(geometry_, options.localiser,
                                           SensorModel::FromArray(array, array_dir));
  if (!options.map_doa_channel.empty())
    map_localiser_ = std::make_unique<Localiser>(geometry_, options.map_localiser,
                                                 SensorModel::FromArray(array, array_dir));
  if (options.classify)
    classifier_ =
        std::make_unique<DirectionalClassifier>(geometry_, localiser_->kind(), options.classes);
}

void DoaStream::SkipSamples(int64_t samples) {
  localiser_->SkipSamples(samples);
  if (map_localiser_) map_localiser_->SkipSamples(samples);
  if (classifier_) classifier_->SkipSamples(samples);
}

void DoaStream::ResetStream() {
  localiser_->ResetStream();
  if (map_localiser_) map_localiser_->ResetStream();
  if (classifier_) classifier_->ResetStream();
}

void DoaStream::Push(const int16_t* data, int frames, int block_channels, int64_t utime,
                     std::vector<sarmap::doa_t>* doa, std::vector<sarmap::doa_t>* map_doa) {
  const int64_t before = localiser_->samples_seen();
  outs_.clear();
  localiser_->Push(data, frames, block_channels, &outs_);
  if (map_localiser_) {
    map_outs_.clear();
    map_localiser_->Push(data, frames, block_channels, &map_outs_);
  }
  if (classifier_) classifier_->Push(data, frames, block_channels);
  Messages(outs_, options_.localiser, utime, before, doa);
  if (map_localiser_) Messages(map_outs_, options_.map_localiser, utime, before, map_doa);
}

void DoaStream::PushFloat(const std::vector<std::vector<float>>& mic_channels, size_t count,
                          int64_t base_utime, int64_t base_sample, std::vector<sarmap::doa_t>* doa,
                          std::vector<sarmap::doa_t>* map_doa) {
  outs_.clear();
  localiser_->PushFloat(mic_channels, 0, count, &outs_);
  if (map_localiser_) {
    map_outs_.clear();
    map_localiser_->PushFloat(mic_channels, 0, count, &map_outs_);
  }
  if (classifier_) classifier_->PushFloat(mic_channels, 0, count);
  Messages(outs_, options_.localiser, base_utime, base_sample, doa);
  if (map_localiser_) Messages(map_outs_, options_.map_localiser, base_utime, base_sample, map_doa);
}

void DoaStream::Messages(const std::vector<LocaliserOutput>& stream, const LocaliserOptions& lo,
                         int64_t base_utime, int64_t base_sample, std::vector<sarmap::doa_t>* out) {
  const int8_t method = MethodCode(lo.method);
  const int8_t kind = static_cast<int8_t>(localiser_->kind());
  for (const auto& o : stream) {
    sarmap::doa_t doa;
    doa.header.utime =
        base_utime + common::SecondsToUtime(static_cast<double>(o.centre_sample - base_sample) /
                                            geometry_.sample_rate_hz);
    doa.header.frame = "mic_array";
    doa.device_id = device_;
    struct Entry {
      int64_t id;
      const Direction* direction;
      const Eigen::Matrix2d* covariance;
      double power, confidence;
    };
    std::vector<Entry> entries;
    for (const auto& t : o.tracks)
      if (t.updated) entries.push_back({t.id, &t.direction, &t.covariance, t.power, t.confidence});
    if (options_.publish_untracked)
      for (const auto& d : o.directions) {
        bool in_track = false;
        for (const auto& t : o.tracks)
          in_track |= t.updated && AngularDistanceRad(geometry_, localiser_->kind(), t.direction,
                                                      d.direction) < DegToRad(lo.tracker.gate_deg);
        if (!in_track) entries.push_back({-1, &d.direction, &d.covariance, d.power, d.confidence});
      }
    std::vector<SoundClassEstimate> classes(entries.size());
    if (classifier_ && !entries.empty()) {
      std::vector<Direction> directions;
      for (const auto& e : entries) directions.push_back(*e.direction);
      const int64_t block =
          static_cast<int64_t>(std::llround(lo.block_s * geometry_.sample_rate_hz));
      // The stream the sound map reads marks the class tracks; the other one (the speech
      // beams' DOA) only reads them: its reports of one source near another's direction
      // marked the other's frames as sounding (lab tour: the smoke alarm mapped as a voice).
      const bool marks = map_localiser_ ? &lo == &options_.map_localiser : true;
      classes = marks ? classifier_->Observe(o.end_sample - block, o.end_sample, directions)
                      : classifier_->Lookup(directions);
    }
    for (size_t i = 0; i < entries.size(); ++i) {
      const Entry& e = entries[i];
      sarmap::doa_source_t s{};
      s.track_id = e.id;
      s.kind = kind;
      s.azimuth_rad = e.direction->azimuth_rad;
      s.elevation_rad = e.direction->elevation_rad;
      for (int j = 0; j < 4; ++j) s.covariance[j] = (*e.covariance)(j / 2, j % 2);
      s.power = static_cast<float>(e.power);
      s.confidence = static_cast<float>(e.confidence);
      s.method = method;
      s.sound_class = static_cast<int8_t>(classes[i].sound_class);
      s.class_confidence = static_cast<float>(classes[i].confidence);
      doa.sources.push_back(s);
    }
    doa.num_sources = static_cast<int32_t>(doa.sources.size());
    out->push_back(doa);
  }
}

}  // namespace sound
}  // namespace sarmap
