#include "vision_people/pcd_frame.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <cstring>
#include <limits>

namespace sarmap {
namespace vision_people {

bool LoadPcdFrame(const std::string& path, const PinholeIntrinsics& intrinsics, RgbdFrame* frame,
                  std::string* error) {
  pcl::PCLPointCloud2 cloud;
  pcl::PCDReader reader;
  if (reader.read(path, cloud) < 0) {
    *error = "cannot read PCD file '" + path + "'";
    return false;
  }
  if (cloud.height <= 1) {
    *error = path + ": not an organized cloud";
    return false;
  }
  int ox = -1, oy = -1, oz = -1, orgb = -1;
  for (const auto& f : cloud.fields) {
    if (f.count != 1) continue;
    if (f.name == "x" && f.datatype == pcl::PCLPointField::FLOAT32) ox = f.offset;
    if (f.name == "y" && f.datatype == pcl::PCLPointField::FLOAT32) oy = f.offset;
    if (f.name == "z" && f.datatype == pcl::PCLPointField::FLOAT32) oz = f.offset;
    if (f.name == "rgb" || f.name == "rgba") orgb = f.offset;
  }
  if (ox < 0 || oy < 0 || oz < 0) {
    *error = path + ": no float x y z fields";
    return false;
  }
  frame->width = static_cast<int>(cloud.width);
  frame->height = static_cast<int>(cloud.height);
  frame->intrinsics = intrinsics;
  const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
  frame->xyz.resize(3 * n);
  frame->rgb.clear();
  if (orgb >= 0) frame->rgb.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = cloud.data.data() + i * cloud.point_step;
    float x, y, z;
    std::memcpy(&x, p + ox, 4);
    std::memcpy(&y, p + oy, 4);
    std::memcpy(&z, p + oz, 4);
    frame->xyz[3 * i] = x;
    frame->xyz[3 * i + 1] = y;
    frame->xyz[3 * i + 2] = z;
    if (orgb >= 0) {
      uint32_t rgba;
      std::memcpy(&rgba, p + orgb, 4);
      frame->rgb[3 * i] = static_cast<uint8_t>((rgba >> 16) & 0xff);
      frame->rgb[3 * i + 1] = static_cast<uint8_t>((rgba >> 8) & 0xff);
      frame->rgb[3 * i + 2] = static_cast<uint8_t>(rgba & 0xff);
    }
  }
  return true;
}

}  // namespace vision_people
}  // namespace sarmap
