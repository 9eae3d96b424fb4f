#include "slam/map_io.h"

#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace slam {
namespace {

constexpr double kOccupiedThresh = 0.65, kFreeThresh = 0.196;

void RenameOrThrow(const std::string& from, const std::string& to) {
  if (std::rename(from.c_str(), to.c_str()) != 0) {
    throw std::runtime_error("cannot rename '" + from + "' to '" + to + "'");
  }
}

}  // namespace

void SaveMapServerMap(const OccupancyMap& map, const std::string& prefix) {
  const std::string pgm = prefix + ".pgm", yaml = prefix + ".yaml";
  {
    std::ofstream out(pgm + ".tmp", std::ios::binary);
    if (!out) throw std::runtime_error("cannot write '" + pgm + "'");
    out << "P5\n# sarmap-slam map, " << map.resolution_m << " m/pixel\n"
        << map.width << " " << map.height << "\n255\n";
    for (int y = map.height - 1; y >= 0; --y) {
      for (int x = 0; x < map.width; ++x) {
        const int v = map.cells[static_cast<size_t>(y) * map.width + x];
        uint8_t px = 205;
        if (v >= 0) px = v >= kOccupiedThresh * 100 ? 0 : (v <= kFreeThresh * 100 ? 254 : 205);
        out.put(static_cast<char>(px));
      }
    }
    if (!out) throw std::runtime_error("write failed: '" + pgm + "'");
  }
  RenameOrThrow(pgm + ".tmp", pgm);
  {
    std::ofstream out(yaml + ".tmp");
    out.precision(10);
    const std::string image = pgm.substr(pgm.find_last_of('/') + 1);
    out << "image: " << image << "\nresolution: " << map.resolution_m << "\norigin: ["
        << map.origin_x_m << ", " << map.origin_y_m << ", 0.0]\nnegate: 0\noccupied_thresh: "
        << kOccupiedThresh << "\nfree_thresh: " << kFreeThresh << "\n";
    if (!out) throw std::runtime_error("write failed: '" + yaml + "'");
  }
  RenameOrThrow(yaml + ".tmp", yaml);
}

OccupancyMap LoadMapServerMap(const std::string& yaml_path) {
  YAML::Node y;
  try {
    y = YAML::LoadFile(yaml_path);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read map '" + yaml_path + "': " + e.what());
  }
  OccupancyMap map;
  std::string image = y["image"].as<std::string>();
  if (image.empty() || image[0] != '/') {
    const size_t slash = yaml_path.find_last_of('/');
    if (slash != std::string::npos) image = yaml_path.substr(0, slash + 1) + image;
  }
  map.resolution_m = y["resolution"].as<double>();
  map.origin_x_m = y["origin"][0].as<double>();
  map.origin_y_m = y["origin"][1].as<double>();
  const bool negate = y["negate"] && y["negate"].as<int>() != 0;
  const double occ = y["occupied_thresh"] ? y["occupied_thresh"].as<double>() : kOccupiedThresh;
  const double free = y["free_thresh"] ? y["free_thresh"].as<double>() : kFreeThresh;
  std::ifstream in(image, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open map image '" + image + "'");
  std::string magic;
  in >> magic;
  auto next_int = [&]() {
    int v;
    while (in >> std::ws && in.peek() == '#') in.ignore(1 << 20, '\n');
    if (!(in >> v)) throw std::runtime_error("bad PGM header in '" + image + "'");
    return v;
  };
  if (magic != "P5") throw std::runtime_error("'" + image + "' is not a binary PGM (P5)");
  map.width = next_int();
  map.height = next_int();
  const int maxval = next_int();
  in.get();
  if (map.width <= 0 || map.height <= 0 || maxval <= 0 || maxval > 255) {
    throw std::runtime_error("unsupported PGM in '" + image + "'");
  }
  std::vector<uint8_t> px(static_cast<size_t>(map.width) * map.height);
  in.read(reinterpret_cast<char*>(px.data()), px.size());
  if (!in) throw std::runtime_error("PGM truncated: '" + image + "'");
  map.cells.resize(px.size());
  for (int row = 0; row < map.height; ++row) {
    const int y_cell = map.height - 1 - row;
    for (int x = 0; x < map.width; ++x) {
      const double v = px[static_cast<size_t>(row) * map.width + x] / double(maxval);
      const double p = negate ? v : 1.0 - v;
      map.cells[static_cast<size_t>(y_cell) * map.width + x] =
          p > occ ? 100 : (p < free ? 0 : -1);
    }
  }
  return map;
}

}  // namespace slam
}  // namespace sarmap
