#pragma once
// PCL's own ground-based people detector (pcl::people::GroundBasedPeopleDetectionApp with
// PersonClassifier and PCL's trained HOG SVM), run on an RgbdFrame: the reference our
// detector is checked against. The only translation unit that includes pcl/people templates.

#include <Eigen/Core>

#include <string>
#include <vector>

#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

struct PclReferencePerson {
  Eigen::Vector3d centroid_camera;  // PersonCluster::getTCenter()
  double height_m = 0;
  double confidence = 0;            // HOG SVM score
};

struct PclReferenceOptions {
  std::string svm_file;
  double voxel_size_m = 0.06;
  double min_confidence = -1.5;
  double min_height_m = 1.3, max_height_m = 2.3;
  double min_width_m = 0.1, max_width_m = 8.0;
};

// Runs PCL's detector on a colour frame with the given floor (a, b, c, d as PCL expects);
// false with `error` set when it cannot run.
bool RunPclReference(const RgbdFrame& frame, const Eigen::Vector4d& ground_coeffs,
                     const PclReferenceOptions& options, std::vector<PclReferencePerson>* people,
                     std::string* error);

}  // namespace vision_people
}  // namespace sarmap
