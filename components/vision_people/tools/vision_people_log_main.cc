// sarmap-log-vision-people: runs sarmap-vision-people's adapter (VisionPeopleNode: frame
// pairing, detector, k-of-n confirmation) over a log's DEPTH and RGB on the log's clock
// (logtools::NodeReplay), as fast as the CPU allows. When
// the log holds SIM_TRUTH it scores every detection against the simulated people (where the
// camera truly was) and lists the false ones with the features that let them through.
//
//   sarmap-log vision-people run.lcmlog [--config config/vision_people.yaml] [--set ...]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/decode.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/node_replay.h"
#include "sarmap/sim_truth_t.hpp"
#include "vision_people/vision_people_node.h"

namespace {

using namespace sarmap;
using namespace sarmap::vision_people;

struct TruthSample {
  Eigen::Isometry3d map_from_base = Eigen::Isometry3d::Identity();
  std::vector<sim_person_t> people;
};

Eigen::Isometry3d BaseFromTruth(const sim_truth_t& m) {
  return common::ToRigid3d(m.robot_position_m, m.robot_orientation).ToIsometry();
}

// map_from_base at `utime`, interpolated between the two truth samples around it (the
// simulator publishes truth at 10 Hz, the camera runs at 30 Hz). False outside the truth.
bool TruthAt(const std::map<int64_t, TruthSample>& truth, int64_t utime, Eigen::Isometry3d* pose,
             const TruthSample** nearest) {
  if (truth.empty()) return false;
  auto after = truth.lower_bound(utime);
  if (after == truth.end() || (after == truth.begin() && after->first != utime)) return false;
  if (after->first == utime || after == truth.begin()) {
    *pose = after->second.map_from_base;
    *nearest = &after->second;
    return true;
  }
  const auto before = std::prev(after);
  const double s = static_cast<double>(utime - before->first) /
                   static_cast<double>(after->first - before->first);
  const Eigen::Isometry3d& a = before->second.map_from_base;
  const Eigen::Isometry3d& b = after->second.map_from_base;
  *pose = Eigen::Isometry3d::Identity();
  pose->linear() =
      Eigen::Quaterniond(a.linear()).slerp(s, Eigen::Quaterniond(b.linear())).toRotationMatrix();
  pose->translation() = (1 - s) * a.translation() + s * b.translation();
  *nearest = s < 0.5 ? &before->second : &after->second;
  return true;
}

const char* Kind(const PersonCandidate& c) {
  if (c.lying) return "lying";
  if (c.hog_used) return "rgbd";
  return "depth";
}

struct Score {
  int64_t true_positive = 0, false_positive = 0;
};

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-vision-people", [&] {
    common::ArgParser parser(
        "sarmap-log-vision-people",
        "Runs sarmap-vision-people (its adapter: frame pairing, detector and k-of-n\n"
        "confirmation, on the log's clock) over a log's DEPTH and RGB frames. With SIM_TRUTH in "
        "the log, each\n"
        "detection is scored against the simulated people: a detection within --match-m of a\n"
        "person (on the floor plane, where the camera truly was) is true, any other is false;\n"
        "false ones are listed with their features (--list-false N).");
    common::NodeArgs node_args;
    std::string log_path, truth_channel = "SIM_TRUTH";
    double match_m = 0.6;
    int list_false = 20;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddFlag("--truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag("--match-m", &match_m,
                   "a detection this close to a simulated person (floor plane) is true");
    parser.AddFlag("--list-false", &list_false, "list at most this many false detections");
    const auto parsed = common::ParseNodeOptions<VisionPeopleOptions>(
        &parser, &node_args, argc, argv, "config/vision_people.yaml");
    if (!parsed) return 0;
    const VisionPeopleOptions& options = *parsed;
    const Eigen::Isometry3d base_from_camera =
        common::LoadRobot(options.robot_config).base_from_camera.ToRigid3d().ToIsometry();

    // The truth first (a small part of the log), so frames can be placed between samples.
    std::map<int64_t, TruthSample> truth;
    {
      logtools::LcmLogReader reader(log_path);
      logtools::LogEvent e;
      while (reader.Next(&e)) {
        if (e.channel != truth_channel) continue;
        sim_truth_t m;
        if (!common::DecodeMessage(e.data.data(), e.data.size(), &m)) continue;
        truth[m.header.utime] = TruthSample{BaseFromTruth(m), m.people};
      }
    }

    std::map<std::string, Score> raw, confirmed;
    std::map<std::string, int64_t> false_by_place;  // "kind x y" (0.5 m cells) -> count
    int64_t frames = 0, scored_frames = 0, listed = 0;

    auto score = [&](const PersonCandidate& c, const Eigen::Isometry3d& map_from_camera,
                     const TruthSample& sample, int64_t utime, bool is_confirmed) {
      const Eigen::Vector3d p = map_from_camera * c.position_camera;
      double best = 1e9;
      for (const auto& person : sample.people)
        best =
            std::min(best, std::hypot(p.x() - person.position_m[0], p.y() - person.position_m[1]));
      const bool is_true = best <= match_m;
      Score& s = (is_confirmed ? confirmed : raw)[Kind(c)];
      (is_true ? s.true_positive : s.false_positive) += 1;
      if (is_true || !is_confirmed) return;
      char place[96];
      snprintf(place, sizeof(place), "%-5s near (%5.1f, %5.1f)", Kind(c), std::round(p.x() * 2) / 2,
               std::round(p.y() * 2) / 2);
      ++false_by_place[place];
      if (listed++ >= list_false) return;
      printf(
          "false %s t=%.2f s map (%.2f, %.2f) range %.2f m: height %.2f bottom %.2f width %.2f "
          "depth %.2f head_w %.2f shoulder_w %.2f prominence %.2f fill %.2f visible %.2f "
          "length %.2f relief %.2f depth_score %.2f hog %.2f conf %.2f supported %d box u %.0f v "
          "%.0f..%.0f\n",
          Kind(c), utime * 1e-6, p.x(), p.y(), c.position_camera.norm(), c.height_m, c.bottom_m,
          c.width_m, c.depth_extent_m, c.head_width_m, c.shoulder_width_m, c.head_prominence_m,
          c.fill, c.visible_fraction, c.length_m, c.relief_m, c.depth_score, c.hog_score,
          c.confidence, c.supported, c.box_u_center, c.box_v_top, c.box_v_bottom);
    };

    // sarmap-vision-people's adapter on the log's clock: its stamp gates, frame pairing,
    // detector and confirmation, each frame scored as it is processed.
    common::Node node("sarmap-log-vision-people", logtools::ReplayNodeArgs(node_args));
    VisionPeopleNode vision(options, &node);
    vision.set_frame_observer([&](const RgbdFrame& frame, const DetectionResult& result,
                                  const std::vector<ConfirmedPerson>& accepted) {
      ++frames;
      Eigen::Isometry3d map_from_base;
      const TruthSample* sample = nullptr;
      if (!TruthAt(truth, frame.utime, &map_from_base, &sample)) return;
      ++scored_frames;
      const Eigen::Isometry3d map_from_camera = map_from_base * base_from_camera;
      for (const auto& c : result.people) score(c, map_from_camera, *sample, frame.utime, false);
      for (const auto& c : accepted) score(c.person, map_from_camera, *sample, frame.utime, true);
    });
    logtools::NodeReplay replay(&node);
    const auto start = std::chrono::steady_clock::now();
    const auto stats = replay.Run(log_path, [&](logtools::LogEvent* e) {
      return e->channel == options.depth_channel || e->channel == options.rgb_channel;
    });
    vision.Finish();
    replay.Drain();
    const double elapsed_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (const auto& p : stats.problems)
      fprintf(stderr, "log damaged at byte %ld: %s\n", static_cast<long>(p.file_offset),
              p.what.c_str());

    printf(
        "%ld frames (%ld without a usable image), %.1f ms per frame (reading, decoding, pairing, "
        "detection, confirmation: the node's whole work, this machine, one thread)\n",
        static_cast<long>(frames), static_cast<long>(vision.bad_frames()),
        frames ? elapsed_ms / static_cast<double>(frames) : 0.0);
    for (const auto& [name, n] : vision.pairing_warnings())
      printf("  pairing: %s %ld\n", name.c_str(), static_cast<long>(n));
    if (truth.empty()) {
      printf("no %s in the log: nothing to score against\n", truth_channel.c_str());
      return 0;
    }
    printf("%ld frames within the truth; detections within %.2f m of a person are true\n",
           static_cast<long>(scored_frames), match_m);
    printf("%-10s %-6s %8s %8s %14s\n", "stage", "cue", "true", "false", "false/frame");
    for (const auto* table : {&raw, &confirmed}) {
      for (const auto& [kind, s] : *table)
        printf("%-10s %-6s %8ld %8ld %14.4f\n", table == &raw ? "frame" : "confirmed", kind.c_str(),
               static_cast<long>(s.true_positive), static_cast<long>(s.false_positive),
               scored_frames ? s.false_positive / static_cast<double>(scored_frames) : 0.0);
    }
    if (!false_by_place.empty()) {
      printf("confirmed false detections by place (0.5 m cells, map frame):\n");
      for (const auto& [place, n] : false_by_place)
        printf("  %s: %ld frames\n", place.c_str(), static_cast<long>(n));
    }
    return 0;
  });
}
