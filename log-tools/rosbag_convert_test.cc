// ROS bags in and out: a bag the test writes with every supported type goes through
// sarmap-log import-rosbag and comes out with the right channels, counts and geometry;
// export-rosbag writes POSE, MAP and PEOPLE_MAP as ROS messages that import back unchanged; a
// bag rebuilt from the Intel CARMEN log gives sarmap-slam-offline the same relations error as
// the CARMEN log itself.
#include "log-tools/rosbag_convert.h"

#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>
#include <sys/wait.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "common/decode.h"
#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/robot_config.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/ros_audio_msgs.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/image_t.hpp"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"
#include "slam/carmen.h"
#include "slam/relations.h"

// A LaserScan cut short after its header: what a truncated recording leaves.
struct TruncatedScan {
  std_msgs::Header header;
};
namespace ros {
namespace message_traits {
template <>
struct MD5Sum<TruncatedScan> {
  static const char* value() { return MD5Sum<sensor_msgs::LaserScan>::value(); }
  static const char* value(const TruncatedScan&) { return value(); }
};
template <>
struct DataType<TruncatedScan> {
  static const char* value() { return DataType<sensor_msgs::LaserScan>::value(); }
  static const char* value(const TruncatedScan&) { return value(); }
};
template <>
struct Definition<TruncatedScan> {
  static const char* value() { return Definition<sensor_msgs::LaserScan>::value(); }
  static const char* value(const TruncatedScan&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<TruncatedScan> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.header);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace serialization
}  // namespace ros

namespace sarmap {
namespace logtools {
namespace {

const std::string kBin = SARMAP_BIN_DIR;
const std::string kConfig = std::string(SARMAP_SOURCE_DIR) + "/config/rosbag.yaml";

// Runs a command; stdout+stderr in *out, the exit code returned.
int RunCommand(const std::string& cmd, std::string* out) {
  out->clear();
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[1024];
  while (fgets(buf, sizeof(buf), p)) *out += buf;
  const int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

ros::Time T(double s) { return ros::Time(s); }

std_msgs::Header Header(double s, const std::string& frame) {
  std_msgs::Header h;
  h.stamp = T(s);
  h.frame_id = frame;
  return h;
}

geometry_msgs::TransformStamped Transform(double s, const std::string& parent,
                                          const std::string& child, double x, double y, double z,
                                          double yaw) {
  geometry_msgs::TransformStamped t;
  t.header = Header(s, parent);
  t.child_frame_id = child;
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.translation.z = z;
  t.transform.rotation.w = std::cos(yaw / 2);
  t.transform.rotation.z = std::sin(yaw / 2);
  return t;
}

sensor_msgs::CameraInfo Info(double s, const std::string& frame, int w, int h) {
  sensor_msgs::CameraInfo info;
  info.header = Header(s, frame);
  info.width = w;
  info.height = h;
  info.distortion_model = "plumb_bob";
  info.D = {0.1, -0.2, 0.001, 0.002, 0.05};
  info.K = {525, 0, 319.5, 0, 526, 239.5, 0, 0, 1};
  return info;
}

// Every event of an LCM log by channel.
std::map<std::string, std::vector<std::vector<uint8_t>>> ReadLog(const std::string& path) {
  std::map<std::string, std::vector<std::vector<uint8_t>>> out;
  lcm::LogFile log(path, "r");
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* d = static_cast<const uint8_t*>(ev->data);
    out[ev->channel].emplace_back(d, d + ev->datalen);
  }
  return out;
}

template <class T>
T Decode(const std::vector<uint8_t>& data) {
  T msg;
  EXPECT_TRUE(common::DecodeMessage(data.data(), data.size(), &msg));
  return msg;
}

// A bag with every type import-rosbag converts, and one it does not.
void WriteEveryTypeBag(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  tf2_msgs::TFMessage statics;
  statics.transforms = {Transform(0, "base_link", "laser", 0.2, 0.01, 0.3, 0.1),
                        Transform(0, "base_link", "camera_link", 0.1, 0, 0.55, 0),
                        Transform(0, "camera_link", "camera_depth_optical_frame", 0, 0, 0, 0),
                        Transform(0, "base_link", "mic_array", 0.05, 0, 0.6, M_PI / 2)};
  // Optical frame: z forward, x right (a rotation on top of camera_link).
  auto& optical = statics.transforms[2].transform.rotation;
  optical.w = 0.5;
  optical.x = -0.5;
  optical.y = 0.5;
  optical.z = -0.5;
  bag.write("/tf_static", T(100), statics);
  bag.write("/camera/depth/camera_info", T(100), Info(100, "camera_depth_optical_frame", 4, 3));
  bag.write("/camera/rgb/camera_info", T(100), Info(100, "camera_rgb_optical_frame", 4, 3));
  bag.write("/camera/depth_registered/camera_info", T(100),
            Info(100, "camera_rgb_optical_frame", 4, 3));
  audio_common_msgs::AudioInfo ainfo;
  ainfo.channels = 2;
  ainfo.sample_rate = 48000;
  ainfo.sample_format = "S16LE";
  ainfo.coding_format = "wave";
  bag.write("/audio/audio_info", T(100), ainfo);
  for (int i = 0; i < 5; ++i) {
    sensor_msgs::LaserScan s;
    s.header = Header(100.1 + 0.1 * i, "laser");
    s.angle_min = -2.0f;
    s.angle_max = 2.0f;
    s.angle_increment = 4.0f / 399;
    s.range_min = 0.1f;
    s.range_max = 20.0f;
    s.ranges.assign(400, 1.5f + i);
    s.intensities.assign(400, 7.0f);
    bag.write("/scan", T(100.15 + 0.1 * i), s);
  }
  for (int i = 0; i < 10; ++i) {
    nav_msgs::Odometry o;
    o.header = Header(100 + 0.05 * i, "odom");
    o.child_frame_id = "base_link";
    o.pose.pose.position.x = 0.1 * i;
    o.pose.pose.orientation.w = std::cos(0.05 * i);
    o.pose.pose.orientation.z = std::sin(0.05 * i);
    o.twist.twist.linear.x = 2.0;
    bag.write("/odom", T(100.01 + 0.05 * i), o);
  }
  for (int i = 0; i < 4; ++i) {
    tf2_msgs::TFMessage tf;
    tf.transforms = {Transform(100 + 0.1 * i, "odom", "base_link", 0.3 * i, 0, 0, 0.2 * i),
                     Transform(100 + 0.1 * i, "map", "odom", 5, 5, 0, 0)};  // not odometry
    bag.write("/tf", T(100.02 + 0.1 * i), tf);
  }
  for (int i = 0; i < 2; ++i) {
    sensor_msgs::Image d;
    d.header = Header(100.2 + i, "camera_depth_optical_frame");
    d.width = 4;
    d.height = 3;
    d.encoding = "16UC1";
    d.step = 10;  // rows padded by 2 bytes
    d.data.assign(30, 0);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        const uint16_t mm = static_cast<uint16_t>(1000 + 100 * r + c + i);
        std::memcpy(&d.data[r * 10 + 2 * c], &mm, 2);
      }
    }
    bag.write("/camera/depth/image_raw", T(100.25 + i), d);
    sensor_msgs::Image f;
    f.header = Header(100.3 + i, "camera_rgb_optical_frame");
    f.width = 4;
    f.height = 3;
    f.encoding = "32FC1";
    f.step = 16;
    f.data.assign(48, 0);
    for (int k = 0; k < 12; ++k) {
      const float m = k == 5 ? std::nanf("") : 1.234f + 0.001f * k;
      std::memcpy(&f.data[4 * k], &m, 4);
    }
    bag.write("/camera/depth_registered/image", T(100.35 + i), f);
  }
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::Image c;
    c.header = Header(100.4 + i, "camera_rgb_optical_frame");
    c.width = 4;
    c.height = 3;
    c.encoding = "rgb8";
    c.step = 12;
    c.data.assign(36, static_cast<uint8_t>(10 * i));
    bag.write("/camera/rgb/image_color", T(100.45 + i), c);
  }
  {
    // image_transport's JPEG beside the raw colour image: 16 x 8, red above, blue below.
    std::vector<uint8_t> rgb(16 * 8 * 3, 0);
    for (int k = 0; k < 16 * 8; ++k) rgb[3 * k + (k < 64 ? 0 : 2)] = 255;
    const auto jpeg =
        common::MakeColorImage(header_t{}, camera_intrinsics_t{}, rgb.data(), 16, 8, 90);
    sensor_msgs::CompressedImage c;
    c.header = Header(100.48, "camera_rgb_optical_frame");
    c.format = "rgb8; jpeg compressed bgr8";
    c.data = jpeg.data;
    bag.write("/camera/rgb/image_color/compressed", T(100.48), c);
  }
  for (int i = 0; i < 3; ++i) {
    audio_common_msgs::AudioData a;  // 2 channels, 160 frames
    for (int k = 0; k < 320; ++k) {
      const int16_t v = static_cast<int16_t>(k - 1000 * i);
      a.data.push_back(static_cast<uint8_t>(v & 0xff));
      a.data.push_back(static_cast<uint8_t>((v >> 8) & 0xff));
    }
    bag.write("/audio/audio", T(100.5 + 0.01 * i), a);
    if (i < 2) {
      audio_common_msgs::AudioDataStamped st;
      st.header = Header(100.6 + 0.01 * i, "mic_array");
      st.audio.data.assign(64, 0);
      bag.write("/mic/audio_stamped", T(100.61 + 0.01 * i), st);
    }
  }
  geometry_msgs::PoseStamped pose;
  pose.header = Header(100.7, "map");
  pose.pose.position.x = 1.5;
  pose.pose.orientation.w = 1;
  bag.write("/sarmap/pose", T(100.7), pose);
  nav_msgs::OccupancyGrid grid;
  grid.header = Header(100.8, "map");
  grid.info.resolution = 0.05f;
  grid.info.width = 3;
  grid.info.height = 2;
  grid.info.origin.position.x = -1;
  grid.info.origin.position.y = -2;
  grid.info.origin.orientation.w = 1;
  grid.data = {-1, 0, 100, 0, 0, -1};
  bag.write("/map", T(100.8), grid);
  visualization_msgs::MarkerArray people;
  visualization_msgs::Marker mk;
  mk.header = Header(100.9, "map");
  mk.ns = "people";
  mk.id = 7;
  mk.type = visualization_msgs::Marker::SPHERE;
  mk.pose.position.x = 2;
  mk.pose.position.y = 3;
  mk.scale.x = mk.scale.y = 0.4;
  mk.scale.z = 0.2;
  mk.text = "cues=5 confidence=0.75 keyword=help";
  people.markers.push_back(mk);
  bag.write("/sarmap/people", T(100.9), people);
  std_msgs::String note;
  note.data = "not converted";
  bag.write("/diagnostics_text", T(100.95), note);
  bag.close();
}

TEST(RosbagConvertTest, EveryTypeImportsWithItsCountAndGeometry) {
  const std::string dir = ::testing::TempDir();
  const std::string bag = dir + "/every_type.bag", log = dir + "/every_type.lcmlog";
  WriteEveryTypeBag(bag);
  std::string out;
  ASSERT_EQ(
      RunCommand(kBin + "/sarmap-log-import-rosbag " + bag + " -o " + log + " --config " + kConfig +
                     " --set 'topics=[/mic/audio_stamped=AUDIO_MIC, "
                     "/camera/rgb/image_color/compressed=RGB_JPEG]'",
                 &out),
      0)
      << out;
  EXPECT_NE(out.find("/diagnostics_text"), std::string::npos) << out;
  EXPECT_NE(out.find("unsupported type, skipped"), std::string::npos) << out;
  // sarmap-log info: each channel with its count.
  ASSERT_EQ(RunCommand(kBin + "/sarmap-log-info --json " + log + " 2>/dev/null", &out), 0) << out;
  const auto info = nlohmann::json::parse(out);
  std::map<std::string, std::pair<std::string, int64_t>> channels;
  std::map<std::string, std::string> geometry;
  for (const auto& c : info["channels"]) {
    channels[c["channel"]] = {c["type"], c["count"]};
    geometry[c["channel"]] = c["geometry"];
  }
  const std::map<std::string, std::pair<std::string, int64_t>> expected = {
      {"SCAN", {"laser_scan_t", 5}},       {"ODOM", {"odometry_t", 14}},
      {"DEPTH", {"image_t", 4}},           {"RGB", {"image_t", 3}},
      {"RGB_JPEG", {"image_t", 1}},        {"AUDIO", {"audio_frame_t", 3}},
      {"AUDIO_MIC", {"audio_frame_t", 2}}, {"POSE", {"pose_t", 1}},
      {"MAP", {"occupancy_grid_t", 1}},    {"PEOPLE_MAP", {"people_map_t", 1}}};
  EXPECT_EQ(channels, expected) << out;
  EXPECT_EQ(geometry["SCAN"],
            "400 beams -114.59..114.59 deg step 0.5744 deg, 0.10-20.00 m, intensities");
  EXPECT_EQ(geometry["DEPTH"], "4x3 depth u16 zstd, fx 525.0 fy 526.0 cx 319.5 cy 239.5");
  EXPECT_EQ(geometry["RGB"], "4x3 rgb8, fx 525.0 fy 526.0 cx 319.5 cy 239.5");
  EXPECT_EQ(geometry["AUDIO"], "2 ch, 48000 Hz, 160 samples");
  EXPECT_EQ(geometry["MAP"], "3x2 cells of 0.050 m, origin (-1.00, -2.00) m");

  const auto events = ReadLog(log);
  // Each scan's own geometry.
  const auto scan = Decode<laser_scan_t>(events.at("SCAN")[2]);
  EXPECT_EQ(scan.header.utime, 100300000);
  EXPECT_EQ(scan.header.frame, "laser");
  EXPECT_FLOAT_EQ(scan.angle_min_rad, -2.0f);
  EXPECT_FLOAT_EQ(scan.angle_increment_rad, 4.0f / 399);
  EXPECT_FLOAT_EQ(scan.range_min_m, 0.1f);
  EXPECT_FLOAT_EQ(scan.range_max_m, 20.0f);
  ASSERT_EQ(scan.num_ranges, 400);
  EXPECT_FLOAT_EQ(scan.ranges_m[0], 3.5f);
  EXPECT_EQ(scan.num_intensities, 400);
  // Odometry: nav_msgs first in time, /tf odom -> base_link among them; frames renamed.
  int from_tf = 0;
  for (const auto& e : events.at("ODOM")) {
    const auto o = Decode<odometry_t>(e);
    EXPECT_EQ(o.header.frame, "odom");
    EXPECT_EQ(o.child_frame, "base");
    from_tf += o.linear_velocity_mps[0] == 0;
  }
  EXPECT_EQ(from_tf, 4);
  // Depth: 16UC1 with padded rows, 32FC1 in metres, both in millimetres with intrinsics.
  std::vector<uint16_t> mm;
  std::string error;
  int depth16 = 0, depth32 = 0;
  for (const auto& e : events.at("DEPTH")) {
    const auto d = Decode<image_t>(e);
    ASSERT_TRUE(common::DecodeDepthImage(d, &mm, &error)) << error;
    ASSERT_EQ(mm.size(), 12u);
    EXPECT_DOUBLE_EQ(d.intrinsics.fx, 525);
    EXPECT_DOUBLE_EQ(d.intrinsics.cy, 239.5);
    EXPECT_EQ(d.intrinsics.distortion_model, +camera_intrinsics_t::DISTORTION_BROWN_CONRADY);
    EXPECT_DOUBLE_EQ(d.depth_unit_m, 0.001);
    if (d.header.frame == "camera_depth_optical_frame") {
      EXPECT_EQ(mm[2 * 4 + 3], 1000 + 200 + 3 + depth16);
      ++depth16;
    } else {
      EXPECT_EQ(mm[0], 1234);
      EXPECT_EQ(mm[11], 1245);
      EXPECT_EQ(mm[5], 0);  // NaN: no reading
      ++depth32;
    }
  }
  EXPECT_EQ(depth16, 2);
  EXPECT_EQ(depth32, 2);
  const auto rgb = Decode<image_t>(events.at("RGB")[1]);
  EXPECT_EQ(rgb.pixel_format, +image_t::PIXEL_RGB8);
  EXPECT_EQ(rgb.width, 4);
  ASSERT_EQ(rgb.size, 36);
  EXPECT_EQ(rgb.data[35], 10);
  // The JPEG as it came, its size from its header, the colour camera's intrinsics.
  const auto jpeg = Decode<image_t>(events.at("RGB_JPEG")[0]);
  EXPECT_EQ(jpeg.compression, +image_t::COMPRESSION_JPEG);
  EXPECT_EQ(jpeg.width, 16);
  EXPECT_EQ(jpeg.height, 8);
  EXPECT_DOUBLE_EQ(jpeg.intrinsics.fx, 525);
  std::vector<uint8_t> decoded;
  ASSERT_TRUE(common::DecodeColorImage(jpeg, &decoded, &error)) << error;
  EXPECT_GT(decoded[0], 200);                     // red above
  EXPECT_GT(decoded[3 * (16 * 7 + 8) + 2], 200);  // blue below
  // Audio: format from AudioInfo, contiguous sample indices.
  const auto a = Decode<audio_frame_t>(events.at("AUDIO")[2]);
  EXPECT_EQ(a.sample_rate_hz, 48000);
  EXPECT_EQ(a.num_channels, 2);
  EXPECT_EQ(a.num_samples, 160);
  EXPECT_EQ(a.first_sample_index, 320);
  EXPECT_EQ(a.samples[3], 3 - 2000);
  const auto stamped = Decode<audio_frame_t>(events.at("AUDIO_MIC")[1]);
  EXPECT_EQ(stamped.header.utime, 100610000);
  EXPECT_EQ(stamped.sample_rate_hz, 16000);  // no AudioInfo in /mic: the options
  EXPECT_EQ(stamped.num_samples, 32);
  const auto map = Decode<occupancy_grid_t>(events.at("MAP")[0]);
  EXPECT_EQ(map.width, 3);
  EXPECT_DOUBLE_EQ(map.origin_y_m, -2);
  EXPECT_EQ(static_cast<int8_t>(map.data[2]), 100);
  const auto people = Decode<people_map_t>(events.at("PEOPLE_MAP")[0]);
  ASSERT_EQ(people.num_people, 1);
  EXPECT_EQ(people.people[0].id, 7);
  EXPECT_EQ(people.people[0].cues, 5);
  EXPECT_EQ(people.people[0].keyword, "help");
  EXPECT_NEAR(people.people[0].covariance[0], 0.04, 1e-9);

  // /tf_static in config/robot.yaml's form.
  const auto robot = common::LoadRobot(dir + "/every_type.robot.yaml");
  EXPECT_NEAR(robot.base_from_mic_array.x_m, 0.05, 1e-9);
  EXPECT_NEAR(robot.base_from_mic_array.yaw_rad, M_PI / 2, 1e-9);
  const auto base_from_camera = robot.base_from_camera.ToRigid3d();
  EXPECT_NEAR(base_from_camera.translation().z(), 0.55, 1e-9);
  // The optical frame looks forward: its z axis is the base's x axis.
  EXPECT_NEAR(
      (base_from_camera.rotation() * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 0,
      1e-9);
  std::ifstream extrinsics(dir + "/every_type.robot.yaml");
  std::stringstream text;
  text << extrinsics.rdbuf();
  EXPECT_NE(text.str().find("slam.scan.laser_x_m=0.200000"), std::string::npos) << text.str();
}

TEST(RosbagConvertTest, UnsupportedTypeNamedInTheConfigIsAnErrorListingTheBag) {
  const std::string dir = ::testing::TempDir();
  const std::string bag = dir + "/unsupported.bag";
  WriteEveryTypeBag(bag);
  std::string out;
  EXPECT_EQ(RunCommand(kBin + "/sarmap-log-import-rosbag " + bag + " -o " + dir +
                           "/unsupported.lcmlog --config " + kConfig +
                           " --set 'topics=[/diagnostics_text=DIAG]'",
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("/diagnostics_text (mapped to DIAG) has type std_msgs/String"),
            std::string::npos)
      << out;
  // The listing names everything the bag holds.
  for (const char* t : {"/scan", "sensor_msgs/LaserScan", "/audio/audio",
                        "audio_common_msgs/AudioData", "/tf_static", "tf2_msgs/TFMessage"}) {
    EXPECT_NE(out.find(t), std::string::npos) << t << "\n" << out;
  }
  // A bag with nothing convertible.
  {
    rosbag::Bag only(dir + "/only_strings.bag", rosbag::bagmode::Write);
    std_msgs::String s;
    only.write("/chatter", T(1), s);
  }
  EXPECT_EQ(RunCommand(
                kBin + "/sarmap-log-import-rosbag " + dir + "/only_strings.bag --config " + kConfig,
                &out),
            1)
      << out;
  EXPECT_NE(out.find("nothing to import"), std::string::npos) << out;
  EXPECT_NE(out.find("/chatter"), std::string::npos) << out;
  EXPECT_EQ(
      RunCommand(kBin + "/sarmap-log-import-rosbag " + dir + "/missing.bag --config " + kConfig,
                 &out),
      1)
      << out;
  EXPECT_NE(out.find("cannot read ROS bag"), std::string::npos) << out;
}

TEST(RosbagConvertTest, UndecodableMessagesAreSkippedAndCounted) {
  const std::string dir = ::testing::TempDir();
  const std::string bag_path = dir + "/truncated.bag", log = dir + "/truncated.lcmlog";
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    sensor_msgs::LaserScan s;
    s.header = Header(1, "laser");
    s.angle_increment = 0.01f;
    s.range_max = 10;
    s.ranges.assign(100, 2.0f);
    bag.write("/scan", T(1), s);
    TruncatedScan cut;
    cut.header = Header(1.1, "laser");
    bag.write("/scan", T(1.1), cut);
    s.header = Header(1.2, "laser");
    bag.write("/scan", T(1.2), s);
  }
  std::string out;
  ASSERT_EQ(RunCommand(kBin + "/sarmap-log-import-rosbag " + bag_path + " -o " + log +
                           " --config " + kConfig,
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("undecodable messages skipped"), std::string::npos) << out;
  EXPECT_NE(out.find("-> SCAN  1 undecodable, skipped"), std::string::npos) << out;
  const auto events = ReadLog(log);
  ASSERT_EQ(events.at("SCAN").size(), 2u);
  EXPECT_EQ(Decode<laser_scan_t>(events.at("SCAN")[1]).header.utime, 1'200'000);
}

mapped_person_t Person(int64_t id, double x, double y, int8_t cues) {
  mapped_person_t p{};
  p.id = id;
  p.position_m[0] = x;
  p.position_m[1] = y;
  p.covariance[0] = 0.09;
  p.covariance[4] = 0.16;
  p.covariance[8] = 0.01;
  p.confidence = 0.5f;
  p.cues = cues;
  p.num_detections = 4;
  p.people_count = 1;
  p.keyword = id == 1 ? "help" : "";
  p.sound_source_id = -1;
  return p;
}

TEST(RosbagConvertTest, ExportWritesStandardMessagesThatImportBack) {
  const std::string dir = ::testing::TempDir();
  const std::string log = dir + "/rosbag_export.lcmlog", bag = dir + "/rosbag_export.bag",
                    back = dir + "/rosbag_export_back.lcmlog";
  {
    logtools::LcmLogWriter f(log);
    for (int i = 0; i < 3; ++i) {
      pose_t p{};
      p.header.utime = 5'000'000 + 100'000 * i;
      p.header.frame = "map";
      p.child_frame = "base";
      p.position_m[0] = 0.5 * i;
      p.position_m[1] = -0.25 * i;
      p.orientation[0] = std::cos(0.1 * i);
      p.orientation[3] = std::sin(0.1 * i);
      p.node_id = -1;
      f.Write("POSE", p, p.header.utime + 1000);
    }
    for (int i = 0; i < 2; ++i) {
      occupancy_grid_t g{};
      g.header.utime = 5'000'000 + 500'000 * i;
      g.header.frame = "map";
      g.resolution_m = 0.05;
      g.width = 20;
      g.height = 10;
      g.origin_x_m = -0.5;
      g.origin_y_m = -0.25;
      g.origin_yaw_rad = 0.0;
      g.compression = occupancy_grid_t::COMPRESSION_NONE;
      for (int k = 0; k < 200; ++k)
        g.data.push_back(static_cast<uint8_t>(k % 3 == 0 ? -1 : k % 3 == 1 ? 0 : 100));
      g.size = 200;
      f.Write("MAP", g, g.header.utime + 2000);
    }
    for (int i = 0; i < 2; ++i) {
      people_map_t pm{};
      pm.header.utime = 5'100'000 + 500'000 * i;
      pm.header.frame = "map";
      pm.people.push_back(
          Person(1, 1.0, 2.0, mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_HEARD));
      if (i == 0) pm.people.push_back(Person(2, -1.0, 0.5, mapped_person_t::CUE_HEARD));
      pm.num_people = static_cast<int32_t>(pm.people.size());
      f.Write("PEOPLE_MAP", pm, pm.header.utime + 3000);
    }
  }
  std::string out;
  ASSERT_EQ(
      RunCommand(kBin + "/sarmap-log-export-rosbag " + log + " -o " + bag + " --config " + kConfig,
                 &out),
      0)
      << out;

  // Standard ROS messages with the right types and MD5 sums.
  {
    rosbag::Bag b(bag, rosbag::bagmode::Read);
    rosbag::View view(b);
    std::map<std::string, std::string> types, md5;
    for (const auto* c : view.getConnections()) {
      types[c->topic] = c->datatype;
      md5[c->topic] = c->md5sum;
    }
    EXPECT_EQ(types["/sarmap/pose"], "geometry_msgs/PoseStamped");
    EXPECT_EQ(types["/map"], "nav_msgs/OccupancyGrid");
    EXPECT_EQ(types["/sarmap/people"], "visualization_msgs/MarkerArray");
    EXPECT_EQ(md5["/map"], ros::message_traits::MD5Sum<nav_msgs::OccupancyGrid>::value());
    std::map<std::string, int> counts;
    for (const auto& m : view) {
      ++counts[m.getTopic()];
      if (auto pm = m.instantiate<visualization_msgs::MarkerArray>();
          pm && counts[m.getTopic()] == 2) {
        // Person 2 left the map: its marker is deleted.
        ASSERT_EQ(pm->markers.size(), 2u);
        EXPECT_EQ(pm->markers[1].id, 2);
        EXPECT_EQ(pm->markers[1].action, +visualization_msgs::Marker::DELETE);
        EXPECT_NEAR(pm->markers[0].scale.x, 0.6, 1e-9);  // 1-sigma diameter
      }
      if (auto g = m.instantiate<nav_msgs::OccupancyGrid>()) {
        EXPECT_EQ(g->header.frame_id, "map");
        EXPECT_EQ(g->info.width, 20u);
        EXPECT_EQ(g->data[2], 100);
      }
    }
    EXPECT_EQ(counts["/sarmap/pose"], 3);
    EXPECT_EQ(counts["/map"], 2);
    EXPECT_EQ(counts["/sarmap/people"], 2);
  }

  // And back: the same poses, cells and people.
  ASSERT_EQ(
      RunCommand(kBin + "/sarmap-log-import-rosbag " + bag + " -o " + back + " --config " + kConfig,
                 &out),
      0)
      << out;
  const auto original = ReadLog(log), imported = ReadLog(back);
  for (const char* channel : {"POSE", "MAP", "PEOPLE_MAP"}) {
    ASSERT_EQ(imported.count(channel), 1u) << channel;
    EXPECT_EQ(imported.at(channel).size(), original.at(channel).size()) << channel;
  }
  for (size_t i = 0; i < 3; ++i) {
    const auto a = Decode<pose_t>(original.at("POSE")[i]),
               b = Decode<pose_t>(imported.at("POSE")[i]);
    EXPECT_EQ(a.header.utime, b.header.utime);
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(a.position_m[k], b.position_m[k]);
    for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(a.orientation[k], b.orientation[k]);
  }
  const auto ga = Decode<occupancy_grid_t>(original.at("MAP")[1]),
             gb = Decode<occupancy_grid_t>(imported.at("MAP")[1]);
  EXPECT_EQ(ga.data, gb.data);
  EXPECT_NEAR(ga.resolution_m, gb.resolution_m, 1e-7);  // float in ROS
  EXPECT_DOUBLE_EQ(ga.origin_x_m, gb.origin_x_m);
  for (size_t i = 0; i < 2; ++i) {
    const auto pa = Decode<people_map_t>(original.at("PEOPLE_MAP")[i]);
    const auto pb = Decode<people_map_t>(imported.at("PEOPLE_MAP")[i]);
    ASSERT_EQ(pa.num_people, pb.num_people);
    for (int k = 0; k < pa.num_people; ++k) {
      EXPECT_EQ(pa.people[k].id, pb.people[k].id);
      EXPECT_EQ(pa.people[k].cues, pb.people[k].cues);
      EXPECT_EQ(pa.people[k].keyword, pb.people[k].keyword);
      EXPECT_FLOAT_EQ(pa.people[k].confidence, pb.people[k].confidence);
      EXPECT_DOUBLE_EQ(pa.people[k].position_m[1], pb.people[k].position_m[1]);
      for (int c : {0, 4, 8})
        EXPECT_NEAR(pa.people[k].covariance[c], pb.people[k].covariance[c], 1e-12);
    }
  }
}

// The Intel log's first kScans scans as a CARMEN file and as a ROS bag built from the parsed
// CARMEN records (LaserScan + Odometry, record times in line order as a recorder writes them,
// header stamps the CARMEN times), both through sarmap-slam-offline: the same relations error.
constexpr int kScans = 1000;

slam::RelationErrors PrefixErrors(const std::string& trajectory_path,
                                  const std::string& relations_path) {
  const auto traj = slam::LoadTrajectory(trajectory_path);
  std::vector<slam::Relation> rel;
  if (traj.empty()) return {};
  double t0 = 1e18, t1 = -1e18;
  for (const auto& p : traj) {
    t0 = std::min(t0, p.time_s);
    t1 = std::max(t1, p.time_s);
  }
  for (const auto& r : slam::LoadRelations(relations_path)) {
    if (r.t1_s >= t0 && r.t2_s >= t0 && r.t1_s <= t1 && r.t2_s <= t1) rel.push_back(r);
  }
  return slam::EvaluateRelations(traj, rel);
}

// The prefix as a CARMEN log (interlaced by sarmap-log-interlace-carmen: scans of four
// geometries) and as a bag made from it, both through sarmap-slam-offline.
void CompareBagWithCarmen(bool interlace) {
  const std::string data = std::string(SARMAP_DATA_DIR) + "/slam/intel";
  const std::string dir = ::testing::TempDir();
  const std::string name = interlace ? "intel_interlaced" : "intel_prefix";
  const std::string carmen = dir + "/" + name + ".log", bag_path = dir + "/" + name + ".bag";
  {
    std::ifstream in(data + "/intel.log");
    std::ofstream out(interlace ? dir + "/intel_plain_prefix.log" : carmen);
    std::string line;
    int scans = 0;
    while (std::getline(in, line) && scans < kScans) {
      out << line << "\n";
      scans += line.rfind("RAWLASER1", 0) == 0 || line.rfind("FLASER", 0) == 0;
    }
  }
  std::string out;
  if (interlace) {
    ASSERT_EQ(RunCommand(kBin + "/sarmap-log-interlace-carmen " + dir + "/intel_plain_prefix.log " +
                             carmen,
                         &out),
              0)
        << out;
  }
  std::set<std::pair<size_t, float>> geometries;  // (beam count, start angle) in the bag
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    int64_t record_ns = 0;
    const auto record_time = [&](double stamp_s) {  // monotonic, as a recorder receives them
      record_ns = std::max(record_ns + 1000, static_cast<int64_t>(std::llround(stamp_s * 1e9)));
      ros::Time t;
      t.fromNSec(record_ns);
      return t;
    };
    const auto odometry = [&](const slam::CarmenOdometry& o) {
      nav_msgs::Odometry msg;
      msg.header = Header(o.time_s, "odom");
      msg.header.stamp.fromNSec(std::llround(o.time_s * 1e6) * 1000);
      msg.child_frame_id = "base_link";
      msg.pose.pose.position.x = o.x_m;
      msg.pose.pose.position.y = o.y_m;
      msg.pose.pose.orientation.w = std::cos(o.theta_rad / 2);
      msg.pose.pose.orientation.z = std::sin(o.theta_rad / 2);
      msg.twist.twist.linear.x = o.tv_mps;
      msg.twist.twist.angular.z = o.rv_radps;
      bag.write("/odom", record_time(o.time_s), msg);
    };
    slam::CarmenReader reader;
    reader.on_odometry = odometry;
    reader.on_laser = [&](const slam::CarmenLaser& l) {
      if (l.has_odometry) odometry(l.odometry);
      sensor_msgs::LaserScan s;
      s.header.frame_id = "laser";
      s.header.stamp.fromNSec(std::llround(l.time_s * 1e6) * 1000);
      s.angle_min = static_cast<float>(l.angle_min_rad);
      s.angle_increment = static_cast<float>(l.angle_increment_rad);
      s.angle_max =
          static_cast<float>(l.angle_min_rad + l.angle_increment_rad * (l.ranges_m.size() - 1));
      s.range_min = 0;
      // CARMEN's max reading means no return; ROS drops ranges above range_max.
      s.range_max = std::nextafter(static_cast<float>(l.range_max_m), 0.f);
      s.ranges = l.ranges_m;
      geometries.insert({s.ranges.size(), s.angle_min});
      bag.write("/scan", record_time(l.time_s), s);
    };
    slam::ReadCarmenFile(carmen, &reader);
  }
  EXPECT_EQ(geometries.size(), interlace ? 4u : 1u);
  ASSERT_EQ(RunCommand(kBin + "/sarmap-log-import-rosbag " + bag_path + " -o " + dir + "/" + name +
                           "_bag.lcmlog --config " + kConfig,
                       &out),
            0)
      << out;
  ASSERT_EQ(RunCommand(kBin + "/sarmap-slam-offline " + carmen + " --quiet --output " + dir + "/" +
                           name + "_carmen.txt",
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("scans " + std::to_string(kScans) + " (rejected 0,"), std::string::npos)
      << out;
  // The bag's record order is the CARMEN line order (its stamps go back at times), so the LCM
  // log is run in log order as the CARMEN log is.
  ASSERT_EQ(
      RunCommand(kBin + "/sarmap-slam-offline " + dir + "/" + name +
                     "_bag.lcmlog --log-order --quiet --output " + dir + "/" + name + "_bag.txt",
                 &out),
      0)
      << out;
  EXPECT_NE(out.find("scans " + std::to_string(kScans) + " (rejected 0,"), std::string::npos)
      << out;
  const auto carmen_errors =
      PrefixErrors(dir + "/" + name + "_carmen.txt", data + "/intel.relations");
  const auto bag_errors = PrefixErrors(dir + "/" + name + "_bag.txt", data + "/intel.relations");
  std::printf(
      "Intel first %d scans%s: CARMEN %d relations, %.6f m, %.4f deg; bag %d relations, %.6f m, "
      "%.4f deg\n",
      kScans, interlace ? " interlaced" : "", carmen_errors.used, carmen_errors.abs_trans_m.mean,
      carmen_errors.abs_rot_deg.mean, bag_errors.used, bag_errors.abs_trans_m.mean,
      bag_errors.abs_rot_deg.mean);
  EXPECT_GT(carmen_errors.used, 50);
  EXPECT_EQ(bag_errors.used, carmen_errors.used);
  EXPECT_NEAR(bag_errors.abs_trans_m.mean, carmen_errors.abs_trans_m.mean, 1e-4);
  EXPECT_NEAR(bag_errors.abs_rot_deg.mean, carmen_errors.abs_rot_deg.mean, 0.01);
}

TEST(RosbagConvertTest, IntelAsABagGivesTheSameRelationsErrorAsTheCarmenLog) {
  const std::string log = std::string(SARMAP_DATA_DIR) + "/slam/intel/intel.log";
  if (!std::ifstream(log)) GTEST_SKIP() << "shared data missing: " << log;
  CompareBagWithCarmen(false);
}

TEST(RosbagConvertTest, AnInterlacedScannerAsABagKeepsEveryScansGeometry) {
  // LaserScans whose start angle, increment and beam count change from scan to scan: every
  // one is imported with its own geometry and used by SLAM, as in the CARMEN log.
  const std::string log = std::string(SARMAP_DATA_DIR) + "/slam/intel/intel.log";
  if (!std::ifstream(log)) GTEST_SKIP() << "shared data missing: " << log;
  CompareBagWithCarmen(true);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
