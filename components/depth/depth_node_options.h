#pragma once
// Options of sarmap-depth (config/depth.yaml).

#include <string>

#include "common/options.h"
#include "depth/depth_to_scan.h"

namespace sarmap {
namespace depth {

struct DepthNodeOptions {
  std::string source = "openni2";  // openni2 | folder | lcm
  std::string device_uri = "";     // openni2: "" = first device, or a .oni recording path
  bool color = true;               // also publish RGB
  bool register_depth = true;      // openni2: depth registered to colour when supported
  // folder replay: depth images (16-bit PNG/PGM/TIFF), sorted by name; colour images matched by
  // replacing depth_pattern with color_pattern in the path.
  std::string folder = "";
  std::string depth_pattern = "depth";
  std::string color_pattern = "color";
  double folder_depth_unit_m = 0.001;  // metres per stored depth unit (TUM: 0.0002)
  double depth_scale = 0;  // stored units per metre (1000 mm PNG, 5000 TUM); 0: see above
  double folder_fx = 525, folder_fy = 525, folder_cx = 319.5, folder_cy = 239.5;
  double rate_hz = 10.0;                           // folder replay rate
  bool loop = false;                               // folder replay: start again at the end
  std::string robot_config = "config/robot.yaml";  // base_from_camera
  std::string depth_channel = "DEPTH";
  std::string rgb_channel = "RGB";
  std::string scan_channel = "SCAN";
  int jpeg_quality = 85;
  // Depth to scan.
  double min_height_m = 0.05;
  double max_height_m = 1.0;
  double range_min_m = 0.45;
  double range_max_m = 4.5;
  int num_beams = 0;
  int row_step = 2;
  double range_noise_k = 0;
  double surface_window_sigmas = 6;
  double scan_max_rate_hz = 0;  // SCANs per second of frame stamps at most (0: one per frame)
  // The scan part, for depth::DepthToScan.
  DepthToScanOptions ScanOptions() const {
    DepthToScanOptions o;
    o.min_height_m = min_height_m;
    o.max_height_m = max_height_m;
    o.range_min_m = range_min_m;
    o.range_max_m = range_max_m;
    o.num_beams = num_beams;
    o.row_step = row_step;
    o.range_noise_k = range_noise_k;
    o.surface_window_sigmas = surface_window_sigmas;
    return o;
  }
  template <class V>
  void Visit(V& v) {
    v("source", source,
      "openni2 (device or .oni), folder (image replay), or lcm (DEPTH from the bus, e.g. the "
      "simulator: only SCAN is published)",
      OneOf({"openni2", "folder", "lcm"}));
    v("device_uri", device_uri, "OpenNI2 device URI or .oni file; empty = first device");
    v("color", color, "publish RGB as well");
    v("register_depth", register_depth, "OpenNI2: register depth to colour when supported");
    v("folder", folder, "folder replay: directory with depth (and colour) images");
    v("depth_pattern", depth_pattern, "folder replay: depth files contain this text");
    v("color_pattern", color_pattern,
      "folder replay: colour file = depth path with depth_pattern replaced by this");
    v("folder_depth_unit_m", folder_depth_unit_m,
      "folder replay: metres per depth unit (used when depth_scale is 0 and the folder is no TUM "
      "sequence)",
      Positive());
    v("depth_scale", depth_scale,
      "folder replay: stored depth units per metre (1000: millimetres, 5000: TUM); 0: "
      "folder_depth_unit_m, or 5000 for a TUM folder (depth.txt + rgb.txt)",
      NonNegative());
    v("folder_fx", folder_fx, "folder replay intrinsics fx");
    v("folder_fy", folder_fy, "folder replay intrinsics fy");
    v("folder_cx", folder_cx, "folder replay intrinsics cx");
    v("folder_cy", folder_cy, "folder replay intrinsics cy");
    v("rate_hz", rate_hz, "folder replay rate", Positive());
    v("loop", loop, "folder replay: loop");
    v("robot_config", robot_config, "robot description with base_from_camera");
    v("depth_channel", depth_channel, "output depth images");
    v("rgb_channel", rgb_channel, "output colour images");
    v("scan_channel", scan_channel, "output depth-derived laser scans");
    v("jpeg_quality", jpeg_quality, "RGB JPEG quality", InRange(1, 100));
    v("min_height_m", min_height_m, "scan height band: lowest obstacle height above the floor");
    v("max_height_m", max_height_m, "scan height band: highest obstacle height (robot height)");
    v("range_min_m", range_min_m, "closer depth is invalid", Positive());
    v("range_max_m", range_max_m, "farther depth is no return (free up to here)");
    v("num_beams", num_beams, "beams per scan (0 = image width)", AtLeast(0));
    v("row_step", row_step, "use every n-th image row for the scan", AtLeast(1));
    v("range_noise_k", range_noise_k,
      "depth noise sigma = k * range^2 (m): a beam is the range of its nearest surface's pixels "
      "(their mean about their median), not their minimum, which lies ~2.5 sigma short (0: the "
      "minimum)",
      NonNegative());
    v("surface_window_sigmas", surface_window_sigmas,
      "the nearest surface: pixels within this many sigma of the beam's closest pixel", Positive());
    v("scan_max_rate_hz", scan_max_rate_hz,
      "make a SCAN from at most this many frames per second (by their stamps; images are still "
      "published from every frame); 0: every frame",
      NonNegative());
  }
  void Validate(common::Validator& c) const {
    c.That(max_height_m > min_height_m, "max_height_m", "must be > min_height_m");
    c.That(range_max_m > range_min_m, "range_max_m", "must be > range_min_m");
  }
};

}  // namespace depth
}  // namespace sarmap
