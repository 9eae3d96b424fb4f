#include "vision_people/pcl_reference.h"

#include <pcl/people/ground_based_people_detection_app.h>
#include <pcl/point_types.h>

namespace sarmap {
namespace vision_people {

bool RunPclReference(const RgbdFrame& frame, const Eigen::Vector4d& ground_coeffs,
                     const PclReferenceOptions& options, std::vector<PclReferencePerson>* people,
                     std::string* error) {
  using PointT = pcl::PointXYZRGBA;
  if (!frame.has_color() || frame.width <= 0 || frame.height <= 0 ||
      frame.xyz.size() != 3 * static_cast<size_t>(frame.width) * frame.height) {
    *error = "PCL's detector needs an organized cloud with colour";
    return false;
  }
  pcl::PointCloud<PointT>::Ptr cloud(new pcl::PointCloud<PointT>(frame.width, frame.height));
  cloud->is_dense = false;
  for (size_t i = 0; i < cloud->size(); ++i) {
    PointT& p = (*cloud)[i];
    p.x = frame.xyz[3 * i];
    p.y = frame.xyz[3 * i + 1];
    p.z = frame.xyz[3 * i + 2];
    p.r = frame.rgb[3 * i];
    p.g = frame.rgb[3 * i + 1];
    p.b = frame.rgb[3 * i + 2];
    p.a = 255;
  }
  pcl::people::PersonClassifier<pcl::RGB> classifier;
  if (!classifier.loadSVMFromFile(options.svm_file)) {
    *error = "cannot load " + options.svm_file;
    return false;
  }
  Eigen::Matrix3f K;
  K << static_cast<float>(frame.intrinsics.fx), 0, static_cast<float>(frame.intrinsics.cx), 0,
      static_cast<float>(frame.intrinsics.fy), static_cast<float>(frame.intrinsics.cy), 0, 0, 1;
  pcl::people::GroundBasedPeopleDetectionApp<PointT> app;
  app.setVoxelSize(static_cast<float>(options.voxel_size_m));
  app.setIntrinsics(K);
  app.setClassifier(classifier);
  app.setPersonClusterLimits(static_cast<float>(options.min_height_m), static_cast<float>(options.max_height_m),
                             static_cast<float>(options.min_width_m), static_cast<float>(options.max_width_m));
  Eigen::VectorXf ground = ground_coeffs.cast<float>();
  app.setInputCloud(cloud);
  app.setGround(ground);
  std::vector<pcl::people::PersonCluster<PointT>> clusters;
  app.compute(clusters);
  people->clear();
  for (auto& c : clusters) {
    if (c.getPersonConfidence() <= options.min_confidence) continue;
    PclReferencePerson p;
    p.centroid_camera = c.getTCenter().cast<double>();
    p.height_m = c.getHeight();
    p.confidence = c.getPersonConfidence();
    people->push_back(p);
  }
  return true;
}

}  // namespace vision_people
}  // namespace sarmap
