#pragma once
// Offline DOA accuracy on a labelled multichannel recording: runs the streaming localiser
// over the file and compares every block's strongest direction (and a whole-file estimate)
// with the true direction; and a multi-talker scorer (detection, tracks, latency, CPU).

#include <cstdint>
#include <string>
#include <vector>

#include "sound_localisation/localiser.h"

namespace sarmap {
namespace sound {

struct DoaFileResult {
  std::string file, method;
  int blocks = 0;  // blocks with an estimate
  double median_azimuth_error_deg = NAN, median_elevation_error_deg = NAN;
  double mean_azimuth_error_deg = NAN;
  double whole_azimuth_deg = NAN, whole_elevation_deg = NAN;  // one estimate from all active frames
  std::vector<Direction> block_estimates;
};

// truth: azimuth/elevation (1-D arrays: angle to the axis in azimuth_rad).
DoaFileResult EvaluateDoaFile(const std::string& path, const ArrayGeometry& geometry,
                              const LocaliserOptions& options, const Direction& truth);
double Median(std::vector<double> v);

// ---------------------------------------------------------------- multi-talker scoring
//
// One scorer for real recordings and simulated scenes. The localiser runs over the scene as a
// stream; every output (one per block, its window block_s * window_blocks long) is scored
// against the talkers whose speech fills at least half of that window:
//   found    a direction of the block (tracked or not) within found_deg of the talker;
//   covered  a confirmed track (alive after the block) within found_deg;
//   tracked  a confirmed track updated in the block within found_deg (what the DOA stream
//            carries with a track id);
//   spurious a confirmed track whose median distance to the nearest talker over its updates
//            exceeds spurious_deg;
//   onset    from a talker's first speech frame to the first output with a confirmed track
//            within onset_deg.
// A talker's speech frames (hop_size frames) are those whose energy in its own signal is
// 10 dB above the signal's 10th-percentile frame energy and within 30 dB of its loudest frame.

struct SceneTalker {
  Direction direction;
  std::vector<float> signal;  // the talker alone (a real one-talker recording: a microphone)
};

struct Scene {
  std::string name;
  std::vector<std::vector<float>> mics;  // array channel order
  std::vector<SceneTalker> talkers;
};

struct ScoreOptions {
  double found_deg = 5.0;
  double spurious_deg = 10.0;
  double onset_deg = 10.0;
};

struct SceneScore {
  std::string name;
  int talkers = 0;
  int speech_pairs = 0;  // (output, talker) with the talker speaking
  int found = 0, covered = 0, tracked = 0;
  int confirmed_tracks = 0, spurious_tracks = 0;
  std::vector<double> onset_latency_s;  // per talker; NAN when never tracked
  double cpu_s = 0, audio_s = 0;
  double median_elevation_error_deg = NAN;     // of the found directions
  std::vector<Direction> spurious_directions;  // median direction of each spurious track
};

// The localiser (built here from options) over the scene; CPU time is the thread's.
SceneScore ScoreScene(const Scene& scene, const ArrayGeometry& geometry,
                      const LocaliserOptions& options, const ScoreOptions& score = ScoreOptions());
// A labelled multichannel recording of one talker; channels through the array's channel_map.
Scene LoadRecordedScene(const std::string& path, const ArrayGeometry& geometry,
                        const Direction& truth);
// Talkers (real speech, each its own signal) at distance_m from the array centre in a shoebox
// room (room_simulation.h), directions in the array frame, white sensor noise noise_std.
Scene SimulateTalkerScene(const std::string& name, const ArrayGeometry& geometry,
                          const std::vector<std::vector<float>>& talker_signals,
                          const std::vector<Direction>& directions, double distance_m,
                          double rt60_s, double noise_std, uint32_t seed);
// The simulated benchmark: num_talkers talkers (2 or 3) in each of several rooms, speech from
// the CMU ARCTIC files in speech_dir (staggered starts, overlapping). Empty if the files are
// absent.
std::vector<Scene> SimulatedBenchmarkScenes(const ArrayGeometry& geometry,
                                            const std::string& speech_dir, int num_talkers);

}  // namespace sound
}  // namespace sarmap
