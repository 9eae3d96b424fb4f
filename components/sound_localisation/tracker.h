#pragma once
// Multi-source DOA tracker: births, deaths, persistence through short silences, stable ids.
//
// Each track is a random-walk Kalman filter on (azimuth, elevation) (1-D: angle to the
// axis): prediction adds q^2 dt to the variances; a measurement z with covariance R updates
// x += K (z - x), K = P (P + R)^-1 (angle differences wrapped). Association is greedy
// nearest-first within a gate (angular distance). An unassociated measurement starts a
// tentative track; it is confirmed (and gets the next id) after `birth_hits` hits within
// `birth_window_s`; a track not updated for `max_silence_s` dies.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/options.h"
#include "sound_localisation/array_geometry.h"

namespace sarmap {
namespace sound {

struct TrackerOptions {
  double gate_deg = 20.0;
  int birth_hits = 2;
  double birth_window_s = 1.0;
  double max_silence_s = 2.0;
  double process_noise_deg_per_sqrt_s = 10.0;
  template <class V>
  void Visit(V& v) {
    v("gate_deg", gate_deg, "a measurement further than this from a track starts a new one");
    v("birth_hits", birth_hits, "hits needed to confirm a track (and give it an id)");
    v("birth_window_s", birth_window_s, "tentative tracks not confirmed within this die");
    v("max_silence_s", max_silence_s, "a track survives silences up to this long");
    v("process_noise_deg_per_sqrt_s", process_noise_deg_per_sqrt_s, "random-walk process noise");
  }
  void Validate(common::Validator& check) const {
    check.Positive("gate_deg", gate_deg);
    check.That(birth_hits >= 1, "birth_hits", "must be >= 1");
    check.Positive("birth_window_s", birth_window_s);
    check.Positive("max_silence_s", max_silence_s);
    check.NonNegative("process_noise_deg_per_sqrt_s", process_noise_deg_per_sqrt_s);
  }
};

struct TrackMeasurement {
  Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity() * 0.003;
  double power = 0, confidence = 0;
};

struct Track {
  int64_t id = -1;  // -1 while tentative
  Direction direction;
  Eigen::Matrix2d covariance;
  double birth_s = 0, last_update_s = 0;
  int hits = 0;
  bool updated = false;  // in the latest Update()
  double power = 0, confidence = 0;
  bool confirmed() const { return id >= 0; }
};

class DoaTracker {
 public:
  DoaTracker(const ArrayGeometry& geometry, DoaKind kind, TrackerOptions options);
  // Advances to time_s and applies this block's measurements. Returns the confirmed tracks.
  std::vector<Track> Update(double time_s, const std::vector<TrackMeasurement>& measurements);
  const std::vector<Track>& tracks() const { return tracks_; }
  int64_t tracks_created() const { return next_id_; }

 private:
  ArrayGeometry geometry_;
  DoaKind kind_;
  TrackerOptions options_;
  std::vector<Track> tracks_;
  int64_t next_id_ = 0;
  double last_time_s_ = -1;
};

}  // namespace sound
}  // namespace sarmap
