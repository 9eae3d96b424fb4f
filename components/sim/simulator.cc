#include "sim/simulator.h"

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "sim/appearance.h"
#include "sim/audio_sim.h"
#include "sim/floor_plan.h"
#include "sim/renderer.h"
#include "sim/robot.h"
#include "sim/sound_sources.h"

namespace sarmap {
namespace sim {
namespace fs = std::filesystem;
namespace {

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

// Relative paths: from the repository root; files (not the data dir) may also be given
// relative to the working directory.
std::string Resolve(const std::string& path, const std::string& root, bool try_cwd = true) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  std::error_code ec;
  if (try_cwd && fs::is_regular_file(path, ec)) return path;
  if (root.empty()) return try_cwd ? common::ResolveConfigPath(path) : path;
  return (fs::path(root) / path).lexically_normal().string();
}

void SetQuaternion(double yaw, double q[4]) {
  q[0] = std::cos(yaw / 2);
  q[1] = 0;
  q[2] = 0;
  q[3] = std::sin(yaw / 2);
}

}  // namespace

std::string FindRepoRoot(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  if (ec) return "";
  for (fs::path dir = p.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (dir.filename() == "config") return dir.parent_path().string();
    if (dir == dir.root_path()) break;
  }
  return "";
}

SimSetup LoadSetup(const SimOptions& options, const std::string& repo_root) {
  SimSetup setup;
  setup.options = options;
  setup.world = LoadWorld(Resolve(options.world, repo_root));
  const std::string robot_path = Resolve(options.robot_config, repo_root);
  setup.robot = common::LoadRobot(robot_path);
  std::string array = options.audio.mic_array.empty() ? setup.robot.mic_array : options.audio.mic_array;
  if (array.find('/') == std::string::npos && array.find(".yaml") == std::string::npos) {
    array = (fs::path(robot_path).parent_path() / "arrays" / (array + ".yaml")).string();
  } else {
    array = Resolve(array, repo_root);
  }
  setup.array = common::LoadMicArray(array);
  setup.data_dir = Resolve(options.data_dir, repo_root, false);
  return setup;
}

struct Simulator::Impl {
  std::vector<Appearance> appearances;
  std::unique_ptr<Renderer> renderer;
  std::unique_ptr<AudioSim> audio;
  std::unique_ptr<Robot> robot;
  common::Rigid3d base_from_camera, base_from_array;
  double dt = 0.005;
  double next_odom = 0, next_cam = 0, next_truth = 0, next_floor = 0;
  int64_t seq_odom = 0, seq_depth = 0, seq_rgb = 0, seq_truth = 0, seq_floor = 0;
  sarmap::occupancy_grid_t floor;  // the reachable floor, computed once (the world is static)
  std::map<std::string, int64_t> seq_audio;
  std::vector<int> person_pixels;
  sarmap::camera_intrinsics_t intrinsics;
  RenderOutput render;
};

Simulator::Simulator(const SimSetup& setup) : impl_(std::make_unique<Impl>()), setup_(setup) {
  const SimOptions& o = setup_.options;
  start_utime_ = o.start_utime > 0
                     ? o.start_utime
                     : std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch()).count();
  const uint64_t seed = static_cast<uint64_t>(o.seed);
  impl_->dt = 1.0 / o.physics_rate_hz;
  impl_->base_from_camera = setup_.robot.base_from_camera.ToRigid3d();
  impl_->base_from_array = setup_.robot.base_from_mic_array.ToRigid3d();
  impl_->robot = std::make_unique<Robot>(setup_.world, o, setup_.robot.max_linear_mps,
                                         setup_.robot.max_angular_radps, seed * 3 + 1);
  if (o.camera.enabled) {
    std::string warning;
    impl_->appearances = LoadAppearances(setup_.data_dir, 8, &warning);
    if (!warning.empty()) warnings_.push_back(warning);
    impl_->renderer = std::make_unique<Renderer>(o.camera, seed * 3 + 2);
    impl_->renderer->SetWorld(setup_.world, &impl_->appearances);
    const Intrinsics& in = impl_->renderer->intrinsics();
    impl_->intrinsics.width = in.width;
    impl_->intrinsics.height = in.height;
    impl_->intrinsics.fx = in.fx;
    impl_->intrinsics.fy = in.fy;
    impl_->intrinsics.cx = in.cx;
    impl_->intrinsics.cy = in.cy;
    impl_->intrinsics.distortion_model = sarmap::camera_intrinsics_t::DISTORTION_NONE;
    for (double& d : impl_->intrinsics.distortion) d = 0;
  }
  if (o.audio.enabled) {
    if (!o.audio.asynchronous && (!setup_.array.clock_drift.empty() || !setup_.array.start_offsets_s.empty())) {
      warnings_.push_back("array '" + setup_.array.name +
                          "' has start offsets / clock drift, used only with audio.asynchronous: true");
    }
    const std::string cache = (std::filesystem::temp_directory_path() /
                               ("sarmap-sim-espeak-" + std::to_string(::getuid())))
                                  .string();
    const int rate = setup_.array.sample_rate_hz;
    std::vector<std::unique_ptr<SourceSignal>> signals;
    for (const SoundSource& s : setup_.world.sources) {
      std::vector<std::vector<float>> clips;
      for (const std::string& clip : s.clips) {
        std::string error;
        std::vector<float> samples;
        if (clip.rfind("espeak:", 0) == 0) {
          if (!o.audio.espeak) continue;
          samples = EspeakClip(clip.substr(7), cache, rate, &error);
        } else {
          samples = LoadClip(fs::path(clip).is_absolute() ? clip : setup_.data_dir + "/" + clip, rate, &error);
        }
        if (samples.empty()) {
          warnings_.push_back("source '" + s.name + "': " + error);
        } else {
          clips.push_back(std::move(samples));
        }
      }
      if (s.kind == SourceKind::kVoice && clips.empty()) {
        warnings_.push_back("source '" + s.name + "': no clip could be loaded, the voice is silent");
      }
      signals.push_back(std::make_unique<SourceSignal>(s, std::move(clips), rate, seed * 1000 + s.id));
    }
    impl_->audio = std::make_unique<AudioSim>(o.audio, setup_.array, impl_->base_from_array, setup_.world,
                                              std::move(signals), seed * 3 + 3);
  }
  impl_->person_pixels.assign(setup_.world.people.size(), 0);
  // The floor the robot can cover (the world is static: computed once, zstd-compressed; a
  // 180 m^2 site is ~100 k cells, a few kB on the wire).
  const GridMap floor = ReachableFloor(setup_.world, o.robot_radius_m, 0.05);
  sarmap::header_t header{};
  header.frame = "map";
  impl_->floor = common::MakeOccupancyGrid(header, floor, true);
}

Simulator::~Simulator() = default;

int64_t Simulator::utime() const { return start_utime_ + static_cast<int64_t>(std::llround(t_ * 1e6)); }

common::Rigid2d Simulator::map_from_base() const { return impl_->robot->map_from_base(); }
int Simulator::collisions() const { return impl_->robot->collisions(); }
const Contact& Simulator::last_contact() const { return impl_->robot->last_contact(); }

common::Rigid3d Simulator::map_from_camera() const {
  return common::Rigid3d::FromRigid2d(impl_->robot->map_from_base()) * impl_->base_from_camera;
}

void Simulator::SetVelocityCommand(double linear_mps, double angular_radps) {
  impl_->robot->SetCommand(linear_mps, angular_radps, t_);
}

void Simulator::SetRobotPose(const common::Rigid2d& pose) {
  // Rebuild the robot at the new pose (tests place the camera precisely).
  World w = setup_.world;
  w.robot.pose = Eigen::Vector3d(pose.translation().x(), pose.translation().y(), pose.yaw_rad());
  w.robot.path.clear();
  impl_->robot = std::make_unique<Robot>(w, setup_.options, setup_.robot.max_linear_mps,
                                         setup_.robot.max_angular_radps, setup_.options.seed * 3 + 1);
}

int Simulator::appearance_count() const { return static_cast<int>(impl_->appearances.size()); }

AudioSim* Simulator::audio() { return impl_->audio.get(); }

const Renderer* Simulator::renderer() const { return impl_->renderer.get(); }

Simulator::View Simulator::RenderView() {
  View view;
  if (!impl_->renderer) return view;
  impl_->render.fill_true_depth = true;
  impl_->renderer->Render(map_from_camera(), &impl_->render);
  view.width = impl_->renderer->intrinsics().width;
  view.height = impl_->renderer->intrinsics().height;
  view.rgb = impl_->render.rgb;
  view.depth_mm = impl_->render.depth_mm;
  view.person_pixels = impl_->render.person_pixels;
  view.person_box = impl_->render.person_box;
  return view;
}

void Simulator::AdvanceTo(double target_s, SimSink* sink) {
  const SimOptions& o = setup_.options;
  Impl& m = *impl_;
  const double cpu0 = ThreadCpuSeconds();
  while (t_ + m.dt <= target_s + 1e-9) {
    double c = ThreadCpuSeconds();
    m.robot->Step(t_, m.dt);
    t_ += m.dt;
    timing_.physics_s += ThreadCpuSeconds() - c;
    sarmap::header_t header;
    header.utime = utime();
    if (o.floor_period_s > 0 && t_ + 1e-9 >= m.next_floor) {
      m.next_floor += o.floor_period_s;
      m.floor.header.utime = header.utime;
      m.floor.header.seq = m.seq_floor++;
      sink->Publish(o.channels.floor, m.floor);
    }
    if (t_ + 1e-9 >= m.next_odom) {
      m.next_odom += 1.0 / o.odometry.rate_hz;
      m.robot->UpdateOdometry();
      sarmap::odometry_t odom;
      odom.header = header;
      odom.header.frame = "odom";
      odom.header.seq = m.seq_odom++;
      odom.child_frame = "base";
      const common::Rigid2d& p = m.robot->odom_from_base();
      odom.position_m[0] = p.translation().x();
      odom.position_m[1] = p.translation().y();
      odom.position_m[2] = 0;
      SetQuaternion(p.yaw_rad(), odom.orientation);
      for (double& v : odom.pose_covariance) v = 0;
      odom.pose_covariance[0] = odom.pose_covariance[7] = m.robot->odom_var_xy() + 1e-9;
      odom.pose_covariance[14] = odom.pose_covariance[21] = odom.pose_covariance[28] = 1e-9;
      odom.pose_covariance[35] = m.robot->odom_var_yaw() + 1e-9;
      odom.linear_velocity_mps[0] = m.robot->linear_mps();
      odom.linear_velocity_mps[1] = odom.linear_velocity_mps[2] = 0;
      odom.angular_velocity_radps[0] = odom.angular_velocity_radps[1] = 0;
      odom.angular_velocity_radps[2] = m.robot->angular_radps();
      for (double& v : odom.twist_covariance) v = 0;
      const double sv = o.odometry.trans_noise * std::abs(m.robot->linear_mps()) + 1e-3;
      const double sw = o.odometry.rot_noise * std::abs(m.robot->angular_radps()) + 1e-3;
      odom.twist_covariance[0] = sv * sv;
      odom.twist_covariance[35] = sw * sw;
      for (int k : {7, 14, 21, 28}) odom.twist_covariance[k] = 1e-9;
      sink->Publish(o.channels.odom, odom);
    }
    if (m.renderer && t_ + 1e-9 >= m.next_cam) {
      m.next_cam += 1.0 / o.camera.rate_hz;
      c = ThreadCpuSeconds();
      m.render.fill_true_depth = false;
      m.renderer->Render(map_from_camera(), &m.render);
      const double c2 = ThreadCpuSeconds();
      timing_.render_s += c2 - c;
      for (size_t k = 0; k < m.person_pixels.size(); ++k) m.person_pixels[k] = m.render.person_pixels[k];
      sarmap::header_t cam_header = header;
      cam_header.frame = "camera";
      cam_header.seq = m.seq_depth++;
      const Intrinsics& in = m.renderer->intrinsics();
      sarmap::image_t depth = common::MakeDepthImage(cam_header, m.intrinsics, m.render.depth_mm.data(),
                                                     in.width, in.height, o.camera.compress_depth);
      sink->Publish(o.channels.depth, depth);
      cam_header.seq = m.seq_rgb++;
      sarmap::image_t rgb = common::MakeColorImage(cam_header, m.intrinsics, m.render.rgb.data(), in.width,
                                                   in.height, o.camera.jpeg_quality);
      sink->Publish(o.channels.rgb, rgb);
      timing_.encode_s += ThreadCpuSeconds() - c2;
    }
    if (m.audio) {
      c = ThreadCpuSeconds();
      while (static_cast<double>(m.audio->generated()) / m.audio->sample_rate_hz() <= t_ + 0.02) {
        m.audio->GenerateBlock(m.robot->map_from_base(), m.robot->linear_mps(), m.robot->angular_radps());
      }
      std::vector<AudioFrameOut> frames;
      m.audio->CollectFrames(t_, start_utime_, &frames);
      for (AudioFrameOut& f : frames) {
        const std::string channel = f.channel_suffix.empty() ? o.channels.audio : o.channels.audio + "_" + f.channel_suffix;
        f.frame.header.seq = m.seq_audio[channel]++;
        sink->Publish(channel, f.frame);
      }
      timing_.audio_s += ThreadCpuSeconds() - c;
    }
    if (t_ + 1e-9 >= m.next_truth) {
      m.next_truth += 1.0 / o.truth_rate_hz;
      sarmap::sim_truth_t truth;
      truth.header = header;
      truth.header.frame = "map";
      truth.header.seq = m.seq_truth++;
      truth.world = setup_.world.name;
      const common::Rigid2d& p = m.robot->map_from_base();
      truth.robot_position_m[0] = p.translation().x();
      truth.robot_position_m[1] = p.translation().y();
      truth.robot_position_m[2] = 0;
      SetQuaternion(p.yaw_rad(), truth.robot_orientation);
      std::vector<bool> calling(setup_.world.people.size(), false);
      std::vector<SourceSignal*> signals;
      if (m.audio) signals = m.audio->signals();
      for (const SoundSource& s : setup_.world.sources) {
        sarmap::sim_sound_source_t src{};
        src.id = s.id;
        src.name = s.name;
        src.kind = static_cast<int8_t>(s.kind);
        for (int k = 0; k < 3; ++k) src.position_m[k] = s.position[k];
        src.active = false;
        for (SourceSignal* sig : signals) {
          if (sig->source().id == s.id) src.active = sig->ActiveAt(t_);
        }
        src.person_id = s.person_id;
        if (src.active && s.person_id > 0) calling[s.person_id - 1] = true;
        truth.sources.push_back(src);
      }
      for (size_t k = 0; k < setup_.world.people.size(); ++k) {
        const Person& person = setup_.world.people[k];
        sarmap::sim_person_t sp;
        sp.id = person.id;
        sp.name = person.name;
        sp.position_m[0] = person.position.x();
        sp.position_m[1] = person.position.y();
        sp.position_m[2] = 0;
        sp.yaw_rad = person.yaw_rad;
        sp.posture = static_cast<int8_t>(person.posture);
        sp.visible_to_camera = m.person_pixels[k] >= 50;
        sp.calling = calling[k];
        truth.people.push_back(sp);
      }
      truth.num_people = static_cast<int32_t>(truth.people.size());
      truth.num_sources = static_cast<int32_t>(truth.sources.size());
      for (int k = 0; k < 3; ++k) truth.start_pose[k] = setup_.world.robot.pose[k];
      truth.distance_m = m.robot->distance_m();
      truth.collisions = m.robot->collisions();
      sink->Publish(o.channels.truth, truth);
    }
  }
  timing_.total_s += ThreadCpuSeconds() - cpu0;
}

}  // namespace sim
}  // namespace sarmap
