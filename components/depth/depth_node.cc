// sarmap-depth: RGB-D input (OpenNI2 device or .oni recording, or an image folder) -> DEPTH,
// RGB and a depth-derived SCAN (see depth_to_scan.h).

#include <OpenNI.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "common/stamp_decimator.h"
#include "common/time.h"
#include "depth/depth_node_options.h"
#include "depth/depth_to_scan.h"
#include "sarmap/image_t.hpp"
#include "sarmap/laser_scan_t.hpp"

using namespace sarmap;

namespace {

struct Frame {
  common::Utime utime = 0;
  depth::PinholeIntrinsics intrinsics;
  std::vector<uint16_t> depth_mm;
  std::vector<uint8_t> rgb;  // empty when none
  int rgb_width = 0, rgb_height = 0;
  double depth_unit_m = 0.001;
  bool republish_images = true;  // false when the images came from the bus
};

class Publisher {
 public:
  Publisher(const depth::DepthNodeOptions& o, common::Node* node,
            const Eigen::Isometry3d& base_from_camera)
      : options_(o),
        base_from_camera_(base_from_camera),
        depth_pub_(node->Advertise<image_t>(o.depth_channel)),
        rgb_pub_(node->Advertise<image_t>(o.rgb_channel)),
        scan_pub_(node->Advertise<laser_scan_t>(o.scan_channel)),
        scan_decimator_(o.scan_max_rate_hz) {}

  // Whether the frame stamped `utime` becomes a SCAN (scan_max_rate_hz); a frame that does not
  // is counted in scans_skipped().
  bool ScanDue(common::Utime utime) { return scan_decimator_.Take(utime); }

  // Publishes the frame's images (unless they came from the bus) and, with `with_scan`, its SCAN.
  void Publish(const Frame& f, bool with_scan) {
    if (!converter_ || converter_->intrinsics().width != f.intrinsics.width ||
        converter_->intrinsics().height != f.intrinsics.height) {
      converter_ = std::make_unique<depth::DepthToScan>(options_.ScanOptions(), f.intrinsics,
                                                        base_from_camera_);
    }
    header_t header;
    header.utime = f.utime;
    header.frame = "camera";
    camera_intrinsics_t in{};
    in.width = f.intrinsics.width;
    in.height = f.intrinsics.height;
    in.fx = f.intrinsics.fx, in.fy = f.intrinsics.fy, in.cx = f.intrinsics.cx,
    in.cy = f.intrinsics.cy;
    in.distortion_model = camera_intrinsics_t::DISTORTION_NONE;
    if (f.republish_images) {
      image_t depth_msg =
          common::MakeDepthImage(header, in, f.depth_mm.data(), in.width, in.height);
      depth_pub_.Publish(&depth_msg);
    }
    if (f.republish_images && options_.color && !f.rgb.empty()) {
      camera_intrinsics_t cin = in;
      cin.width = f.rgb_width;
      cin.height = f.rgb_height;
      image_t rgb_msg = common::MakeColorImage(header, cin, f.rgb.data(), f.rgb_width, f.rgb_height,
                                               options_.jpeg_quality);
      rgb_pub_.Publish(&rgb_msg);
    }
    ++frames_;
    if (!with_scan) return;
    const depth::PlanarScan s = converter_->Convert(f.depth_mm.data(), f.depth_unit_m);
    laser_scan_t scan{};
    scan.header.utime = f.utime;
    scan.header.frame = "base";
    scan.angle_min_rad = s.angle_min_rad;
    scan.angle_increment_rad = s.angle_increment_rad;
    scan.range_min_m = s.range_min_m;
    scan.range_max_m = s.range_max_m;
    scan.ranges_m = s.ranges_m;
    scan.num_ranges = static_cast<int32_t>(s.ranges_m.size());
    // A depth-derived scan's intensities are each return's visible-from range (components/
    // depth/README.md): the explorer keeps a low obstacle it can no longer see from close by.
    scan.intensities = s.visible_from_m;
    scan.num_intensities = static_cast<int32_t>(scan.intensities.size());
    scan_pub_.Publish(&scan);
  }
  int64_t frames() const { return frames_; }
  int64_t scans_skipped() const { return scan_decimator_.skipped(); }

 private:
  depth::DepthNodeOptions options_;
  Eigen::Isometry3d base_from_camera_;
  common::Node::Publisher<image_t> depth_pub_, rgb_pub_;
  common::Node::Publisher<laser_scan_t> scan_pub_;
  std::unique_ptr<depth::DepthToScan> converter_;
  common::StampDecimator scan_decimator_;
  int64_t frames_ = 0;
};

// One image pair of a folder replay.
struct FolderImage {
  std::string depth, color;  // color: "" when none
};

// TUM RGB-D layout: depth.txt and rgb.txt ("timestamp path" lines, '#' comments) beside
// depth/ and rgb/; each depth image is paired with the colour image closest in time (within
// 0.02 s, as TUM's associate.py). Empty when the folder has no such lists.
std::vector<FolderImage> TumImages(const std::string& folder) {
  auto read = [&](const std::string& name) {
    std::vector<std::pair<double, std::string>> entries;
    std::ifstream in(folder + "/" + name);
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream s(line);
      double t;
      std::string path;
      if (s >> t >> path) entries.emplace_back(t, folder + "/" + path);
    }
    return entries;
  };
  std::vector<FolderImage> images;
  if (access((folder + "/depth.txt").c_str(), R_OK) != 0) return images;
  const auto depth = read("depth.txt");
  const auto rgb = read("rgb.txt");
  for (const auto& [t, path] : depth) {
    FolderImage image{path, ""};
    double best = 0.02;
    for (const auto& [tc, cpath] : rgb) {
      if (std::abs(tc - t) <= best) {
        best = std::abs(tc - t);
        image.color = cpath;
      }
    }
    images.push_back(image);
  }
  return images;
}

// Image-folder replay: a TUM sequence (depth.txt + rgb.txt), or depth files sorted by name.
int RunFolder(const depth::DepthNodeOptions& o, common::Node* node, Publisher* pub) {
  std::vector<FolderImage> images = TumImages(o.folder);
  const bool tum = !images.empty();
  if (!tum) {
    // Depth files: regular files whose name contains depth_pattern, in the folder or in a
    // sub-folder named like it (folder/depth/1.pgm with folder/color/1.png beside).
    std::vector<std::string> files;
    std::function<void(const std::string&, bool)> scan_dir = [&](const std::string& path,
                                                                 bool all) {
      DIR* dir = opendir(path.c_str());
      if (!dir) return;
      while (dirent* e = readdir(dir)) {
        const std::string name = e->d_name;
        if (name.empty() || name[0] == '.') continue;
        const std::string full = path + "/" + name;
        struct stat st;
        if (stat(full.c_str(), &st) != 0) continue;
        const bool match = all || name.find(o.depth_pattern) != std::string::npos;
        if (S_ISDIR(st.st_mode)) {
          if (match && !all) scan_dir(full, true);
        } else if (match) {
          files.push_back(full);
        }
      }
      closedir(dir);
    };
    scan_dir(o.folder, false);
    if (files.empty() && access(o.folder.c_str(), R_OK) != 0) {
      throw std::runtime_error("cannot open folder '" + o.folder + "'");
    }
    std::sort(files.begin(), files.end());
    for (const std::string& path : files) {
      FolderImage image{path, ""};
      if (o.color) {
        std::string cpath = path;
        const size_t at = cpath.rfind(o.depth_pattern);
        if (at != std::string::npos) cpath.replace(at, o.depth_pattern.size(), o.color_pattern);
        for (const std::string& p : {cpath, cpath.substr(0, cpath.rfind('.')) + ".png"}) {
          if (p != path && access(p.c_str(), R_OK) == 0) {
            image.color = p;
            break;
          }
        }
      }
      images.push_back(image);
    }
  }
  if (images.empty()) {
    throw std::runtime_error("no depth images in '" + o.folder +
                             "' (neither depth.txt nor files named '*" + o.depth_pattern + "*')");
  }
  // Metres per stored unit: depth_scale when given; TUM stores 5000 units per metre.
  const double unit_m = o.depth_scale > 0 ? 1.0 / o.depth_scale
                        : tum             ? 1.0 / 5000
                                          : o.folder_depth_unit_m;
  SARMAP_LOG(INFO) << "replaying " << images.size() << " depth images from " << o.folder
                   << (tum ? " (TUM layout)" : "") << ", " << unit_m * 1000 << " mm per unit";
  const double period = 1.0 / o.rate_hz;
  double next = common::SteadySeconds();
  size_t i = 0;
  int64_t unreadable = 0;
  while (!node->stopping()) {
    if (i == images.size()) {
      if (!o.loop || pub->frames() == 0) break;
      i = 0;
    }
    const FolderImage& image = images[i++];
    cv::Mat d = cv::imread(image.depth, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
    if (d.empty()) {
      ++unreadable;
      SARMAP_LOG(WARN) << "skipping '" << image.depth << "': not an image";
      continue;
    }
    if (d.depth() == CV_8U) {
      // An 8-bit depth image (a preview, or a 16-bit PNG re-saved by a viewer) has lost the
      // range: every frame would be wrong, so stop here.
      throw std::runtime_error(
          "'" + image.depth +
          "' is an 8-bit image: depth needs 16-bit values (millimetres, or set depth_scale)");
    }
    Frame f;
    f.utime = common::WallClockUtime();
    f.intrinsics = {d.cols, d.rows, o.folder_fx, o.folder_fy, o.folder_cx, o.folder_cy};
    f.depth_mm.resize(static_cast<size_t>(d.cols) * d.rows);
    // 16-bit units, or 32-bit float metres (some TIFF writers).
    const double to_mm = d.depth() == CV_32F ? 1000.0 : unit_m / 0.001;
    cv::Mat dd;
    d.convertTo(dd, CV_64F, to_mm);
    for (int r = 0; r < d.rows; ++r) {
      for (int col = 0; col < d.cols; ++col) {
        const double mm = dd.at<double>(r, col);
        f.depth_mm[static_cast<size_t>(r) * d.cols + col] =
            std::isfinite(mm) && mm > 0 ? static_cast<uint16_t>(std::min(65535.0, std::round(mm)))
                                        : 0;
      }
    }
    if (o.color && !image.color.empty()) {
      cv::Mat c = cv::imread(image.color, cv::IMREAD_COLOR);
      if (!c.empty()) {
        cv::cvtColor(c, c, cv::COLOR_BGR2RGB);
        f.rgb.assign(c.data, c.data + c.total() * 3);
        f.rgb_width = c.cols;
        f.rgb_height = c.rows;
      }
    }
    pub->Publish(f, pub->ScanDue(f.utime));
    node->SpinOnce(0.0);
    next += period;
    const double wait = next - common::SteadySeconds();
    if (wait > 0) node->SpinOnce(wait);
  }
  if (pub->frames() == 0 && !node->stopping()) {
    throw std::runtime_error("published no frames from '" + o.folder + "' (" +
                             std::to_string(unreadable) + " of " + std::to_string(images.size()) +
                             " images unreadable)");
  }
  SARMAP_LOG(INFO) << "published " << pub->frames() << " frames (" << pub->scans_skipped()
                   << " without a scan: scan_max_rate_hz)";
  return 0;
}

int RunOpenNI(const depth::DepthNodeOptions& o, common::Node* node, Publisher* pub) {
  using namespace openni;
  if (OpenNI::initialize() != STATUS_OK) {
    throw std::runtime_error(std::string("OpenNI2 initialisation failed: ") +
                             OpenNI::getExtendedError());
  }
  struct Shutdown {
    ~Shutdown() { OpenNI::shutdown(); }
  } shutdown;
  Device device;
  const char* uri = o.device_uri.empty() ? ANY_DEVICE : o.device_uri.c_str();
  if (device.open(uri) != STATUS_OK) {
    throw std::runtime_error(
        "no OpenNI2 device " +
        (o.device_uri.empty() ? std::string("connected") : "'" + o.device_uri + "'") + ": " +
        OpenNI::getExtendedError());
  }
  VideoStream depth_stream, color_stream;
  if (depth_stream.create(device, SENSOR_DEPTH) != STATUS_OK) {
    throw std::runtime_error(std::string("cannot open the depth stream: ") +
                             OpenNI::getExtendedError());
  }
  VideoMode mode = depth_stream.getVideoMode();
  mode.setPixelFormat(PIXEL_FORMAT_DEPTH_1_MM);
  depth_stream.setVideoMode(mode);  // recordings keep their own format
  const bool color = o.color && color_stream.create(device, SENSOR_COLOR) == STATUS_OK;
  if (color && o.register_depth &&
      device.isImageRegistrationModeSupported(IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
    device.setImageRegistrationMode(IMAGE_REGISTRATION_DEPTH_TO_COLOR);
  }
  if (depth_stream.start() != STATUS_OK || (color && color_stream.start() != STATUS_OK)) {
    throw std::runtime_error(std::string("cannot start streams: ") + OpenNI::getExtendedError());
  }
  SARMAP_LOG(INFO) << "OpenNI2 device '" << device.getDeviceInfo().getName() << "' streaming";
  VideoFrameRef depth_frame, color_frame;
  while (!node->stopping()) {
    int ready = -1;
    VideoStream* streams[] = {&depth_stream};
    if (OpenNI::waitForAnyStream(streams, 1, &ready, 500) != STATUS_OK) {
      node->SpinOnce(0.0);
      if (device.isFile()) break;  // end of the recording
      continue;
    }
    if (depth_stream.readFrame(&depth_frame) != STATUS_OK || !depth_frame.isValid()) continue;
    Frame f;
    f.utime = common::WallClockUtime();
    const int w = depth_frame.getWidth(), h = depth_frame.getHeight();
    const double hfov = depth_stream.getHorizontalFieldOfView(),
                 vfov = depth_stream.getVerticalFieldOfView();
    f.intrinsics = {w,
                    h,
                    (w / 2.0) / std::tan(hfov / 2),
                    (h / 2.0) / std::tan(vfov / 2),
                    (w - 1) / 2.0,
                    (h - 1) / 2.0};
    const auto* px = static_cast<const uint16_t*>(depth_frame.getData());
    const bool is_100um = depth_frame.getVideoMode().getPixelFormat() == PIXEL_FORMAT_DEPTH_100_UM;
    f.depth_mm.resize(static_cast<size_t>(w) * h);
    for (size_t i = 0; i < f.depth_mm.size(); ++i) f.depth_mm[i] = is_100um ? px[i] / 10 : px[i];
    if (color && color_stream.readFrame(&color_frame) == STATUS_OK && color_frame.isValid() &&
        color_frame.getVideoMode().getPixelFormat() == PIXEL_FORMAT_RGB888) {
      const auto* c = static_cast<const uint8_t*>(color_frame.getData());
      f.rgb.assign(c,
                   c + static_cast<size_t>(color_frame.getWidth()) * color_frame.getHeight() * 3);
      f.rgb_width = color_frame.getWidth();
      f.rgb_height = color_frame.getHeight();
    }
    pub->Publish(f, pub->ScanDue(f.utime));
    node->SpinOnce(0.0);
  }
  SARMAP_LOG(INFO) << "published " << pub->frames() << " frames (" << pub->scans_skipped()
                   << " without a scan: scan_max_rate_hz)";
  return 0;
}

// DEPTH from the bus (the simulator, or a driver on another computer): SCAN only.
int RunLcm(const depth::DepthNodeOptions& o, common::Node* node, Publisher* pub) {
  int64_t bad = 0;
  node->Subscribe<image_t>(
      o.depth_channel,
      [&](const image_t& m, const common::ReceiveInfo&) {
        if (!pub->ScanDue(m.header.utime)) return;  // not decoded either
        Frame f;
        std::string error;
        if (!common::DecodeDepthImage(m, &f.depth_mm, &error)) {
          if (++bad % 100 == 1)
            SARMAP_LOG(WARN) << "undecodable depth image (" << bad << " so far): " << error;
          return;
        }
        f.utime = m.header.utime;
        f.intrinsics.width = m.width;
        f.intrinsics.height = m.height;
        f.intrinsics.fx = m.intrinsics.fx;
        f.intrinsics.fy = m.intrinsics.fy;
        f.intrinsics.cx = m.intrinsics.cx;
        f.intrinsics.cy = m.intrinsics.cy;
        f.depth_unit_m = m.depth_unit_m;
        f.republish_images = false;
        pub->Publish(f, true);
      },
      2);
  return node->Run();
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-depth", [&]() -> int {
    common::NodeArgs node_args;
    common::ArgParser parser("sarmap-depth",
                             "RGB-D input (OpenNI2 device, .oni recording or image folder) -> "
                             "DEPTH, RGB and a depth-derived SCAN.");
    parser.SetEpilog(
        "Examples:\n"
        "  sarmap-depth                                   # first OpenNI2 device\n"
        "  sarmap-depth --set device_uri=rec.oni          # a recording\n"
        "  sarmap-depth --set source=folder --set folder=DIR --set rate_hz=5\n"
        "  sarmap-depth --set source=lcm                  # SCAN from DEPTH on the bus "
        "(simulator)");
    const auto parsed = common::ParseNodeOptions<depth::DepthNodeOptions>(
        &parser, &node_args, argc, argv, "config/depth.yaml");
    if (!parsed) return 0;
    const depth::DepthNodeOptions& options = *parsed;
    const common::RobotOptions robot = common::LoadRobot(options.robot_config);
    const Eigen::Isometry3d base_from_camera = robot.base_from_camera.ToRigid3d().ToIsometry();
    common::Node node("sarmap-depth", node_args);
    Publisher pub(options, &node, base_from_camera);
    if (options.source == "lcm") return RunLcm(options, &node, &pub);
    return options.source == "folder" ? RunFolder(options, &node, &pub)
                                      : RunOpenNI(options, &node, &pub);
  });
}
