#include "mission/mission_runner.h"

#include <time.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "common/grid_geometry.h"
#include "common/image_messages.h"
#include "common/memory.h"
#include "common/message_conversions.h"
#include "common/robot_config.h"
#include "common/time.h"
#include "depth/depth_node_options.h"
#include "depth/depth_to_scan.h"
#include "explore/explore.h"
#include "explore/explore_messages.h"
#include "explore/explore_node_options.h"
#include "people_map/people_map.h"
#include "people_map/people_map_intake.h"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sim/robot.h"
#include "sim/simulator.h"
#include "slam/messages.h"
#include "slam/slam.h"
#include "slam/slam_node_options.h"
#include "sound_localisation/doa_stream.h"
#include "sound_map/online_sound_map.h"
#include "sound_map/sound_map_intake.h"
#include "sound_map/sound_map_messages.h"
#include "speech/speech_stream.h"
#include "vision_people/confirmation_tracker.h"
#include "vision_people/detections_message.h"
#include "vision_people/frame_assembler.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {
namespace mission {

namespace {

double CpuSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// A path from a configuration file, relative to the repository root when not absolute (the
// nodes read them relative to their working directory, the repository root).
std::string Resolve(const std::string& path, const std::string& repo_root) {
  if (path.empty() || path[0] == '/' || repo_root.empty()) return path;
  return repo_root + "/" + path;
}

// The sound chain in process, as sarmap-sound-localisation, sarmap-speech and sarmap-sound-map
// run it: AUDIO -> DoaStream -> DOA (speech beams) and DOA_MAP (sound map); AUDIO + DOA ->
// SpeechStream -> PEOPLE_AUDIO; DOA_MAP + PEOPLE_AUDIO + POSE + SLAM_ANCHORS + MAP ->
// SoundMapIntake -> SOUND_MAP and SLAM_ANCHOR_REQUEST.
struct SoundChain {
  SoundChain(const sound::SoundLocalisationOptions& localisation,
             const common::MicArrayOptions& array, const std::string& array_dir,
             const speech::SpeechNodeOptions& speech_options,
             const sound_map::SoundMapNodeOptions& map_options, const sound_map::ArrayMount& mount)
      : doa(localisation, array, array_dir),
        speech(speech_options, array),
        map(map_options.map, mount) {}
  sound::DoaStream doa;
  speech::SpeechStream speech;
  sound_map::OnlineSoundMap map;
  std::unique_ptr<sound_map::SoundMapIntake> intake;
  std::vector<sarmap::doa_t> doas, map_doas;
  std::vector<sarmap::speech_event_t> events;
  std::vector<sarmap::people_detections_t> heard;
};

// sarmap-vision-people and sarmap-people-map in process (and the sound chain when given):
// RGB-D frames -> detector -> k-of-n confirmation -> PEOPLE_VISUAL -> the people map's intake,
// which places each detection with SLAM's POSE at its capture time; PEOPLE_MAP goes to the
// observer and, as sarmap-explore reads it, the people heard to the explorer.
class Perception {
 public:
  Perception(const vision_people::VisionPeopleOptions& vision,
             const people_map::PeopleMapNodeOptions& people,
             const common::Rigid3d& base_from_camera, const common::Rigid3d& base_from_mic,
             std::unique_ptr<SoundChain> sound, explore::ExploreController* explorer,
             MissionObserver* observer, MissionResult* result,
             people_map::PeopleMapIntake::Request anchor_request)
      : vision_(vision),
        detector_(vision.detector, vision_people::InitialGround(vision),
                  vision_people::MakeHogClassifier(vision.detector.color)),
        tracker_(vision.confirmation),
        assembler_(vision.max_pair_dt_s, vision.color_wait_s, vision.require_color),
        map_(people.map),
        intake_(
            people, base_from_camera, base_from_mic, &map_,
            [this](common::Utime utime) { Publish(utime); }, std::move(anchor_request)),
        publish_period_s_(people.publish_period_s),
        sound_(std::move(sound)),
        explorer_(explorer),
        observer_(observer),
        result_(result) {}

  void set_start_s(double s) { start_s_ = s; }
  SoundChain* sound() { return sound_.get(); }
  int people_on_map() const { return people_on_map_; }
  int sound_sources() const { return sound_sources_; }
  int64_t detections_without_pose() const { return intake_.without_pose(); }

  void OnPose(const sarmap::pose_t& m) {
    now_s_ = common::UtimeToSeconds(m.header.utime) - start_s_;
    const double cpu0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    intake_.OnPose(m);
    // The node's timer: what is due is applied and PEOPLE_MAP republished every publish_period_s.
    if (now_s_ - last_publish_s_ >= publish_period_s_) {
      intake_.Release();
      if (intake_.latest_utime() > 0) Publish(intake_.latest_utime());
    }
    const double cpu1 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    result_->people_map_cpu_s += cpu1 - cpu0;
    if (sound_) {
      sound_->intake->OnPose(m);
      result_->sound_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpu1;
    }
  }

  void OnImage(const std::string& channel, const sarmap::image_t& m) {
    if (channel != vision_.depth_channel && channel != vision_.rgb_channel) return;
    const double cpu0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    if (channel == vision_.depth_channel)
      assembler_.AddDepth(m, &ready_);
    else
      assembler_.AddColor(m, &ready_);
    std::vector<sarmap::people_detections_t> out;
    for (vision_people::RgbdFrame& frame : ready_) {
      const vision_people::DetectionResult r = detector_.Detect(frame);
      ++result_->vision_frames;
      out.push_back(vision_people::DetectionsMessage(tracker_.Update(r.people), frame.utime,
                                                     vision_.sensor_id));
    }
    ready_.clear();
    const double cpu1 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    result_->vision_cpu_s += cpu1 - cpu0;
    for (const auto& msg : out) intake_.OnSeen(msg);
    result_->people_map_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpu1;
    if (observer_) {
      for (const auto& msg : out)
        if (!msg.detections.empty())
          observer_->OnSeen(common::UtimeToSeconds(msg.header.utime) - start_s_, msg);
    }
  }

  // One audio block: the speech beams take it first (its DOAs come from the localiser after
  // it, as over LCM), then the localiser's DOA steer the beams and DOA_MAP goes to the sound map.
  void OnAudio(const sarmap::audio_frame_t& m) {
    if (!sound_) return;
    SoundChain& s = *sound_;
    const double cpu0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    const std::string device = m.device_id;
    s.doa.set_device(device);
    s.events.clear();
    s.heard.clear();
    s.speech.OnAudio(m.samples.data(), m.num_samples, m.num_channels, m.header.utime, device,
                     &s.events, &s.heard);
    s.doas.clear();
    s.map_doas.clear();
    s.doa.Push(m.samples.data(), m.num_samples, m.num_channels, m.header.utime, &s.doas,
               &s.map_doas);
    std::vector<std::string> warnings;
    for (const auto& d : s.doas) s.speech.OnDoa(d, device, &warnings);
    if (observer_) {
      for (const auto& d : s.doas)
        observer_->OnDoa(common::UtimeToSeconds(d.header.utime) - start_s_, d);
    }
    // The observer sees each input before the sound map's intake takes it: an input can make
    // the intake ask SLAM for anchors, whose answer reaches the intake (and the observer) at
    // once, so a log written by the observer holds the inputs in the order the intake took them.
    // The observer's CPU time is not the sound chain's.
    double observer_cpu_s = 0;
    auto observe = [&](auto show) {
      if (!observer_) return;
      const double c = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
      show();
      observer_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - c;
    };
    for (const auto& d : s.map_doas) {
      observe([&] { observer_->OnDoaMap(common::UtimeToSeconds(d.header.utime) - start_s_, d); });
      s.intake->OnDoa(d);
    }
    for (const auto& h : s.heard) {
      observe([&] { observer_->OnHeard(common::UtimeToSeconds(h.header.utime) - start_s_, h); });
      s.intake->OnHeard(h);
    }
    result_->sound_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpu0 - observer_cpu_s;
    result_->heard_calls += static_cast<int64_t>(s.heard.size());
    const double cpu1 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    for (const auto& h : s.heard) intake_.OnHeard(h);
    result_->people_map_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpu1;
  }

  // SLAM_ANCHORS: to the sound map and the people map.
  void OnAnchors(const sarmap::slam_anchors_t& m) {
    if (sound_) sound_->intake->OnAnchors(m);
    intake_.OnAnchors(m);
  }

  // SOUND_MAP from the sound map's intake.
  void OnSoundMap(const sarmap::sound_map_t& m) {
    sound_sources_ = static_cast<int>(m.sources.size());
    const double cpu0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    intake_.OnSoundMap(m);
    result_->people_map_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpu0;
    if (explorer_) explorer_->OnVoices(explore::VoicesFromMessage(m));
    if (observer_) observer_->OnSoundMap(now_s_, m);
  }

  void Finish() {
    if (sound_) sound_->intake->Finish();
    intake_.Finish();
    if (intake_.latest_utime() > 0) Publish(intake_.latest_utime());
    result_->detections_without_pose = intake_.without_pose();
  }

 private:
  void Publish(common::Utime utime) {
    last_publish_s_ = now_s_;
    const sarmap::people_map_t msg = people_map::PeopleMapMessage(map_.Report(utime), utime);
    people_on_map_ = static_cast<int>(msg.people.size());
    if (explorer_)
      explorer_->OnPeopleMap(explore::HeardPeopleFromMessage(msg),
                             explore::PeoplePositionsFromMessage(msg));
    if (observer_) observer_->OnPeopleMap(now_s_, msg);
  }


  vision_people::VisionPeopleOptions vision_;
  vision_people::PeopleDetector detector_;
  vision_people::ConfirmationTracker tracker_;
  vision_people::FrameAssembler assembler_;
  std::vector<vision_people::RgbdFrame> ready_;
  people_map::PeopleMap map_;
  people_map::PeopleMapIntake intake_;
  double publish_period_s_;
  std::unique_ptr<SoundChain> sound_;
  explore::ExploreController* explorer_;
  MissionObserver* observer_;
  MissionResult* result_;
  double start_s_ = 0, now_s_ = 0, last_publish_s_ = -1e9;
  int people_on_map_ = 0, sound_sources_ = 0;
};

class Loop : public sim::SimSink {
 public:
  Loop(const MissionRunOptions& options, const slam::SlamOptions& slam_options,
       const explore::ExploreOptions& explore_options,
       const depth::DepthToScanOptions& scan_options, const Eigen::Isometry3d& base_from_camera,
       sim::Simulator* simulator, MissionObserver* observer, MissionResult* result,
       const Eigen::Vector2d& pose_sigma_xy_yaw)
      : options_(options),
        slam_(slam_options),
        explore_(explore_options),
        scan_options_(scan_options),
        base_from_camera_(base_from_camera),
        sim_(simulator),
        observer_(observer),
        result_(result),
        perception_(nullptr),
        pose_sigma_xy_yaw_(pose_sigma_xy_yaw) {}

  void Publish(const std::string&, const sarmap::odometry_t& m) override {
    const common::Rigid2d odom_from_base =
        common::ToRigid3d(m.position_m, m.orientation).ToRigid2d();
    slam_.AddOdometry(Seconds(m.header.utime), odom_from_base);
    explore_.OnOdometry(odom_from_base, Seconds(m.header.utime));
  }

  void Publish(const std::string& channel, const sarmap::image_t& m) override {
    if (channel == "DEPTH") OnDepth(m);
    // After SLAM: the frame's POSE is known when its detections reach the people map.
    if (perception_) perception_->OnImage(channel, m);
  }

  void OnDepth(const sarmap::image_t& m) {
    const double slam0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    std::vector<uint16_t> depth_mm;
    std::string error;
    if (!common::DecodeDepthImage(m, &depth_mm, &error)) return;
    if (!converter_) {
      depth::PinholeIntrinsics in;
      in.width = m.width;
      in.height = m.height;
      in.fx = m.intrinsics.fx;
      in.fy = m.intrinsics.fy;
      in.cx = m.intrinsics.cx;
      in.cy = m.intrinsics.cy;
      converter_ = std::make_unique<depth::DepthToScan>(scan_options_, in, base_from_camera_);
    }
    const depth::PlanarScan planar = converter_->Convert(depth_mm.data(), m.depth_unit_m);
    slam::LaserScan scan;
    scan.time_s = Seconds(m.header.utime);
    scan.angle_min_rad = planar.angle_min_rad;
    scan.angle_increment_rad = planar.angle_increment_rad;
    scan.range_min_m = planar.range_min_m;
    scan.range_max_m = planar.range_max_m;
    scan.ranges_m = planar.ranges_m;
    const slam::ScanResult r = slam_.AddScan(scan);
    const double t = scan.time_s - start_s_;
    if (r.accepted) {
      explore_.OnPose(r.map_from_base, scan.time_s);
      PublishPose(m.header.utime, t, r);
    }
    if (r.accepted && t - last_map_s_ >= options_.map_period_s) {
      last_map_s_ = t;
      PublishMap(t);
    }
    result_->slam_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - slam0;
    explore::Scan es;
    es.stamp_s = scan.time_s;
    es.angle_min_rad = scan.angle_min_rad;
    es.angle_increment_rad = scan.angle_increment_rad;
    es.range_min_m = scan.range_min_m;
    es.range_max_m = scan.range_max_m;
    es.ranges_m = scan.ranges_m;
    es.visible_from_m = planar.visible_from_m;
    const double explore0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    const explore::Velocity v = explore_.OnScan(t, es);
    result_->explore_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - explore0;
    sim_->SetVelocityCommand(v.linear_mps, v.angular_radps);
    if (t - last_status_s_ >= 0.5) {
      last_status_s_ = t;
      PublishStatus(m.header.utime, t);
    }
    slam_pose_ = r.map_from_base;
  }

  void Publish(const std::string&, const sarmap::audio_frame_t& m) override {
    if (!perception_) return;
    if (observer_) observer_->OnAudio(Seconds(m.header.utime) - start_s_, m);
    perception_->OnAudio(m);
  }

  // SLAM_ANCHOR_REQUEST from the sound map or the people map: sarmap-slam keeps each client's
  // node ids and answers with SLAM_ANCHORS (every client's anchors) at once and after every
  // optimisation.
  void OnAnchorRequest(const sarmap::slam_anchor_request_t& m) {
    std::vector<int64_t>& ids = anchor_requests_[m.client_id];
    if (ids == m.node_ids) return;
    ids = m.node_ids;
    if (ComputeCovariance()) PublishAnchors(false);
  }

  void Publish(const std::string&, const sarmap::sim_truth_t& m) override {
    const double t = Seconds(m.header.utime) - start_s_;
    result_->distance_m = m.distance_m;
    result_->collisions = m.collisions;
    if (observer_) observer_->OnTruth(t, m);
    if (t - last_sample_s_ >= 1.0) {
      last_sample_s_ = t;
      MissionSample s;
      s.t_s = t;
      const common::Rigid2d truth =
          common::ToRigid3d(m.robot_position_m, m.robot_orientation).ToRigid2d();
      s.truth_pose =
          Eigen::Vector3d(truth.translation().x(), truth.translation().y(), truth.yaw_rad());
      s.slam_pose = Eigen::Vector3d(slam_pose_.translation().x(), slam_pose_.translation().y(),
                                    slam_pose_.yaw_rad());
      s.state = explore_.status().state;
      s.collisions = m.collisions;
      s.distance_m = m.distance_m;
      result_->samples.push_back(s);
    }
  }

  void Publish(const std::string&, const sarmap::occupancy_grid_t& m) override {
    if (observer_) observer_->OnFloor(Seconds(m.header.utime) - start_s_, m);
  }

  void set_start_s(double s) { start_s_ = s; }
  void set_perception(Perception* perception) { perception_ = perception; }
  explore::ExploreController* mutable_explore() { return &explore_; }
  const explore::ExploreController& explore() const { return explore_; }
  const slam::Slam& slam() const { return slam_; }
  double start_s() const { return start_s_; }

 private:
  static double Seconds(int64_t utime) { return common::UtimeToSeconds(utime); }

  void PublishMap(double t) {
    const slam::OccupancyMap map = slam_.DrawMap();
    explore::Grid grid;
    common::CopyGridGeometry(map, &grid);
    grid.cells = map.cells;
    explore_.OnMap(grid);
    SoundChain* sound = perception_ ? perception_->sound() : nullptr;
    // As sarmap-slam: no MAP before the map has a cell (a grid of no cells is malformed).
    if ((observer_ || sound) && map.width > 0 && map.height > 0) {
      sarmap::header_t header{};
      header.utime = static_cast<int64_t>((start_s_ + t) * 1e6);
      header.seq = map_seq_++;
      header.frame = "map";
      const sarmap::occupancy_grid_t m = common::MakeOccupancyGrid(header, map, false);
      if (observer_) observer_->OnMap(t, m);
      if (sound) sound->intake->OnSiteMap(m);
    }
  }

  // As sarmap-slam's ComputeCovariance: one joint covariance of the latest node and the
  // requested anchors (the latest node's block goes on POSE).
  bool ComputeCovariance() {
    if (slam_.num_nodes() == 0) return false;
    std::vector<int64_t> requested;
    for (const auto& [client, ids] : anchor_requests_)
      requested.insert(requested.end(), ids.begin(), ids.end());
    std::vector<int> ids = slam_.HoldAnchors(requested);
    Eigen::MatrixXd cov;
    if (!slam_.JointCovariance(ids, &cov)) return false;
    covariance_ids_ = std::move(ids);
    joint_covariance_ = std::move(cov);
    node_covariance_ = joint_covariance_.topLeftCorner<3, 3>();
    return true;
  }

  // As sarmap-slam's PublishAnchors: SLAM_ANCHORS from the last ComputeCovariance().
  void PublishAnchors(bool loop_closed) {
    if (!perception_ || covariance_ids_.empty()) return;
    const std::vector<int>& ids = covariance_ids_;
    const sarmap::slam_anchors_t msg =
        slam::AnchorsMessage(slam_, ids, joint_covariance_, loop_closed);
    if (observer_) observer_->OnSlamAnchors(Seconds(msg.header.utime) - start_s_, msg);
    perception_->OnAnchors(msg);  // after the observer: see Perception::OnAudio
  }

  // POSE as sarmap-slam publishes it: the scan's pose, with the latest node's covariance from
  // the last optimisation plus the local matching uncertainty (pose_sigma_xy_m, _yaw_deg);
  // SLAM_ANCHORS after it when the scan was optimised.
  void PublishPose(int64_t utime, double t, const slam::ScanResult& r) {
    if (!perception_ && !observer_) return;
    const bool have_covariance = r.optimised && ComputeCovariance();
    sarmap::pose_t msg{};
    msg.header.utime = utime;
    msg.header.frame = "map";
    msg.child_frame = "base";
    common::FromRigid3d(common::Rigid3d::FromRigid2d(r.map_from_base), msg.position_m,
                        msg.orientation);
    Eigen::Matrix3d cov = node_covariance_;
    const double sxy = pose_sigma_xy_yaw_.x(), syaw = pose_sigma_xy_yaw_.y();
    cov(0, 0) += sxy * sxy;
    cov(1, 1) += sxy * sxy;
    cov(2, 2) += syaw * syaw;
    common::SetPlanarCovariance(cov, msg.covariance);
    msg.node_id = r.node_id;
    if (observer_) observer_->OnPose(t, msg);
    if (perception_) perception_->OnPose(msg);  // after the observer: see Perception::OnAudio
    if (have_covariance) PublishAnchors(r.loop_closed);
  }

  void PublishStatus(int64_t utime, double t) {
    const explore::ExploreStatus& s = explore_.status();
    if (s.state == "home" && result_->home_after_s < 0) result_->home_after_s = t;
    if (!observer_) return;
    sarmap::explore_status_t out = explore::ToStatusMessage(s, utime);
    out.header.seq = status_seq_++;
    observer_->OnExploreStatus(t, out);
  }

  MissionRunOptions options_;
  slam::Slam slam_;
  explore::ExploreController explore_;
  depth::DepthToScanOptions scan_options_;
  Eigen::Isometry3d base_from_camera_;
  std::unique_ptr<depth::DepthToScan> converter_;
  sim::Simulator* sim_;
  MissionObserver* observer_;
  MissionResult* result_;
  Perception* perception_;
  Eigen::Vector2d pose_sigma_xy_yaw_;
  Eigen::Matrix3d node_covariance_ = Eigen::Matrix3d::Zero();
  std::map<std::string, std::vector<int64_t>> anchor_requests_;  // client id -> node ids
  std::vector<int> covariance_ids_;
  Eigen::MatrixXd joint_covariance_;
  double start_s_ = 0;
  double last_map_s_ = -1e9, last_status_s_ = -1e9, last_sample_s_ = -1e9;
  int64_t map_seq_ = 0, status_seq_ = 0;
  slam::Rigid2d slam_pose_;
};

// An 8-bit greyscale image as a binary PGM, rows top first.
// A comment line after the magic number places the image in the map frame: the outer corner of
// the bottom-left cell and the cell size.
void WritePgm(const std::string& path, int width, int height, const std::vector<uint8_t>& image,
              double origin_x_m, double origin_y_m, double resolution_m) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f,
               "P5\n# map frame: origin_x_m %.3f origin_y_m %.3f resolution_m %.3f\n%d %d\n255\n",
               origin_x_m, origin_y_m, resolution_m, width, height);
  std::fwrite(image.data(), 1, image.size(), f);
  std::fclose(f);
}

// The explorer's grid as a PGM: unknown grey (128), free white, occupied black, free but too
// near an obstacle light grey (200), seen too little to call (uncertain) 170, the last path 60.
void WriteExplorerMap(const explore::ExploreController& controller, const std::string& path) {
  const explore::ExploreMap& map = controller.map();
  const explore::Grid& g = map.grid();
  std::vector<uint8_t> image(static_cast<size_t>(g.width) * g.height);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int8_t v = g.at(x, y);
      const auto& o = map.options();
      uint8_t c = v < 0                       ? 128
                  : v >= o.occupied_threshold ? 0
                  : v >= o.free_threshold     ? 170
                  : map.Traversable(x, y)     ? 255
                                              : 200;
      image[static_cast<size_t>(g.height - 1 - y) * g.width + x] = c;
    }
  }
  for (const auto& p : controller.status().path) {
    const Eigen::Vector2i c = g.CellOf(p);
    if (g.Contains(c.x(), c.y()))
      image[static_cast<size_t>(g.height - 1 - c.y()) * g.width + c.x()] = 60;
  }
  WritePgm(path, g.width, g.height, image, g.origin_x_m, g.origin_y_m, g.resolution_m);
}

// SLAM's map as a PGM: unknown grey, occupancy 0..100 from white to black.
void WriteSlamMap(const slam::Slam& slam, const std::string& path) {
  const slam::OccupancyMap map = slam.RenderMap();
  std::vector<uint8_t> image(static_cast<size_t>(map.width) * map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const int8_t v = map.cells[static_cast<size_t>(y) * map.width + x];
      image[static_cast<size_t>(map.height - 1 - y) * map.width + x] =
          v < 0 ? 128 : static_cast<uint8_t>(255 - (255 * std::min<int>(v, 100)) / 100);
    }
  }
  WritePgm(path, map.width, map.height, image, map.origin_x_m, map.origin_y_m, map.resolution_m);
}

}  // namespace

MissionResult RunMission(const MissionRunOptions& options, MissionObserver* observer,
                         const std::function<void(double)>& progress) {
  const double cpu0 = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
  const bool sound = options.perception && options.sound;
  // With sound: the array the localiser's configuration describes, on the simulated robot (as
  // make demo runs it).
  std::vector<std::string> sim_overrides = {
      "world=" + options.world,
      "seed=" + std::to_string(options.seed),
      "drive=cmd_vel",
      "speed=0",
      sound ? "audio.enabled=true" : "audio.enabled=false",
      "camera.rate_hz=" + std::to_string(options.camera_rate_hz),
      "camera.jpeg_quality=0",
      "camera.compress_depth=false"};
  if (sound) sim_overrides.push_back("audio.mic_array=" + options.sim_mic_array);
  sim_overrides.insert(sim_overrides.end(), options.sim_overrides.begin(),
                       options.sim_overrides.end());
  const auto sim_options = common::LoadOptions<sim::SimOptions>(options.sim_config, sim_overrides);
  const std::string root = sim::FindRepoRoot(options.sim_config);
  const sim::SimSetup setup = sim::LoadSetup(sim_options, root);
  const auto slam_file =
      common::LoadOptions<slam::SlamNodeOptions>(options.slam_config, options.slam_overrides);
  std::vector<std::string> explore_overrides = options.explore_overrides;
  if (!options.mode.empty()) explore_overrides.push_back("explore.mode=" + options.mode);
  const auto explore_file =
      common::LoadOptions<explore::ExploreNodeOptions>(options.explore_config, explore_overrides);
  const auto depth_file =
      common::LoadOptions<depth::DepthNodeOptions>(options.depth_config, options.depth_overrides);
  const depth::DepthToScanOptions scan_options = depth_file.ScanOptions();
  const Eigen::Isometry3d base_from_camera = setup.robot.base_from_camera.ToRigid3d().ToIsometry();

  sim::Simulator simulator(setup);
  MissionResult result;
  result.warnings = simulator.warnings();
  MissionRunOptions loop_options = options;
  if (loop_options.map_period_s <= 0) loop_options.map_period_s = slam_file.map_period_s;
  Loop loop(loop_options, slam_file.slam, explore_file.explore, scan_options, base_from_camera,
            &simulator, observer, &result,
            Eigen::Vector2d(slam_file.pose_sigma_xy_m, slam_file.pose_sigma_yaw_deg * M_PI / 180));
  loop.set_start_s(1e-6 * static_cast<double>(simulator.start_utime()));
  std::unique_ptr<Perception> perception;
  if (options.perception) {
    // The nodes read their files relative to the repository root (their working directory).
    auto vision = common::LoadOptions<vision_people::VisionPeopleOptions>(
        Resolve(options.vision_config, root), {});
    vision.robot_config = Resolve(vision.robot_config, root);
    vision.detector.color.pcl_svm_file = Resolve(vision.detector.color.pcl_svm_file, root);
    auto people = common::LoadOptions<people_map::PeopleMapNodeOptions>(
        Resolve(options.people_map_config, root), {});
    people.state_file.clear();  // one mission, nothing to resume
    const common::RobotOptions robot = common::LoadRobot(Resolve(people.robot_config, root));
    std::unique_ptr<SoundChain> sound;
    if (options.sound) {
      const auto localisation = common::LoadOptions<sound::SoundLocalisationOptions>(
          Resolve(options.sound_localisation_config, root), {});
      const std::string array_path = Resolve(localisation.array, root);
      const auto array = common::LoadMicArray(array_path);
      auto speech_options =
          common::LoadOptions<speech::SpeechNodeOptions>(Resolve(options.speech_config, root), {});
      auto map_options = common::LoadOptions<sound_map::SoundMapNodeOptions>(
          Resolve(options.sound_map_config, root), {});
      map_options.state_file.clear();
      const common::RobotOptions map_robot =
          common::LoadRobot(Resolve(map_options.robot_config, root));
      try {
        sound = std::make_unique<SoundChain>(
            localisation, array, array_path.substr(0, array_path.find_last_of('/') + 1),
            speech_options, map_options, sound_map::MountFromRobot(map_robot));
      } catch (const std::invalid_argument& e) {
        throw common::OptionsError(e.what());
      }
      SoundChain* chain = sound.get();
      chain->intake = std::make_unique<sound_map::SoundMapIntake>(
          map_options, &chain->map,
          [&perception](sarmap::sound_map_t& m) { perception->OnSoundMap(m); },
          [&loop](sarmap::slam_anchor_request_t& r) { loop.OnAnchorRequest(r); });
    }
    perception = std::make_unique<Perception>(
        vision, people, robot.base_from_camera.ToRigid3d(), robot.base_from_mic_array.ToRigid3d(),
        std::move(sound), loop.mutable_explore(), observer, &result,
        [&loop](sarmap::slam_anchor_request_t& r) { loop.OnAnchorRequest(r); });
    perception->set_start_s(1e-6 * static_cast<double>(simulator.start_utime()));
    loop.set_perception(perception.get());
  }
  const std::vector<sim::Obstacle> obstacles = sim::CollisionObstacles(simulator.world(), true);
  const double step_s = 0.05;
  double next_progress = 10;
  double next_report = options.report_period_s;
  double next_release_s = common::SteadySeconds() + common::kReleaseFreeMemoryPeriod_s;
  for (double t = step_s; t <= options.duration_s + 1e-9; t += step_s) {
    simulator.AdvanceTo(t, &loop);
    if (simulator.collisions() > static_cast<int>(result.contacts.size())) {
      const sim::Contact& c = simulator.last_contact();
      char text[160];
      const auto& status = loop.explore().status();
      std::snprintf(text, sizeof(text),
                    "t=%.1f s at (%.2f, %.2f) m heading %.0f deg: %s (explorer %s, driven by %s)",
                    c.t_s, c.map_from_base.translation().x(), c.map_from_base.translation().y(),
                    c.map_from_base.yaw_rad() * 180 / M_PI, c.what.c_str(), status.state.c_str(),
                    status.driven_by.c_str());
      result.contacts.resize(simulator.collisions(), text);
    }
    const common::Rigid2d base = simulator.map_from_base();
    for (const sim::Obstacle& o : obstacles) {
      const double gap = sim::SegmentDistance(base.translation(), o.a, o.b) - o.half_width -
                         sim_options.robot_radius_m;
      if (gap < result.closest_gap_m) {
        result.closest_gap_m = gap;
        char text[200];
        const auto& status = loop.explore().status();
        std::snprintf(text, sizeof(text),
                      "t=%.2f s at (%.2f, %.2f) m heading %.0f deg: %s (explorer %s, driven by %s)",
                      t, base.translation().x(), base.translation().y(),
                      base.yaw_rad() * 180 / M_PI, o.what.c_str(), status.state.c_str(),
                      status.driven_by.c_str());
        result.closest_gap_what = text;
      }
    }
    if (progress && t >= next_progress) {
      progress(t);
      next_progress += 10;
    }
    // As every node does (common::Node::Run), so that the reported resident size is what the
    // components hold.
    if (common::SteadySeconds() >= next_release_s) {
      common::ReleaseFreeMemory();
      next_release_s = common::SteadySeconds() + common::kReleaseFreeMemoryPeriod_s;
    }
    if (options.report_period_s > 0 && t >= next_report - 0.5 * step_s) {
      next_report += options.report_period_s;
      MissionReport report;
      report.t_s = t;
      report.state = loop.explore().status().state;
      report.distance_m = result.distance_m;
      report.cpu_s = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
      report.slam_cpu_s = result.slam_cpu_s;
      report.explore_cpu_s = result.explore_cpu_s;
      report.vision_cpu_s = result.vision_cpu_s;
      report.people_map_cpu_s = result.people_map_cpu_s;
      report.sound_cpu_s = result.sound_cpu_s;
      report.rss_mb = common::ResidentMegabytes();
      report.heap_mb = common::HeapInUseMegabytes();
      report.slam_memory = loop.slam().Memory();
      const slam::SlamStats& stats = loop.slam().stats();
      report.slam_nodes = loop.slam().num_live_nodes();
      report.slam_submaps = loop.slam().num_live_submaps();
      report.slam_nodes_kept = loop.slam().num_nodes_kept_for_anchors();
      report.slam_submaps_kept_area = stats.submaps_kept_new_area;
      report.slam_submaps_kept_obstacles = stats.submaps_kept_new_obstacles;
      report.slam_optimisations = stats.optimisations;
      report.slam_loop_closures = stats.loop_closures;
      report.slam_optimise_s = stats.optimise_seconds;
      const slam::Slam::MapDrawingStats& drawing = loop.slam().map_drawing_stats();
      report.slam_map_s = drawing.seconds;
      report.slam_map_draws = drawing.draws;
      report.slam_map_redraws = drawing.redraws;
      if (perception) {
        report.people_on_map = perception->people_on_map();
        report.sound_sources = perception->sound_sources();
        report.detections_without_pose = perception->detections_without_pose();
      }
      result.reports.push_back(report);
    }
    if (loop.explore().status().state == "home" && t > 5) {
      // Home: the mission is over; a few more seconds so that the last map is drawn.
      simulator.AdvanceTo(t + 1.0, &loop);
      result.simulated_s = t + 1.0;
      break;
    }
    result.simulated_s = t;
  }
  if (perception) perception->Finish();
  for (const slam::StampedPose2& p : loop.slam().Trajectory())
    result.final_slam_trail.emplace_back(p.time_s - loop.start_s(), p.x_m, p.y_m, p.yaw_rad);
  if (!options.explorer_map_pgm.empty()) WriteExplorerMap(loop.explore(), options.explorer_map_pgm);
  if (!options.slam_map_pgm.empty()) WriteSlamMap(loop.slam(), options.slam_map_pgm);
  result.final_state = loop.explore().status().state;
  result.recoveries = loop.explore().status().recoveries;
  result.looks = loop.explore().status().looks;
  result.came_home = result.final_state == "home";
  result.cpu_s = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
  return result;
}

}  // namespace mission
}  // namespace sarmap
