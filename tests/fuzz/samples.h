#pragma once
// Valid encodings of every message type for tests and fuzzers: random samples
// (sarmap/message_samples.h) and sane ones, which also pass CheckMessage() and so reach a
// node's handler rather than its drop counter.

#include <cstdint>
#include <random>
#include <vector>

#include "common/message_checks.h"
#include "sarmap/message_samples.h"

namespace sarmap {
namespace testing {

using Bytes = std::vector<uint8_t>;

template <class T>
Bytes Encode(const T& m) {
  Bytes buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Fixes for the fields that a random sample gets wrong for CheckMessage(): positive header
// fields, known enums, consistent counts, unit quaternions, probabilities in [0, 1].
inline void SaneHeader(sarmap::header_t* h) {
  h->utime = h->utime < 0 ? -(h->utime + 1) : h->utime;
  h->seq = h->seq < 0 ? -(h->seq + 1) : h->seq;
}
inline void UnitQuaternion(double (&q)[4]) {
  q[0] = 1;
  q[1] = q[2] = q[3] = 0;
}
template <class T>
void SaneUp(T* m) {
  SaneHeader(&m->header);
}
inline void SaneUp(sarmap::audio_frame_t* m) {
  SaneHeader(&m->header);
  m->num_channels = 2;
  m->sample_rate_hz = 16000;
  m->sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
  m->first_sample_index = 10;
  m->overrun_samples = 0;
  m->num_samples = 3;
  m->num_values = 6;
  m->samples.assign(6, 7);
}
inline void SaneUp(sarmap::image_t* m) {
  SaneHeader(&m->header);
  m->width = 2;
  m->height = 2;
  m->pixel_format = sarmap::image_t::PIXEL_DEPTH_U16;
  m->depth_unit_m = 0.001;
  m->compression = sarmap::image_t::COMPRESSION_NONE;
  m->size = 8;
  m->data.assign(8, 1);
}
inline void SaneUp(sarmap::laser_scan_t* m) {
  SaneHeader(&m->header);
  m->angle_increment_rad = 0.01;
  m->range_min_m = 0.1f;
  m->range_max_m = 10.f;
  m->num_intensities = 0;
  m->intensities.clear();
}
inline void SaneUp(sarmap::pose_t* m) {
  SaneHeader(&m->header);
  UnitQuaternion(m->orientation);
}
inline void SaneUp(sarmap::odometry_t* m) {
  SaneHeader(&m->header);
  UnitQuaternion(m->orientation);
}
inline void SaneUp(sarmap::sim_truth_t* m) {
  SaneHeader(&m->header);
  UnitQuaternion(m->robot_orientation);
}
inline void SaneUp(sarmap::occupancy_grid_t* m) {
  SaneHeader(&m->header);
  m->resolution_m = 0.05;
  m->width = 2;
  m->height = 3;
  m->compression = sarmap::occupancy_grid_t::COMPRESSION_NONE;
  m->size = 6;
  m->data.assign(6, 0);
}
inline void SaneUp(sarmap::slam_anchors_t* m) {
  SaneHeader(&m->header);
  m->covariance_dim = 3 * (1 + m->num_anchors);
  m->covariance.assign(m->covariance_dim, std::vector<double>(m->covariance_dim, 0.5));
}
inline void SaneUp(sarmap::slam_anchor_request_t* m) {
  SaneHeader(&m->header);
  m->client_id = "sound-map";
}
inline void SaneUp(sarmap::doa_t* m) {
  SaneHeader(&m->header);
  for (auto& s : m->sources) {
    s.kind = sarmap::doa_source_t::KIND_AZIMUTH;
    s.method = sarmap::doa_source_t::METHOD_SRP_PHAT;
    s.confidence = 0.5f;
  }
}
inline void SaneUp(sarmap::speech_event_t* m) {
  SaneHeader(&m->header);
  m->confidence = 0.7f;
  m->start_utime = 1;
  m->end_utime = 2;
}
inline void SaneUp(sarmap::people_detections_t* m) {
  SaneHeader(&m->header);
  for (auto& d : m->detections) {
    d.cue = sarmap::person_detection_t::CUE_HEARD;
    d.confidence = 0.5f;
  }
}
inline void SaneUp(sarmap::people_map_t* m) {
  SaneHeader(&m->header);
  for (auto& p : m->people) {
    p.confidence = 0.5f;
    p.num_detections = 1;
  }
}
inline void SaneUp(sarmap::sound_map_t* m) {
  SaneHeader(&m->header);
  for (auto& s : m->sources) s.state = sarmap::sound_source_t::STATE_CONVERGED;
}
inline void SaneUp(sarmap::pm_orders_t* m) {
  SaneHeader(&m->header);
  m->counter = 5;
  for (auto& c : m->commands) {
    c.command_id = "cmd";
    c.stop_signal = 2;
    c.stop_time_allowed_s = 1.0;
  }
}

// A random sample of message type T made sane; false when none of `attempts` draws passes
// CheckMessage().
template <class T, class Rng>
bool SaneSample(Rng& rng, T* out, int attempts = 2000) {
  for (int i = 0; i < attempts; ++i) {
    T m;
    sarmap::samples::Fill(m, rng);
    SaneUp(&m);
    if (common::CheckMessage(m).empty()) {
      *out = std::move(m);
      return true;
    }
  }
  return false;
}

// Encodings of `random` random samples of T (seeds 1..random).
template <class T>
std::vector<Bytes> RandomEncodings(int random) {
  std::vector<Bytes> out;
  for (int seed = 1; seed <= random; ++seed) {
    std::mt19937_64 rng(static_cast<uint64_t>(seed));
    T m;
    sarmap::samples::Fill(m, rng);
    out.push_back(Encode(m));
  }
  return out;
}

}  // namespace testing
}  // namespace sarmap
