#include "sim/simulator.h"

#include <gtest/gtest.h>

#include <functional>
#include <map>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/message_checks.h"
#include "sim/audio_sim.h"
#include "sim/floor_plan.h"

namespace sarmap {
namespace sim {
namespace {

struct ChannelLog {
  std::string type;
  std::vector<int64_t> utimes, seqs;
  std::vector<std::string> frames;
  std::vector<std::string> problems;
  size_t hash = 0;
};

// Collects every message per channel, checks it like a receiver would, and hashes its bytes.
struct CollectingSink : SimSink {
  std::map<std::string, ChannelLog> channels;
  template <class T>
  void Record(const std::string& channel, const T& msg) {
    ChannelLog& log = channels[channel];
    log.type = T::getTypeName();
    log.utimes.push_back(msg.header.utime);
    log.seqs.push_back(msg.header.seq);
    log.frames.push_back(msg.header.frame);
    const std::string problem = common::CheckMessage(msg);
    if (!problem.empty()) log.problems.push_back(problem);
    std::vector<uint8_t> bytes(msg.getEncodedSize());
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    log.hash = log.hash * 1000003u ^ std::hash<std::string>()(std::string(bytes.begin(), bytes.end()));
  }
  void Publish(const std::string& c, const sarmap::odometry_t& m) override { Record(c, m); }
  void Publish(const std::string& c, const sarmap::image_t& m) override {
    Record(c, m);
    std::string error;
    if (m.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16) {
      std::vector<uint16_t> depth;
      if (!common::DecodeDepthImage(m, &depth, &error)) channels[c].problems.push_back(error);
    } else {
      std::vector<uint8_t> rgb;
      if (!common::DecodeColorImage(m, &rgb, &error)) channels[c].problems.push_back(error);
    }
  }
  void Publish(const std::string& c, const sarmap::audio_frame_t& m) override { Record(c, m); }
  void Publish(const std::string& c, const sarmap::sim_truth_t& m) override {
    Record(c, m);
    truths.push_back(m);
  }
  void Publish(const std::string& c, const sarmap::occupancy_grid_t& m) override {
    Record(c, m);
    floors.push_back(m);
  }
  std::vector<sarmap::sim_truth_t> truths;
  std::vector<sarmap::occupancy_grid_t> floors;
};

SimOptions Options(const std::string& world) {
  SimOptions o;
  o.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + world;
  o.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  o.data_dir = SARMAP_DATA_DIR;
  return o;
}

// The world's options with the camera and the audio off and odometry noise along the path only
// (`trans_noise`, no rotation noise).
SimOptions OdometryOnly(const std::string& world, double trans_noise) {
  SimOptions o = Options(world);
  o.camera.enabled = false;
  o.audio.enabled = false;
  o.odometry.trans_noise = trans_noise;
  o.odometry.rot_noise = 0;
  o.odometry.rot_per_trans_rad_per_m = 0;
  return o;
}

void ExpectChannel(const CollectingSink& sink, const std::string& channel, const std::string& frame,
                   double rate_hz, double seconds) {
  SCOPED_TRACE(channel);
  auto it = sink.channels.find(channel);
  ASSERT_NE(it, sink.channels.end()) << "nothing published";
  const ChannelLog& log = it->second;
  EXPECT_NEAR(static_cast<double>(log.utimes.size()), rate_hz * seconds, 2.0);
  EXPECT_TRUE(log.problems.empty()) << log.problems[0];
  for (size_t k = 0; k < log.utimes.size(); ++k) {
    EXPECT_EQ(log.seqs[k], static_cast<int64_t>(k));
    EXPECT_EQ(log.frames[k], frame);
    EXPECT_GE(log.utimes[k], 1700000000000000);
    if (k > 0) {
      EXPECT_GT(log.utimes[k], log.utimes[k - 1]);
    }
  }
  if (!log.utimes.empty()) {
    EXPECT_LE(log.utimes.back(), 1700000000000000 + static_cast<int64_t>(seconds * 1e6) + 1);
  }
}

// Every scenario publishes every channel at its rate with valid headers.
class ScenarioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ScenarioTest, PublishesEveryChannelAtItsRate) {
  const SimOptions options = Options(GetParam());
  Simulator sim(LoadSetup(options, ""));
  for (const auto& w : sim.warnings()) std::printf("warning: %s\n", w.c_str());
  CollectingSink sink;
  const double seconds = 2.0;
  sim.AdvanceTo(seconds, &sink);
  ExpectChannel(sink, "ODOM", "odom", options.odometry.rate_hz, seconds);
  ExpectChannel(sink, "DEPTH", "camera", options.camera.rate_hz, seconds);
  ExpectChannel(sink, "RGB", "camera", options.camera.rate_hz, seconds);
  ExpectChannel(sink, "AUDIO", "mic_array", 16000.0 / options.audio.block_samples, seconds);
  ExpectChannel(sink, "SIM_TRUTH", "map", options.truth_rate_hz, seconds);
  EXPECT_EQ(sink.channels.size(), 6u);  // and SIM_FLOOR
  ASSERT_FALSE(sink.truths.empty());
  EXPECT_EQ(sink.truths.back().num_people, static_cast<int>(sim.world().people.size()));
  EXPECT_EQ(sink.truths.back().num_sources, static_cast<int>(sim.world().sources.size()));
}

INSTANTIATE_TEST_SUITE_P(Worlds, ScenarioTest,
                         ::testing::Values("lab_lit.yaml", "lab_dark.yaml", "corridor_glass.yaml",
                                           "open_area_sound.yaml"),
                         [](const auto& info) { return info.param.substr(0, info.param.find('.')); });

TEST(SimulatorTest, LabTruthShowsTheHiddenPersonCallingAndTheOthersInView) {
  Simulator sim(LoadSetup(Options("lab_lit.yaml"), ""));
  CollectingSink sink;
  sim.AdvanceTo(2.0, &sink);  // carol calls "help" from t = 1 s
  std::map<std::string, sarmap::sim_person_t> people;
  bool carol_called = false;
  for (const auto& truth : sink.truths) {
    for (const auto& p : truth.people) {
      if (p.name == "carol") carol_called = carol_called || p.calling;
    }
  }
  for (const auto& p : sink.truths.back().people) people[p.name] = p;
  EXPECT_TRUE(people["alice"].visible_to_camera);
  EXPECT_TRUE(people["bob"].visible_to_camera);
  EXPECT_FALSE(people["carol"].visible_to_camera);  // behind the cabinet
  EXPECT_TRUE(carol_called);
  EXPECT_EQ(static_cast<int>(people["carol"].posture), static_cast<int>(sarmap::sim_person_t::POSTURE_SITTING));
}

// The reachable floor goes out at start and every 5 simulated seconds, compressed, in the
// world frame, and decodes to ReachableFloor's grid.
TEST(SimulatorTest, PublishesTheReachableFloorAtStartAndEveryFiveSeconds) {
  SimOptions o = Options("lab_lit.yaml");
  o.camera.enabled = false;
  o.audio.enabled = false;
  Simulator sim(LoadSetup(o, ""));
  CollectingSink sink;
  sim.AdvanceTo(11.0, &sink);
  ASSERT_EQ(sink.floors.size(), 3u);  // t = 0, 5, 10
  EXPECT_TRUE(sink.channels["SIM_FLOOR"].problems.empty());
  EXPECT_EQ(sink.channels["SIM_FLOOR"].type, "occupancy_grid_t");
  const sarmap::occupancy_grid_t& msg = sink.floors.front();
  EXPECT_LE(msg.header.utime, 1700000000000000 + 10000);
  EXPECT_NEAR((sink.floors[1].header.utime - msg.header.utime) * 1e-6, 5.0, 0.01);  // first after one step
  EXPECT_EQ(msg.header.frame, "map");
  EXPECT_EQ(msg.origin_yaw_rad, 0.0);
  EXPECT_EQ(msg.compression, +sarmap::occupancy_grid_t::COMPRESSION_ZSTD);
  std::vector<int8_t> cells;
  std::string error;
  ASSERT_TRUE(common::DecodeOccupancyGrid(msg, &cells, &error)) << error;
  const GridMap expected = ReachableFloor(sim.world(), o.robot_radius_m, 0.05);
  EXPECT_EQ(msg.width, expected.width);
  EXPECT_EQ(msg.origin_x_m, expected.origin_x_m);
  EXPECT_EQ(cells, expected.cells);
  // The lab is about 8 x 6 m: most of it is reachable floor.
  const double area = FloorArea(expected);
  std::printf("lab_lit reachable floor: %.1f m^2, SIM_FLOOR %d bytes for %d cells\n", area, msg.size,
              msg.width * msg.height);
  EXPECT_GT(area, 30.0);
  EXPECT_LT(area, 48.0);
  EXPECT_LT(msg.size, 20000);
}

TEST(SimulatorTest, OtherArraysAndAnAsynchronousArray) {
  SimOptions o = Options("lab_lit.yaml");
  o.camera.enabled = false;
  o.audio.mic_array = std::string(SARMAP_SOURCE_DIR) + "/config/arrays/cube8.yaml";
  {
    Simulator sim(LoadSetup(o, ""));
    CollectingSink sink;
    sim.AdvanceTo(1.0, &sink);
    ExpectChannel(sink, "AUDIO", "mic_array", 31.25, 1.0);
  }
  // Each microphone its own sound card: AUDIO_<DEVICE> channels.
  o.audio.mic_array = std::string(SARMAP_SOURCE_DIR) + "/config/arrays/async6.yaml";
  o.audio.asynchronous = true;
  Simulator sim(LoadSetup(o, ""));
  CollectingSink sink;
  sim.AdvanceTo(1.5, &sink);
  for (int m = 0; m < 6; ++m) {
    const std::string channel = "AUDIO_ASYNC6" + std::to_string(m);
    ASSERT_TRUE(sink.channels.count(channel)) << channel;
    const ChannelLog& log = sink.channels.at(channel);
    EXPECT_GE(log.utimes.size(), 40u) << channel;  // 1.5 s minus its start offset, at 31.25 Hz
    EXPECT_TRUE(log.problems.empty()) << channel;
    for (size_t k = 0; k < log.seqs.size(); ++k) EXPECT_EQ(log.seqs[k], static_cast<int64_t>(k));
  }
  EXPECT_FALSE(sink.channels.count("AUDIO"));
}

TEST(SimulatorTest, SameSeedSameRunOtherSeedOtherRun) {
  auto run = [](int64_t seed) {
    SimOptions o = Options("lab_lit.yaml");
    o.seed = seed;
    o.camera.rate_hz = 5;  // keep the test short
    Simulator sim(LoadSetup(o, ""));
    CollectingSink sink;
    sim.AdvanceTo(1.0, &sink);
    std::map<std::string, size_t> hashes;
    for (const auto& [channel, log] : sink.channels) hashes[channel] = log.hash;
    return hashes;
  };
  const auto a = run(11), b = run(11), c = run(12);
  EXPECT_EQ(a, b);
  for (const char* channel : {"ODOM", "DEPTH", "RGB", "AUDIO"}) {
    EXPECT_NE(a.at(channel), c.at(channel)) << channel;
  }
}

TEST(SimulatorTest, FollowsVelocityCommandsAndStopsWhenTheyStop) {
  SimOptions o = OdometryOnly("open_area_sound.yaml", 0);
  o.drive = "cmd_vel";
  Simulator sim(LoadSetup(o, ""));
  CollectingSink sink;
  sim.SetVelocityCommand(0.4, 0.0);
  for (int k = 1; k <= 10; ++k) {  // commands at 10 Hz for 1 s
    sim.AdvanceTo(0.1 * k, &sink);
    sim.SetVelocityCommand(0.4, 0.0);
  }
  EXPECT_NEAR(sim.map_from_base().translation().x(), 0.4, 0.01);
  sim.AdvanceTo(3.0, &sink);  // no more commands: stops after the timeout
  EXPECT_NEAR(sim.map_from_base().translation().x(), 0.4 + 0.4 * o.cmd_vel_timeout_s, 0.02);
  // Noise-free odometry follows the truth.
  const ChannelLog& odom = sink.channels.at("ODOM");
  EXPECT_FALSE(odom.utimes.empty());
}

// Translational noise: the odometry's distance error after d metres has std
// trans_noise * sqrt(d), whatever the ODOM rate.
TEST(SimulatorTest, OdometryNoiseGrowsAsConfigured) {
  for (double rate : {10.0, 50.0}) {
    double sum2 = 0;
    const int runs = 60;
    for (int seed = 1; seed <= runs; ++seed) {
      SimOptions o = OdometryOnly("open_area_sound.yaml", 0.05);
      o.drive = "cmd_vel";
      o.seed = seed;
      o.odometry.rate_hz = rate;
      Simulator sim(LoadSetup(o, ""));
      struct LastOdom : SimSink {
        sarmap::odometry_t last;
        void Publish(const std::string&, const sarmap::odometry_t& m) override { last = m; }
        void Publish(const std::string&, const sarmap::image_t&) override {}
        void Publish(const std::string&, const sarmap::audio_frame_t&) override {}
        void Publish(const std::string&, const sarmap::sim_truth_t&) override {}
        void Publish(const std::string&, const sarmap::occupancy_grid_t&) override {}
      } sink;
      for (int k = 1; k <= 40; ++k) {  // 0.5 m/s for 4 s: 2 m
        sim.SetVelocityCommand(0.5, 0.0);
        sim.AdvanceTo(0.1 * k, &sink);
      }
      const double error = sink.last.position_m[0] - sim.map_from_base().translation().x();
      sum2 += error * error;
    }
    const double std_dev = std::sqrt(sum2 / runs), expected = 0.05 * std::sqrt(2.0);
    std::printf("ODOM %.0f Hz: distance error std after 2 m %.4f m (model %.4f)\n", rate, std_dev, expected);
    EXPECT_NEAR(std_dev, expected, 0.3 * expected);
  }
}

TEST(SimulatorTest, OdometryNoiseAndSlipMakeOdometryDrift) {
  SimOptions o = OdometryOnly("open_area_sound.yaml", 0);
  o.odometry.slip = 0.1;  // the base moves 10 % less than the wheels say
  Simulator sim(LoadSetup(o, ""));
  struct OdomSink : CollectingSink {
    sarmap::odometry_t last;
    void Publish(const std::string& c, const sarmap::odometry_t& m) override {
      last = m;
      CollectingSink::Publish(c, m);
    }
  } sink;
  sim.AdvanceTo(8.0, &sink);  // along the first side of the square path
  const double truth_x = sim.map_from_base().translation().x();
  EXPECT_GT(truth_x, 1.0);
  EXPECT_NEAR(sink.last.position_m[0], truth_x / 0.9, 0.02);
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
