#include "log-tools/rosbag_convert.h"

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/decode.h"
#include "common/image_messages.h"
#include "common/transform.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/ros_audio_msgs.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/image_t.hpp"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {

namespace {

constexpr const char* kLaserScan = "sensor_msgs/LaserScan";
constexpr const char* kOdometry = "nav_msgs/Odometry";
constexpr const char* kTf = "tf2_msgs/TFMessage";
constexpr const char* kImage = "sensor_msgs/Image";
constexpr const char* kCompressedImage = "sensor_msgs/CompressedImage";
constexpr const char* kCameraInfo = "sensor_msgs/CameraInfo";
constexpr const char* kAudioData = "audio_common_msgs/AudioData";
constexpr const char* kAudioStamped = "audio_common_msgs/AudioDataStamped";
constexpr const char* kAudioInfo = "audio_common_msgs/AudioInfo";
constexpr const char* kPoseStamped = "geometry_msgs/PoseStamped";
constexpr const char* kOccupancyGrid = "nav_msgs/OccupancyGrid";
constexpr const char* kMarkerArray = "visualization_msgs/MarkerArray";

constexpr const char* kPeopleNamespace = "people";

std::map<std::string, std::string> ParsePairs(const std::vector<std::string>& pairs) {
  std::map<std::string, std::string> out;
  for (const auto& p : pairs) {
    const size_t eq = p.find('=');
    out[p.substr(0, eq)] = eq == std::string::npos ? "" : p.substr(eq + 1);
  }
  return out;
}

int64_t ToUtime(const ros::Time& t) {
  return static_cast<int64_t>(t.sec) * 1000000 + (t.nsec + 500) / 1000;
}
ros::Time FromUtime(int64_t utime) {
  ros::Time t;
  t.sec = static_cast<uint32_t>(utime / 1000000);
  t.nsec = static_cast<uint32_t>((utime % 1000000) * 1000);
  return t;
}

// The default channel of a supported type ("" when the type is not imported as messages).
std::string DefaultChannel(const std::string& type, const std::string& topic,
                           const std::string& encoding_hint) {
  if (type == kLaserScan) return "SCAN";
  if (type == kOdometry) return "ODOM";
  if (type == kAudioData || type == kAudioStamped) return "AUDIO";
  if (type == kPoseStamped) return "POSE";
  if (type == kOccupancyGrid) return "MAP";
  if (type == kMarkerArray) return "PEOPLE_MAP";
  if (type == kCompressedImage) return "RGB";
  if (type == kImage) {
    // Depth topics by name (sensor_msgs/Image says nothing else before the first message).
    const bool depth = topic.find("depth") != std::string::npos || encoding_hint == "depth";
    return depth ? "DEPTH" : "RGB";
  }
  return "";
}

bool Supported(const std::string& type) {
  return type == kLaserScan || type == kOdometry || type == kTf || type == kImage ||
         type == kCompressedImage || type == kCameraInfo || type == kAudioData ||
         type == kAudioStamped || type == kAudioInfo || type == kPoseStamped ||
         type == kOccupancyGrid || type == kMarkerArray;
}

std::string Namespace(const std::string& topic) {
  const size_t slash = topic.rfind('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

// The camera's namespace of an image topic: image_transport puts compressed images one level
// down (/camera/rgb/image_color/compressed beside /camera/rgb/camera_info).
std::string CameraNamespace(const std::string& topic, const std::string& type) {
  return type == kCompressedImage ? Namespace(Namespace(topic)) : Namespace(topic);
}

// Width and height from a JPEG's start-of-frame or a PNG's IHDR; false when neither.
bool CompressedSize(const std::vector<uint8_t>& d, int* width, int* height) {
  if (d.size() >= 24 && d[0] == 0x89 && d[1] == 'P' && d[2] == 'N' && d[3] == 'G') {
    *width = (d[16] << 24) | (d[17] << 16) | (d[18] << 8) | d[19];
    *height = (d[20] << 24) | (d[21] << 16) | (d[22] << 8) | d[23];
    return *width > 0 && *height > 0;
  }
  if (d.size() < 4 || d[0] != 0xFF || d[1] != 0xD8) return false;
  size_t i = 2;
  while (i + 9 < d.size()) {
    if (d[i] != 0xFF) return false;
    const uint8_t marker = d[i + 1];
    const size_t length = (d[i + 2] << 8) | d[i + 3];
    const bool sof =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      *height = (d[i + 5] << 8) | d[i + 6];
      *width = (d[i + 7] << 8) | d[i + 8];
      return *width > 0 && *height > 0;
    }
    i += 2 + length;
  }
  return false;
}

// Writes sarmap messages to an LCM log, numbering header.seq per channel.
class SequencedLogWriter {
 public:
  explicit SequencedLogWriter(const std::string& path) : log_(path) {}
  template <class Msg>
  void Write(const std::string& channel, int64_t event_utime, Msg* msg) {
    msg->header.seq = seq_[channel]++;
    log_.Write(channel, *msg, event_utime);
    ++counts_[channel];
  }
  const std::map<std::string, int64_t>& counts() const { return counts_; }

 private:
  LcmLogWriter log_;
  std::map<std::string, int64_t> seq_, counts_;
};

common::Rigid3d ToRigid(const geometry_msgs::Transform& t) {
  return common::Rigid3d(
      Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z),
      Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z));
}

// Static transforms, child -> (parent, parent_from_child); answers a_from_b along the tree.
class StaticTree {
 public:
  void Add(const std::string& parent, const std::string& child, const common::Rigid3d& t) {
    edges_[child] = {parent, t};
  }
  bool empty() const { return edges_.empty(); }
  // root_from_frame and the root's name.
  common::Rigid3d FromRoot(std::string frame, std::string* root) const {
    common::Rigid3d t;
    for (int guard = 0; guard < 64; ++guard) {
      auto it = edges_.find(frame);
      if (it == edges_.end()) break;
      t = it->second.second * t;
      frame = it->second.first;
    }
    *root = frame;
    return t;
  }
  bool Lookup(const std::string& a, const std::string& b, common::Rigid3d* a_from_b) const {
    std::string root_a, root_b;
    const common::Rigid3d ra = FromRoot(a, &root_a), rb = FromRoot(b, &root_b);
    if (root_a != root_b) return false;
    *a_from_b = ra.inverse() * rb;
    return true;
  }

 private:
  std::map<std::string, std::pair<std::string, common::Rigid3d>> edges_;
};

std::string ExtrinsicsYaml(const std::string& key, const common::Rigid3d& t) {
  const Eigen::Vector3d ypr = t.rotation().toRotationMatrix().eulerAngles(2, 1, 0);
  std::ostringstream s;
  s.precision(17);
  s << key << ":\n  x_m: " << t.translation().x() << "\n  y_m: " << t.translation().y()
    << "\n  z_m: " << t.translation().z() << "\n  roll_rad: " << ypr.z()
    << "\n  pitch_rad: " << ypr.y() << "\n  yaw_rad: " << ypr.x() << "\n";
  return s.str();
}

sarmap::camera_intrinsics_t ToIntrinsics(const sensor_msgs::CameraInfo& info) {
  sarmap::camera_intrinsics_t k{};
  k.width = static_cast<int32_t>(info.width);
  k.height = static_cast<int32_t>(info.height);
  k.fx = info.K[0];
  k.fy = info.K[4];
  k.cx = info.K[2];
  k.cy = info.K[5];
  const bool brown =
      (info.distortion_model == "plumb_bob" || info.distortion_model == "rational_polynomial") &&
      info.D.size() >= 5;
  k.distortion_model = brown ? sarmap::camera_intrinsics_t::DISTORTION_BROWN_CONRADY
                             : sarmap::camera_intrinsics_t::DISTORTION_NONE;
  for (int i = 0; i < 5 && brown; ++i) k.distortion[i] = info.D[i];
  return k;
}

// Cues and the other fields a MarkerArray person carries in its text ("cues=5 confidence=0.8
// count=1 detections=12 keyword=help").
std::string PersonText(const sarmap::mapped_person_t& p) {
  std::ostringstream s;
  s << "cues=" << static_cast<int>(p.cues) << " confidence=" << p.confidence
    << " count=" << p.people_count << " detections=" << p.num_detections
    << " sound_source=" << p.sound_source_id << " keyword=" << p.keyword;
  return s.str();
}

void ParsePersonText(const std::string& text, sarmap::mapped_person_t* p) {
  std::istringstream s(text);
  std::string field;
  while (s >> field) {
    const size_t eq = field.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = field.substr(0, eq), value = field.substr(eq + 1);
    try {
      if (key == "cues") p->cues = static_cast<int8_t>(std::stoi(value));
      if (key == "confidence") p->confidence = std::stof(value);
      if (key == "count") p->people_count = std::stoi(value);
      if (key == "detections") p->num_detections = std::stoi(value);
      if (key == "sound_source") p->sound_source_id = std::stoll(value);
      if (key == "keyword") p->keyword = value;
    } catch (const std::exception&) {
      // A marker text that is not ours: the fields keep their defaults.
    }
  }
}

}  // namespace

void RosbagOptions::Validate(common::Validator& check) const {
  for (const auto& p : topics) {
    const size_t eq = p.find('=');
    check.That(eq != std::string::npos && eq > 0 && eq + 1 < p.size(), "topics",
               "'" + p + "' is not TOPIC=CHANNEL");
  }
  for (const auto& p : frames) {
    const size_t eq = p.find('=');
    check.That(eq != std::string::npos && eq > 0 && eq + 1 < p.size(), "frames",
               "'" + p + "' is not ROS_FRAME=SARMAP_FRAME");
  }
  check.Positive("audio_sample_rate_hz", audio_sample_rate_hz);
  check.That(!base_frame.empty(), "base_frame", "must not be empty");
}

std::vector<TopicSummary> ListBag(const std::string& bag_path) {
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot read ROS bag '" + bag_path + "': " + e.what());
  }
  rosbag::View view(bag);
  std::map<std::string, TopicSummary> by_topic;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    auto& t = by_topic[c->topic];
    t.topic = c->topic;
    t.type = c->datatype;
  }
  for (const auto& t : by_topic) {
    rosbag::View one(bag, rosbag::TopicQuery(t.first));
    by_topic[t.first].messages = one.size();
  }
  std::vector<TopicSummary> out;
  for (auto& [topic, t] : by_topic) out.push_back(t);
  return out;
}

std::string FormatTopics(const std::vector<TopicSummary>& topics) {
  std::ostringstream s;
  for (const auto& t : topics) {
    char line[512];
    std::string note = t.note;
    if (t.undecodable > 0) {
      note += (note.empty() ? "" : ", ") + std::to_string(t.undecodable) + " undecodable, skipped";
    }
    snprintf(line, sizeof(line), "  %-32s %-36s %8lld  %s%s%s\n", t.topic.c_str(), t.type.c_str(),
             static_cast<long long>(t.messages),
             t.channel.empty() ? "" : ("-> " + t.channel).c_str(),
             t.channel.empty() || note.empty() ? "" : "  ", note.c_str());
    s << line;
  }
  return s.str();
}

RosbagImportResult ImportRosbag(const std::string& bag_path, const std::string& log_path,
                                const RosbagOptions& options, const std::string& extrinsics_path,
                                const std::function<void(double)>& progress) {
  RosbagImportResult result;
  result.topics = ListBag(bag_path);
  const auto topic_channel = ParsePairs(options.topics);
  const auto frame_names = ParsePairs(options.frames);
  const auto frame = [&](const std::string& ros) {
    auto it = frame_names.find(ros);
    return it == frame_names.end() ? ros : it->second;
  };

  // What goes where; unsupported types named in `topics` are an error.
  std::vector<std::string> errors;
  bool anything = false;
  for (auto& t : result.topics) {
    auto mapped = topic_channel.find(t.topic);
    if (!Supported(t.type)) {
      t.note = "unsupported type, skipped";
      if (mapped != topic_channel.end()) {
        errors.push_back("topic " + t.topic + " (mapped to " + mapped->second + ") has type " +
                         t.type + ", which import-rosbag does not convert");
      }
      continue;
    }
    if (t.type == kCameraInfo || t.type == kAudioInfo) {
      t.note = "used for the images / audio in its namespace";
      continue;
    }
    if (t.type == kTf) {
      if (t.topic == "/tf_static") {
        t.note = "static transforms -> extrinsics file";
      } else {
        t.channel = mapped != topic_channel.end() ? mapped->second : options.tf_odom_channel;
        t.note = options.odom_frame + " -> " + options.base_frame + " as odometry";
      }
      anything = true;
      continue;
    }
    t.channel =
        mapped != topic_channel.end() ? mapped->second : DefaultChannel(t.type, t.topic, "");
    anything = true;
  }
  const std::string listing = "the bag holds:\n" + FormatTopics(result.topics);
  if (!errors.empty()) {
    std::string all;
    for (const auto& e : errors) all += e + "\n";
    throw std::runtime_error(all + listing);
  }
  if (!anything) throw std::runtime_error("nothing to import from '" + bag_path + "': " + listing);

  rosbag::Bag bag;
  bag.open(bag_path, rosbag::bagmode::Read);
  // Intrinsics and audio formats first: an image may come before its CameraInfo.
  std::map<std::string, sarmap::camera_intrinsics_t> intrinsics;   // by namespace
  std::map<std::string, audio_common_msgs::AudioInfo> audio_info;  // by namespace
  StaticTree statics;
  {
    rosbag::View infos(bag, [](const rosbag::ConnectionInfo* c) {
      return c->datatype == kCameraInfo || c->datatype == kAudioInfo || c->topic == "/tf_static";
    });
    for (const rosbag::MessageInstance& m : infos) {
      if (m.getDataType() == kCameraInfo) {
        auto info = m.instantiate<sensor_msgs::CameraInfo>();
        if (info && !intrinsics.count(Namespace(m.getTopic()))) {
          intrinsics[Namespace(m.getTopic())] = ToIntrinsics(*info);
        }
      } else if (m.getDataType() == kAudioInfo) {
        auto info = m.instantiate<audio_common_msgs::AudioInfo>();
        if (info && !audio_info.count(Namespace(m.getTopic())))
          audio_info[Namespace(m.getTopic())] = *info;
      } else if (m.getDataType() == kTf) {
        auto tf = m.instantiate<tf2_msgs::TFMessage>();
        if (!tf) continue;
        for (const auto& t : tf->transforms)
          statics.Add(t.header.frame_id, t.child_frame_id, ToRigid(t.transform));
      }
    }
  }

  std::map<std::string, TopicSummary*> summary;
  for (auto& t : result.topics) summary[t.topic] = &t;
  std::set<std::string> warned;
  const auto warn_once = [&](const std::string& topic, const std::string& what) {
    if (warned.insert(topic + what).second) result.warnings.push_back(topic + ": " + what);
  };
  std::map<std::string, int64_t> audio_next_sample;
  std::string first_laser_frame;

  SequencedLogWriter out(log_path);
  rosbag::View view(bag);
  const double total = std::max<double>(1, view.size());
  int64_t done = 0;
  for (const rosbag::MessageInstance& m : view) {
    if (progress && (++done % 256 == 0)) progress(done / total);
    TopicSummary* t = summary[m.getTopic()];
    if (!t || t->channel.empty()) continue;
    const std::string& type = m.getDataType();
    const int64_t record_utime = ToUtime(m.getTime());
    const int64_t before = out.counts().count(t->channel) ? out.counts().at(t->channel) : 0;
    // A message that does not deserialise (truncated, or a type of the same name with another
    // layout) is skipped and counted; the rest of the bag is still converted.
    try {
      if (type == kLaserScan) {
        auto s = m.instantiate<sensor_msgs::LaserScan>();
        if (!s) continue;
        if (first_laser_frame.empty()) first_laser_frame = s->header.frame_id;
        sarmap::laser_scan_t msg{};
        msg.header.utime = ToUtime(s->header.stamp);
        msg.header.frame = frame(s->header.frame_id);
        msg.angle_min_rad = s->angle_min;
        msg.angle_increment_rad = s->angle_increment;
        msg.range_min_m = s->range_min;
        msg.range_max_m = s->range_max;
        msg.ranges_m = s->ranges;
        msg.num_ranges = static_cast<int32_t>(s->ranges.size());
        if (s->intensities.size() == s->ranges.size()) {
          msg.intensities = s->intensities;
          msg.num_intensities = msg.num_ranges;
        }
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kOdometry) {
        auto o = m.instantiate<nav_msgs::Odometry>();
        if (!o) continue;
        sarmap::odometry_t msg{};
        msg.header.utime = ToUtime(o->header.stamp);
        msg.header.frame = frame(o->header.frame_id);
        msg.child_frame = frame(o->child_frame_id);
        const auto& p = o->pose.pose;
        msg.position_m[0] = p.position.x;
        msg.position_m[1] = p.position.y;
        msg.position_m[2] = p.position.z;
        msg.orientation[0] = p.orientation.w;
        msg.orientation[1] = p.orientation.x;
        msg.orientation[2] = p.orientation.y;
        msg.orientation[3] = p.orientation.z;
        std::copy(o->pose.covariance.begin(), o->pose.covariance.end(), msg.pose_covariance);
        msg.linear_velocity_mps[0] = o->twist.twist.linear.x;
        msg.linear_velocity_mps[1] = o->twist.twist.linear.y;
        msg.linear_velocity_mps[2] = o->twist.twist.linear.z;
        msg.angular_velocity_radps[0] = o->twist.twist.angular.x;
        msg.angular_velocity_radps[1] = o->twist.twist.angular.y;
        msg.angular_velocity_radps[2] = o->twist.twist.angular.z;
        std::copy(o->twist.covariance.begin(), o->twist.covariance.end(), msg.twist_covariance);
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kTf) {
        auto tf = m.instantiate<tf2_msgs::TFMessage>();
        if (!tf) continue;
        for (const auto& ts : tf->transforms) {
          if (ts.header.frame_id != options.odom_frame || ts.child_frame_id != options.base_frame)
            continue;
          sarmap::odometry_t msg{};
          msg.header.utime = ToUtime(ts.header.stamp);
          msg.header.frame = frame(ts.header.frame_id);
          msg.child_frame = frame(ts.child_frame_id);
          msg.position_m[0] = ts.transform.translation.x;
          msg.position_m[1] = ts.transform.translation.y;
          msg.position_m[2] = ts.transform.translation.z;
          msg.orientation[0] = ts.transform.rotation.w;
          msg.orientation[1] = ts.transform.rotation.x;
          msg.orientation[2] = ts.transform.rotation.y;
          msg.orientation[3] = ts.transform.rotation.z;
          out.Write(t->channel, record_utime, &msg);
        }
      } else if (type == kImage) {
        auto img = m.instantiate<sensor_msgs::Image>();
        if (!img) continue;
        sarmap::header_t header{};
        header.utime = ToUtime(img->header.stamp);
        header.frame = frame(img->header.frame_id);
        sarmap::camera_intrinsics_t k{};
        auto kit = intrinsics.find(Namespace(m.getTopic()));
        if (kit != intrinsics.end()) {
          k = kit->second;
        } else {
          warn_once(m.getTopic(),
                    "no CameraInfo in " + Namespace(m.getTopic()) + "/: intrinsics left 0");
          k.width = static_cast<int32_t>(img->width);
          k.height = static_cast<int32_t>(img->height);
        }
        const int w = static_cast<int>(img->width), h = static_cast<int>(img->height);
        const std::string& enc = img->encoding;
        const bool swap = img->is_bigendian != 0;
        if (enc == "16UC1" || enc == "mono16" || enc == "32FC1") {
          const size_t bpp = enc == "32FC1" ? 4 : 2;
          if (img->step < w * bpp || img->data.size() < static_cast<size_t>(img->step) * h) {
            warn_once(m.getTopic(), "image data shorter than step x height: skipped");
            continue;
          }
          std::vector<uint16_t> mm(static_cast<size_t>(w) * h);
          for (int r = 0; r < h; ++r) {
            const uint8_t* row = img->data.data() + static_cast<size_t>(r) * img->step;
            for (int c = 0; c < w; ++c) {
              uint8_t b[4];
              std::memcpy(b, row + c * bpp, bpp);
              if (swap) std::reverse(b, b + bpp);
              if (bpp == 2) {
                uint16_t v;
                std::memcpy(&v, b, 2);
                mm[static_cast<size_t>(r) * w + c] = v;
              } else {
                float v;
                std::memcpy(&v, b, 4);
                // Metres to millimetres; no reading (NaN, <= 0) and beyond 65.5 m become 0.
                mm[static_cast<size_t>(r) * w + c] =
                    std::isfinite(v) && v > 0 && v < 65.535f
                        ? static_cast<uint16_t>(std::lround(v * 1000))
                        : 0;
              }
            }
          }
          auto msg = common::MakeDepthImage(header, k, mm.data(), w, h, true);
          out.Write(t->channel, record_utime, &msg);
        } else if (enc == "rgb8" || enc == "bgr8" || enc == "mono8") {
          const int channels = enc == "mono8" ? 1 : 3;
          if (img->step < static_cast<uint32_t>(w * channels) ||
              img->data.size() < static_cast<size_t>(img->step) * h) {
            warn_once(m.getTopic(), "image data shorter than step x height: skipped");
            continue;
          }
          sarmap::image_t msg{};
          msg.header = header;
          msg.intrinsics = k;
          msg.width = w;
          msg.height = h;
          msg.pixel_format = enc == "rgb8"   ? sarmap::image_t::PIXEL_RGB8
                             : enc == "bgr8" ? sarmap::image_t::PIXEL_BGR8
                                             : sarmap::image_t::PIXEL_GRAY8;
          msg.compression = sarmap::image_t::COMPRESSION_NONE;
          msg.data.resize(static_cast<size_t>(w) * h * channels);
          for (int r = 0; r < h; ++r) {
            std::memcpy(msg.data.data() + static_cast<size_t>(r) * w * channels,
                        img->data.data() + static_cast<size_t>(r) * img->step,
                        static_cast<size_t>(w) * channels);
          }
          msg.size = static_cast<int32_t>(msg.data.size());
          out.Write(t->channel, record_utime, &msg);
        } else {
          warn_once(m.getTopic(),
                    "image encoding '" + enc +
                        "' not converted (16UC1, mono16, 32FC1, rgb8, bgr8, mono8 are)");
        }
      } else if (type == kCompressedImage) {
        auto img = m.instantiate<sensor_msgs::CompressedImage>();
        if (!img) continue;
        const std::string& format = img->format;
        const bool png = format.find("png") != std::string::npos;
        if (format.find("compressedDepth") != std::string::npos ||
            format.find("16U") != std::string::npos) {
          warn_once(m.getTopic(), "compressed depth ('" + format +
                                      "') not converted (raw 16UC1 / 32FC1 depth is)");
          continue;
        }
        int w = 0, h = 0;
        if (!CompressedSize(img->data, &w, &h)) {
          warn_once(m.getTopic(), "not a JPEG or PNG image (format '" + format + "'): skipped");
          continue;
        }
        sarmap::image_t msg{};
        msg.header.utime = ToUtime(img->header.stamp);
        msg.header.frame = frame(img->header.frame_id);
        auto kit = intrinsics.find(CameraNamespace(m.getTopic(), type));
        if (kit != intrinsics.end()) {
          msg.intrinsics = kit->second;
        } else {
          warn_once(m.getTopic(), "no CameraInfo in " + CameraNamespace(m.getTopic(), type) +
                                      "/: intrinsics left 0");
          msg.intrinsics.width = w;
          msg.intrinsics.height = h;
        }
        msg.width = w;
        msg.height = h;
        msg.pixel_format = sarmap::image_t::PIXEL_RGB8;  // what it decodes to
        msg.compression =
            png ? sarmap::image_t::COMPRESSION_PNG : sarmap::image_t::COMPRESSION_JPEG;
        msg.data = std::move(img->data);
        msg.size = static_cast<int32_t>(msg.data.size());
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kAudioData || type == kAudioStamped) {
        std::vector<uint8_t> bytes;
        int64_t utime = record_utime;
        std::string frame_id = "mic_array";
        if (type == kAudioStamped) {
          auto a = m.instantiate<audio_common_msgs::AudioDataStamped>();
          if (!a) continue;
          bytes = std::move(a->audio.data);
          utime = ToUtime(a->header.stamp);
          if (!a->header.frame_id.empty()) frame_id = frame(a->header.frame_id);
        } else {
          auto a = m.instantiate<audio_common_msgs::AudioData>();
          if (!a) continue;
          bytes = std::move(a->data);
        }
        int rate = options.audio_sample_rate_hz, channels = options.audio_channels;
        auto info = audio_info.find(Namespace(m.getTopic()));
        if (info != audio_info.end()) {
          const auto& i = info->second;
          if (i.coding_format != "wave" && !i.coding_format.empty()) {
            warn_once(m.getTopic(),
                      "coding_format '" + i.coding_format + "' not converted (raw wave S16LE is)");
            continue;
          }
          if (!i.sample_format.empty() && i.sample_format != "S16LE") {
            warn_once(m.getTopic(),
                      "sample_format '" + i.sample_format + "' not converted (S16LE is)");
            continue;
          }
          rate = static_cast<int>(i.sample_rate);
          channels = std::max(1, static_cast<int>(i.channels));
        }
        const int64_t frames = static_cast<int64_t>(bytes.size()) / (2 * channels);
        sarmap::audio_frame_t msg{};
        msg.header.utime = utime;
        msg.header.frame = frame_id;
        msg.device_id = options.audio_device;
        msg.sample_rate_hz = rate;
        msg.num_channels = static_cast<int16_t>(channels);
        msg.num_samples = static_cast<int32_t>(frames);
        msg.first_sample_index = audio_next_sample[m.getTopic()];
        audio_next_sample[m.getTopic()] += frames;
        msg.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
        msg.num_values = static_cast<int32_t>(frames * channels);
        msg.samples.resize(msg.num_values);
        for (int32_t i = 0; i < msg.num_values; ++i) {
          msg.samples[i] = static_cast<int16_t>(bytes[2 * i] | (bytes[2 * i + 1] << 8));
        }
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kPoseStamped) {
        auto p = m.instantiate<geometry_msgs::PoseStamped>();
        if (!p) continue;
        sarmap::pose_t msg{};
        msg.header.utime = ToUtime(p->header.stamp);
        msg.header.frame = frame(p->header.frame_id);
        msg.child_frame = "base";
        msg.position_m[0] = p->pose.position.x;
        msg.position_m[1] = p->pose.position.y;
        msg.position_m[2] = p->pose.position.z;
        msg.orientation[0] = p->pose.orientation.w;
        msg.orientation[1] = p->pose.orientation.x;
        msg.orientation[2] = p->pose.orientation.y;
        msg.orientation[3] = p->pose.orientation.z;
        msg.node_id = -1;
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kOccupancyGrid) {
        auto g = m.instantiate<nav_msgs::OccupancyGrid>();
        if (!g) continue;
        sarmap::occupancy_grid_t msg{};
        msg.header.utime = ToUtime(g->header.stamp);
        msg.header.frame = frame(g->header.frame_id);
        msg.resolution_m = g->info.resolution;
        msg.width = static_cast<int32_t>(g->info.width);
        msg.height = static_cast<int32_t>(g->info.height);
        msg.origin_x_m = g->info.origin.position.x;
        msg.origin_y_m = g->info.origin.position.y;
        const auto& q = g->info.origin.orientation;
        msg.origin_yaw_rad =
            std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
        msg.compression = sarmap::occupancy_grid_t::COMPRESSION_NONE;
        if (g->data.size() != static_cast<size_t>(msg.width) * msg.height) {
          warn_once(m.getTopic(), "grid data size differs from width x height: skipped");
          continue;
        }
        msg.data.assign(g->data.begin(), g->data.end());
        msg.size = static_cast<int32_t>(msg.data.size());
        out.Write(t->channel, record_utime, &msg);
      } else if (type == kMarkerArray) {
        auto a = m.instantiate<visualization_msgs::MarkerArray>();
        if (!a) continue;
        sarmap::people_map_t msg{};
        msg.header.utime = record_utime;
        msg.header.frame = "map";
        for (const auto& mk : a->markers) {
          if (mk.ns != kPeopleNamespace || mk.action != visualization_msgs::Marker::ADD ||
              mk.type != visualization_msgs::Marker::SPHERE) {
            continue;
          }
          msg.header.utime = ToUtime(mk.header.stamp);
          msg.header.frame = frame(mk.header.frame_id);
          sarmap::mapped_person_t p{};
          p.id = mk.id;
          p.position_m[0] = mk.pose.position.x;
          p.position_m[1] = mk.pose.position.y;
          p.position_m[2] = mk.pose.position.z;
          p.covariance[0] = std::pow(0.5 * mk.scale.x, 2);
          p.covariance[4] = std::pow(0.5 * mk.scale.y, 2);
          p.covariance[8] = std::pow(0.5 * mk.scale.z, 2);
          p.people_count = 1;
          p.sound_source_id = -1;
          ParsePersonText(mk.text, &p);
          msg.people.push_back(p);
        }
        if (msg.people.empty() && !a->markers.empty()) {
          warn_once(m.getTopic(),
                    "MarkerArray without SPHERE markers in namespace 'people': empty people maps");
        }
        msg.num_people = static_cast<int32_t>(msg.people.size());
        out.Write(t->channel, record_utime, &msg);
      }
    } catch (const std::exception& e) {
      ++t->undecodable;
      warn_once(m.getTopic(), std::string("undecodable messages skipped (") + e.what() + ")");
    }
    const int64_t after = out.counts().count(t->channel) ? out.counts().at(t->channel) : 0;
    t->written += after - before;
  }
  if (progress) progress(1.0);
  result.channel_counts = out.counts();

  if (!statics.empty() && !extrinsics_path.empty()) {
    std::ostringstream yaml;
    yaml << "# Static transforms of " << bag_path << " (/tf_static), in config/robot.yaml's form:\n"
         << "# the frames are " << options.base_frame << " (base), " << options.camera_frame
         << " (camera), " << options.mic_array_frame << " (mic_array).\n";
    common::Rigid3d t;
    bool any = false;
    if (statics.Lookup(options.base_frame, options.camera_frame, &t)) {
      yaml << ExtrinsicsYaml("base_from_camera", t);
      any = true;
    }
    if (statics.Lookup(options.base_frame, options.mic_array_frame, &t)) {
      yaml << ExtrinsicsYaml("base_from_mic_array", t);
      any = true;
    }
    const std::string laser = options.laser_frame.empty() ? first_laser_frame : options.laser_frame;
    if (!laser.empty() && statics.Lookup(options.base_frame, laser, &t)) {
      const common::Rigid2d p = t.ToRigid2d();
      char line[256];
      snprintf(line, sizeof(line),
               "# The laser (%s) on the base, for SLAM: --set slam.scan.laser_x_m=%.6f "
               "--set slam.scan.laser_y_m=%.6f --set slam.scan.laser_yaw_rad=%.6f\n",
               laser.c_str(), p.translation().x(), p.translation().y(), p.yaw_rad());
      yaml << line;
      any = true;
    }
    if (!any) {
      result.warnings.push_back("/tf_static holds none of " + options.camera_frame + ", " +
                                options.mic_array_frame + ", " + laser + " under " +
                                options.base_frame + ": no extrinsics written");
    } else {
      std::ofstream f(extrinsics_path);
      if (!(f << yaml.str())) throw std::runtime_error("cannot write '" + extrinsics_path + "'");
      result.extrinsics_path = extrinsics_path;
    }
  }
  return result;
}

RosbagExportResult ExportRosbag(const std::string& log_path, const std::string& bag_path,
                                const RosbagOptions& options,
                                const std::function<void(double)>& progress) {
  RosbagExportResult result;
  // Renames back to ROS frame names.
  std::map<std::string, std::string> ros_frame;
  for (const auto& [ros, ours] : ParsePairs(options.frames)) {
    if (!ros_frame.count(ours)) ros_frame[ours] = ros;
  }
  const auto frame = [&](const std::string& ours) {
    auto it = ros_frame.find(ours);
    return it == ros_frame.end() ? ours : it->second;
  };
  // Channels to topics: the export channels, overridable through `topics` (TOPIC=CHANNEL).
  std::map<std::string, std::string> channel_topic = {
      {options.pose_channel, options.pose_topic},
      {options.map_channel, options.map_topic},
      {options.people_channel, options.people_topic}};
  for (const auto& [topic, channel] : ParsePairs(options.topics)) {
    if (channel_topic.count(channel)) channel_topic[channel] = topic;
  }
  LcmLogReader reader(log_path);
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot write ROS bag '" + bag_path + "': " + e.what());
  }
  bag.setCompression(rosbag::compression::LZ4);
  LogEvent ev;
  int64_t n = 0;
  std::set<int32_t> people_shown;  // marker ids published, to delete the ones that go
  while (reader.Next(&ev)) {
    if (progress && (++n % 256 == 0))
      progress(static_cast<double>(reader.offset()) / std::max<int64_t>(1, reader.file_size()));
    auto topic = channel_topic.find(ev.channel);
    if (topic == channel_topic.end()) continue;
    const std::string type = SarmapTypeName(ev.data);
    const ros::Time record = FromUtime(ev.timestamp_us);
    if (type == "pose_t") {
      sarmap::pose_t p;
      if (!common::DecodeMessage(ev.data.data(), ev.data.size(), &p)) continue;
      geometry_msgs::PoseStamped msg;
      msg.header.stamp = FromUtime(p.header.utime);
      msg.header.seq = static_cast<uint32_t>(p.header.seq);
      msg.header.frame_id = frame(p.header.frame);
      msg.pose.position.x = p.position_m[0];
      msg.pose.position.y = p.position_m[1];
      msg.pose.position.z = p.position_m[2];
      msg.pose.orientation.w = p.orientation[0];
      msg.pose.orientation.x = p.orientation[1];
      msg.pose.orientation.y = p.orientation[2];
      msg.pose.orientation.z = p.orientation[3];
      bag.write(topic->second, record, msg);
    } else if (type == "occupancy_grid_t") {
      sarmap::occupancy_grid_t g;
      if (!common::DecodeMessage(ev.data.data(), ev.data.size(), &g)) continue;
      std::vector<int8_t> cells;
      std::string error;
      if (!common::DecodeOccupancyGrid(g, &cells, &error)) continue;
      nav_msgs::OccupancyGrid msg;
      msg.header.stamp = FromUtime(g.header.utime);
      msg.header.seq = static_cast<uint32_t>(g.header.seq);
      msg.header.frame_id = frame(g.header.frame);
      msg.info.map_load_time = msg.header.stamp;
      msg.info.resolution = static_cast<float>(g.resolution_m);
      msg.info.width = static_cast<uint32_t>(g.width);
      msg.info.height = static_cast<uint32_t>(g.height);
      msg.info.origin.position.x = g.origin_x_m;
      msg.info.origin.position.y = g.origin_y_m;
      msg.info.origin.orientation.w = std::cos(0.5 * g.origin_yaw_rad);
      msg.info.origin.orientation.z = std::sin(0.5 * g.origin_yaw_rad);
      msg.data = std::move(cells);
      bag.write(topic->second, record, msg);
    } else if (type == "people_map_t") {
      sarmap::people_map_t pm;
      if (!common::DecodeMessage(ev.data.data(), ev.data.size(), &pm)) continue;
      visualization_msgs::MarkerArray msg;
      std::set<int32_t> now;
      for (const auto& p : pm.people) {
        visualization_msgs::Marker mk;
        mk.header.stamp = FromUtime(pm.header.utime);
        mk.header.frame_id = frame(pm.header.frame);
        mk.ns = kPeopleNamespace;
        mk.id = static_cast<int32_t>(p.id);
        mk.type = visualization_msgs::Marker::SPHERE;
        mk.action = visualization_msgs::Marker::ADD;
        mk.pose.position.x = p.position_m[0];
        mk.pose.position.y = p.position_m[1];
        mk.pose.position.z = p.position_m[2];
        mk.pose.orientation.w = 1;
        // 1-sigma diameters along the map axes.
        mk.scale.x = 2 * std::sqrt(std::max(0.0, p.covariance[0]));
        mk.scale.y = 2 * std::sqrt(std::max(0.0, p.covariance[4]));
        mk.scale.z = 2 * std::sqrt(std::max(0.0, p.covariance[8]));
        const bool heard = p.cues & sarmap::mapped_person_t::CUE_HEARD;
        const bool seen = p.cues & (sarmap::mapped_person_t::CUE_SEEN_RGBD |
                                    sarmap::mapped_person_t::CUE_SEEN_DEPTH);
        mk.color.r = heard ? 1.0f : 0.2f;
        mk.color.g = seen ? 0.8f : 0.2f;
        mk.color.b = 0.2f;
        mk.color.a = 0.8f;
        mk.text = PersonText(p);
        msg.markers.push_back(mk);
        now.insert(mk.id);
      }
      for (int32_t gone : people_shown) {  // people no longer on the map leave RViz too
        if (now.count(gone)) continue;
        visualization_msgs::Marker mk;
        mk.header.stamp = FromUtime(pm.header.utime);
        mk.header.frame_id = frame(pm.header.frame);
        mk.ns = kPeopleNamespace;
        mk.id = gone;
        mk.action = visualization_msgs::Marker::DELETE;
        msg.markers.push_back(mk);
      }
      people_shown = now;
      bag.write(topic->second, record, msg);
    } else {
      continue;
    }
    ++result.topic_counts[topic->second];
  }
  bag.close();
  if (progress) progress(1.0);
  return result;
}

}  // namespace logtools
}  // namespace sarmap
