#pragma once
// Multi-source DOA tracker: births, deaths, persistence through short silences, stable ids.
//
// Each track is a Kalman filter on (azimuth, elevation) (1-D: angle to the axis) and, with
// velocity_noise_deg_per_s_sqrt_s > 0, their rates: a constant-velocity model whose rate decays
// towards 0 with velocity_time_constant_s (a talker who stops talking is not carried away).
// Prediction adds the position random walk q^2 dt and the rate's noise; a measurement z with
// covariance R updates x += K (z - Hx), K = P H^T S^-1, S = H P H^T + R (angle differences
// wrapped). Association is greedy, smallest Mahalanobis distance first, within the gate
// d^2 = v^T S^-1 v < chi2_2(gate_probability) and gate_deg. With the rates, two talkers whose
// bearings cross keep their tracks: each track's prediction goes on past the other's.
// An unassociated measurement starts a tentative track; it is confirmed (and gets the next id)
// after `birth_hits` hits within `birth_window_s`; a track not updated for `max_silence_s`
// dies.

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
  double velocity_noise_deg_per_s_sqrt_s = 0.0;  // 0: random walk only
  double velocity_time_constant_s = 1.0;
  double gate_probability = 0.0;  // 0: angular gate only
  // A reflection is always weaker than its direct sound, so it is never its block's strongest
  // direction: a track is confirmed only after this many hits as the strongest (0: any hits).
  int primary_hits = 0;
  template <class V>
  void Visit(V& v) {
    v("gate_deg", gate_deg, "a measurement further than this from a track starts a new one",
      Positive());
    v("birth_hits", birth_hits, "hits needed to confirm a track (and give it an id)", AtLeast(1));
    v("birth_window_s", birth_window_s, "tentative tracks not confirmed within this die",
      Positive());
    v("max_silence_s", max_silence_s, "a track survives silences up to this long", Positive());
    v("process_noise_deg_per_sqrt_s", process_noise_deg_per_sqrt_s, "random-walk process noise",
      NonNegative());
    v("velocity_noise_deg_per_s_sqrt_s", velocity_noise_deg_per_s_sqrt_s,
      "constant-velocity model: noise of the bearing rate (0: random walk only)", NonNegative());
    v("velocity_time_constant_s", velocity_time_constant_s,
      "the bearing rate decays to 0 with this time constant", Positive());
    v("primary_hits", primary_hits,
      "hits as its block's strongest direction needed to confirm a track", AtLeast(0));
    v("gate_probability", gate_probability,
      "also gate by Mahalanobis distance: a track's own measurement falls inside with this "
      "probability (0: off)");
  }
  void Validate(common::Validator& check) const {
    check.That(gate_probability >= 0 && gate_probability < 1, "gate_probability",
               "must be in [0, 1)");
  }
};

struct TrackMeasurement {
  Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity() * 0.003;
  double power = 0, confidence = 0;
  bool primary = true;  // the strongest direction of its block
};

struct Track {
  int64_t id = -1;  // -1 while tentative
  Direction direction;
  Eigen::Matrix2d covariance;                                  // of direction (rad^2)
  Eigen::Vector2d rate = Eigen::Vector2d::Zero();              // rad/s (constant-velocity model)
  Eigen::Matrix4d state_covariance = Eigen::Matrix4d::Zero();  // (az, el, az rate, el rate)
  double birth_s = 0, last_update_s = 0;
  int hits = 0;
  int primary_hits = 0;  // hits as its block's strongest direction
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
