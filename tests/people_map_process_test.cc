// sarmap-people-map as a real process: replaying the same inputs gives the same people map,
// and a kill -9 loses nothing already found (the restarted node resumes from its state file).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "common/node.h"
#include "common/robot_config.h"
#include "common/testing/isolated_network.h"
#include "sarmap/doa_source_t.hpp"
#include "sarmap/node_status_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "tests/process.h"

namespace sarmap {
namespace testing {
namespace {

// A person seen by the RGB-D detector at `c` (camera frame).
sarmap::person_detection_t SeenAt(const Eigen::Vector3d& c) {
  sarmap::person_detection_t d{};
  d.cue = sarmap::person_detection_t::CUE_SEEN_RGBD;
  d.has_range = true;
  for (int i = 0; i < 3; ++i) d.position_m[i] = c[i];
  d.position_covariance[0] = d.position_covariance[4] = d.position_covariance[8] = 0.01;
  d.confidence = 0.8f;
  return d;
}

class PeopleMapProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sarmap::IsolatedNetwork())
      GTEST_FAIL() << "run through tests/harness/sarmap-netns (ctest does)";
    dir_ = ::testing::TempDir() + "/pm-" + std::to_string(getpid());
    std::string ignored;
    RunCapture({"mkdir", "-p", dir_}, &ignored);
    lcm_ = std::make_unique<lcm::LCM>(common::DefaultLcmUrl());
    lcm_->subscribe("PEOPLE_MAP", &PeopleMapProcessTest::OnMap, this);
  }
  void OnMap(const lcm::ReceiveBuffer*, const std::string&, const sarmap::people_map_t* m) {
    last_ = *m;
    ++maps_;
  }

  std::unique_ptr<Process> StartNode(const std::string& state_file,
                                     const std::vector<std::string>& sets = {}) {
    std::vector<std::string> args = {"sarmap-people-map", "--set", "reorder_delay_s=0.2", "--set",
                                     "save_period_s=0.2", "--set", "publish_period_s=0.3"};
    if (!state_file.empty()) args.insert(args.end(), {"--set", "state_file=" + state_file});
    for (const std::string& set : sets) args.insert(args.end(), {"--set", set});
    auto p = std::make_unique<Process>(args, dir_ + "/node-" + std::to_string(++starts_) + ".log");
    // Up when its NODE_STATUS... simplest: when it answers a pose with a PEOPLE_MAP republish.
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    return p;
  }

  void Spin(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) lcm_->handleTimeout(20);
  }

  // A robot driving along +x at 0.5 m/s, seeing two people and hearing a third one, hidden,
  // whose position the sound map knows. `from`..`to` in seconds of mission time.
  void Play(double from, double to) {
    const common::Rigid3d base_from_camera = common::RobotOptions().base_from_camera.ToRigid3d();
    const Eigen::Vector3d people[2] = {{3.0, 0.5, 0.9}, {4.0, -0.8, 0.9}};
    for (double t = from; t < to; t += 0.05) {
      const int64_t utime = 1'000'000'000 + static_cast<int64_t>(t * 1e6);
      sarmap::pose_t pose{};
      pose.header.utime = utime;
      pose.header.frame = "map";
      pose.child_frame = "base";
      pose.position_m[0] = 0.5 * t;
      pose.orientation[0] = 1;
      pose.covariance[0] = pose.covariance[7] = 0.01;
      pose.covariance[35] = 0.001;
      lcm_->publish("POSE", &pose);
      const int step = static_cast<int>(std::lround(t / 0.05));
      if (step % 4 == 0) {  // people seen at 5 Hz
        const common::Rigid3d map_from_camera =
            common::Rigid3d(Eigen::Vector3d(0.5 * t, 0, 0), Eigen::Quaterniond::Identity()) *
            base_from_camera;
        sarmap::people_detections_t seen{};
        seen.header.utime = utime;
        seen.header.frame = "camera";
        for (const auto& p : people) {
          const Eigen::Vector3d c = map_from_camera.inverse() * p;
          if (c.z() < 0.5 || c.z() > 4.5) continue;
          seen.detections.push_back(SeenAt(c));
        }
        seen.num_detections = static_cast<int32_t>(seen.detections.size());
        lcm_->publish("PEOPLE_VISUAL", &seen);
      }
      if (step % 20 == 10) {  // the sound map and a call for help at 1 Hz
        sarmap::sound_map_t sound{};
        sound.header.utime = utime;
        sound.header.frame = "map";
        sarmap::sound_source_t s{};
        s.id = 5;
        s.position_m[0] = 2.0;
        s.position_m[1] = 3.0;
        s.covariance[0] = s.covariance[4] = s.covariance[8] = 0.05;
        s.state = sarmap::sound_source_t::STATE_CONVERGED;
        s.has_position = true;
        s.sound_class = sarmap::doa_source_t::SOUND_CLASS_VOICE;
        s.is_person = true;  // the sound map: a voice, heard calling, inside the site
        sound.sources.push_back(s);
        sound.num_sources = 1;
        lcm_->publish("SOUND_MAP", &sound);
        sarmap::people_detections_t heard{};
        heard.header.utime = utime;
        heard.header.frame = "mic_array";
        sarmap::person_detection_t d{};
        d.cue = sarmap::person_detection_t::CUE_HEARD;
        const double ax = 2.0 - (0.5 * t + 0.10), ay = 3.0;  // array 0.10 m ahead of the base
        d.azimuth_rad = std::atan2(ay, ax);
        d.direction_covariance[0] = 0.05 * 0.05;
        d.confidence = 0.7f;
        d.keyword = "help";
        heard.detections.push_back(d);
        heard.num_detections = 1;
        lcm_->publish("PEOPLE_AUDIO", &heard);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      lcm_->handleTimeout(0);
    }
  }

  std::string dir_;
  std::unique_ptr<lcm::LCM> lcm_;
  sarmap::people_map_t last_{};
  int maps_ = 0, starts_ = 0;
};

std::string Describe(const sarmap::people_map_t& m) {
  std::string out;
  char line[200];
  for (const auto& p : m.people) {
    snprintf(line, sizeof(line), "#%lld (%.6f, %.6f) cues %d n %d conf %.6f kw '%s'\n",
             static_cast<long long>(p.id), p.position_m[0], p.position_m[1], p.cues,
             p.num_detections, p.confidence, p.keyword.c_str());
    out += line;
  }
  return out;
}

TEST_F(PeopleMapProcessTest, SameInputsGiveTheSameMapAndTheHiddenCallerIsPlaced) {
  std::string first;
  for (int run = 0; run < 2; ++run) {
    auto node = StartNode("");
    Play(0.0, 6.0);
    Spin(1.0);
    node->Signal(SIGINT);
    ASSERT_EQ(node->Wait(10), 0) << node->Output();
    Spin(0.3);
    const std::string described = Describe(last_);
    if (run == 0) {
      first = described;
      ASSERT_EQ(last_.num_people, 3) << described << node->Output();
      bool hidden = false;
      for (const auto& p : last_.people) {
        if (p.cues == sarmap::mapped_person_t::CUE_HEARD) {
          hidden = true;
          EXPECT_NEAR(p.position_m[0], 2.0, 1e-6);
          EXPECT_NEAR(p.position_m[1], 3.0, 1e-6);
          EXPECT_EQ(p.keyword, "help");
        } else {
          EXPECT_LT(std::min(std::hypot(p.position_m[0] - 3.0, p.position_m[1] - 0.5),
                             std::hypot(p.position_m[0] - 4.0, p.position_m[1] + 0.8)),
                    0.05)
              << described;
        }
      }
      EXPECT_TRUE(hidden) << described;
    } else {
      EXPECT_EQ(described, first);
    }
  }
}

TEST_F(PeopleMapProcessTest, KillNineLosesNothingAlreadyFound) {
  const std::string state = dir_ + "/people.yaml";
  auto node = StartNode(state);
  Play(0.0, 4.0);
  Spin(1.0);  // applied and saved
  const int before = last_.num_people;
  ASSERT_GE(before, 2) << Describe(last_) << node->Output();
  const std::string found_before = Describe(last_);
  node->Signal(SIGKILL);
  node->Wait(5);
  last_ = {};
  auto restarted = StartNode(state);
  Spin(1.0);  // the restarted node republishes what it resumed... once it has a time
  Play(4.0, 4.5);
  Spin(1.0);
  EXPECT_GE(last_.num_people, before) << Describe(last_) << restarted->Output();
  EXPECT_NE(restarted->Output().find("resumed"), std::string::npos) << restarted->Output();
  for (const auto& line : {std::string("#1 "), std::string("#2 ")}) {
    EXPECT_NE(Describe(last_).find(line), std::string::npos) << "lost " << line << " of\n"
                                                             << found_before;
  }
}

// SLAM publishes POSE late while it optimises. A detection made in a turn must be placed with
// the pose of its own time (interpolated once POSE catches up), not with the last pose known when
// it was released: here POSE lags the detections by 0.4 s while the robot swings +-0.5 rad at up
// to 1 rad/s, so the last known pose would be up to 0.2 rad off and put the person (3 m ahead)
// up to 0.6 m sideways.
TEST_F(PeopleMapProcessTest, ADetectionInATurnWaitsForThePoseOfItsTime) {
  auto node = StartNode("");
  const common::Rigid3d base_from_camera = common::RobotOptions().base_from_camera.ToRigid3d();
  const Eigen::Vector3d person(3.0, 0.0, 0.9);
  auto map_from_base = [](double t) {
    return common::Rigid3d(
        Eigen::Vector3d::Zero(),
        Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::sin(2 * t), Eigen::Vector3d::UnitZ())));
  };
  const double lag_s = 0.4;
  for (double t = 0; t < 6.0; t += 0.05) {
    const int64_t utime = 1'000'000'000 + static_cast<int64_t>(std::lround(t * 1e6));
    if (t >= lag_s - 1e-9) {  // the pose of 0.4 s ago
      const double tp = t - lag_s;
      const common::Rigid3d pose_now = map_from_base(tp);
      sarmap::pose_t pose{};
      pose.header.utime = 1'000'000'000 + static_cast<int64_t>(std::lround(tp * 1e6));
      pose.header.frame = "map";
      pose.child_frame = "base";
      const Eigen::Quaterniond q = pose_now.rotation();
      pose.orientation[0] = q.w();
      pose.orientation[3] = q.z();
      pose.covariance[0] = pose.covariance[7] = 0.0001;
      pose.covariance[35] = 0.0001;
      lcm_->publish("POSE", &pose);
    }
    const Eigen::Vector3d c = (map_from_base(t) * base_from_camera).inverse() * person;
    sarmap::people_detections_t seen{};
    seen.header.utime = utime;
    seen.header.frame = "camera";
    seen.detections.push_back(SeenAt(c));
    seen.num_detections = 1;
    lcm_->publish("PEOPLE_VISUAL", &seen);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    lcm_->handleTimeout(0);
  }
  Spin(1.0);
  node->Signal(SIGINT);
  ASSERT_EQ(node->Wait(10), 0) << node->Output();
  Spin(0.3);
  const std::string described = Describe(last_);
  ASSERT_EQ(last_.num_people, 1) << described << node->Output();
  EXPECT_LT(std::hypot(last_.people[0].position_m[0] - 3.0, last_.people[0].position_m[1]), 0.05)
      << described;
}

// One person seen once, then nobody in view while POSE goes on: POSE moves the node's clock, so
// the detection is applied and published without waiting for another detection (or the stop).
TEST_F(PeopleMapProcessTest, PoseAloneReleasesADetectionWhenNobodyElseIsSeen) {
  // One detection, reported as soon as it is placed.
  auto node = StartNode("", {"map.min_seen_detections=1"});
  const common::Rigid3d base_from_camera = common::RobotOptions().base_from_camera.ToRigid3d();
  for (int k = 0; k < 40; ++k) {
    const int64_t utime = 1'000'000'000 + k * 50'000;
    sarmap::pose_t pose{};
    pose.header.utime = utime;
    pose.header.frame = "map";
    pose.child_frame = "base";
    pose.orientation[0] = 1;
    pose.covariance[0] = pose.covariance[7] = pose.covariance[35] = 0.0001;
    lcm_->publish("POSE", &pose);
    if (k == 2) {
      sarmap::people_detections_t seen{};
      seen.header.utime = utime;
      seen.header.frame = "camera";
      seen.detections.push_back(
          SeenAt(base_from_camera.inverse() * Eigen::Vector3d(2.0, 0.0, 0.9)));
      seen.num_detections = 1;
      lcm_->publish("PEOPLE_VISUAL", &seen);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    lcm_->handleTimeout(0);
  }
  Spin(1.5);  // the node runs on; nothing else arrives
  const std::string described = Describe(last_);
  EXPECT_EQ(last_.num_people, 1) << described << node->Output();
  node->Signal(SIGINT);
  ASSERT_EQ(node->Wait(10), 0) << node->Output();
}

// One POSE stamped a year ahead (a skewed clock, a forged message) is dropped and counted: the
// detections after it are still placed and PEOPLE_MAP keeps sane stamps.
TEST_F(PeopleMapProcessTest, OneFarFuturePoseIsDroppedAndDetectionsGoOn) {
  int64_t pose_dropped = 0;
  struct StatusSink {
    int64_t* pose_dropped;
    void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const sarmap::node_status_t* m) {
      if (m->node_name != "sarmap-people-map") return;
      for (const auto& c : m->channels) {
        if (c.channel == "POSE") *pose_dropped = std::max(*pose_dropped, c.dropped_malformed);
      }
    }
  } status{&pose_dropped};
  lcm_->subscribe("NODE_STATUS", &StatusSink::OnStatus, &status);
  auto node = StartNode("");
  const auto detections = [&] {
    int n = 0;
    for (const auto& p : last_.people) n += p.num_detections;
    return n;
  };
  Play(0, 1.0);
  Spin(0.5);
  const int before = detections();
  sarmap::pose_t future{};
  future.header.utime = 1'000'000'000 + 1'000'000 + 365LL * 24 * 3600 * 1'000'000;
  future.header.frame = "map";
  future.child_frame = "base";
  future.position_m[0] = 0.5;
  future.orientation[0] = 1;
  future.covariance[0] = future.covariance[7] = 0.01;
  future.covariance[35] = 0.001;
  lcm_->publish("POSE", &future);
  Play(1.0, 5.0);
  Spin(1.5);
  const std::string described = Describe(last_);
  EXPECT_GE(last_.num_people, 2) << described << node->Output();
  // 5 Hz detections of two people for 4 s: most of the 40 placed.
  EXPECT_GT(detections(), before + 20) << described << node->Output();
  EXPECT_LT(last_.header.utime, 1'000'000'000 + 10'000'000) << described;
  EXPECT_GE(pose_dropped, 1);
  node->Signal(SIGINT);
  ASSERT_EQ(node->Wait(10), 0) << node->Output();
}

// A corrupt state file (here: a flipped bit) is refused with one clear line and set aside; the
// node starts with an empty map and goes on, instead of exiting at every restart.
TEST_F(PeopleMapProcessTest, CorruptStateFileGivesACleanStart) {
  const std::string state = dir_ + "/corrupt-state.yaml";
  {
    auto node = StartNode(state);
    Play(0, 3.0);
    Spin(1.0);
    node->Signal(SIGINT);
    ASSERT_EQ(node->Wait(10), 0) << node->Output();
  }
  std::string text;
  ASSERT_EQ(RunCapture({"cat", state}, &text), 0);
  const size_t digit = text.find_first_of("123456789", text.find("position_m"));
  ASSERT_NE(digit, std::string::npos) << text;
  text[digit] = text[digit] == '9' ? '8' : text[digit] + 1;
  {
    std::FILE* f = std::fopen(state.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  maps_ = 0;
  last_ = {};
  auto node = StartNode(state);
  Play(3.0, 6.0);
  Spin(1.0);
  EXPECT_TRUE(node->Running()) << node->Output();
  EXPECT_NE(node->Output().find("not resumed"), std::string::npos) << node->Output();
  EXPECT_GE(last_.num_people, 2) << Describe(last_) << node->Output();
  std::string ignored;
  EXPECT_EQ(RunCapture({"test", "-f", state + ".corrupt"}, &ignored), 0);
  node->Signal(SIGINT);
  ASSERT_EQ(node->Wait(10), 0) << node->Output();
}

}  // namespace
}  // namespace testing
}  // namespace sarmap
