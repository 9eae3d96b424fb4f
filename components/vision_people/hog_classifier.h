#pragma once
// HOG + linear SVM on colour patches (Dalal & Triggs 2005). Two trained SVMs:
//   - OpenCV's default people detector (INRIA, 64x128 window, 3780-D descriptor);
//   - PCL's trainedLinearSVMForPeopleDetectionWithHOG.yaml over pcl::people::HOG
//     (Dollar's HOG, 3024-D), as PCL's PersonClassifier uses it.
// OpenCV and PCL headers stay in hog_classifier.cc.

#include <memory>
#include <string>
#include <vector>

#include <cstdint>

namespace sarmap {
namespace vision_people {

class HogClassifier {
 public:
  virtual ~HogClassifier() = default;
  virtual std::string name() const = 0;
  // SVM margin of the best window around a person spanning image rows v_top (head) to
  // v_bottom (feet) centred on column u_center. As in training (and PCL), the person fills
  // 75 % of the window height and the window is half as wide as high; parts outside the image
  // are black. search_steps > 0 also tries windows shifted by multiples of 1/8 window (up to
  // +-search_steps) and scaled by 1.1^+-1. `rgb`: RGB8, width x height.
  virtual double Score(const uint8_t* rgb, int width, int height, double u_center, double v_top,
                       double v_bottom, int search_steps) const = 0;
};

std::shared_ptr<const HogClassifier> MakeOpenCvHogClassifier();
// Throws std::runtime_error when the file cannot be read or has the wrong size.
std::shared_ptr<const HogClassifier> MakePclHogClassifier(const std::string& svm_yaml_path);

// Whole-image sliding-window detection with OpenCV's default people detector (the HOG stage
// on its own, for RGB-only evaluation).
struct SlidingWindowOptions {
  double hit_threshold = 0.0;
  double scale_step = 1.05;
  int group_threshold = 1;   // 1 keeps large people (few overlapping windows at coarse scales)
  double upscale = 1.0;       // resize the image first (finds people smaller than 96 px when > 1)
  bool shrink_boxes = true;   // drop the window margins (0.1 w each side, 0.07 h top, 0.8 h tall)
  double pad_fraction = 0.15; // replicate-pad the image by this fraction of its size so that
                              // people filling the frame still fit a window (with its margins)
};
struct ImageBox {
  double x = 0, y = 0, w = 0, h = 0;  // pixels, top-left and size
  double score = 0;
};
std::vector<ImageBox> DetectPeopleInImage(const uint8_t* rgb, int width, int height,
                                          const SlidingWindowOptions& options);

// Intersection over union of two boxes.
double BoxIoU(const ImageBox& a, const ImageBox& b);

// The box with its width set to aspect * height about the same centre: Dollar et al.'s
// pedestrian-benchmark protocol (aspect 0.41) so that IoU does not punish thin annotations.
ImageBox StandardizeAspect(const ImageBox& box, double aspect = 0.41);

// Greedy matching of detections (highest score first) to ground truth at IoU >= min_iou;
// returns the number of true positives.
int MatchBoxes(const std::vector<ImageBox>& detections, const std::vector<ImageBox>& truth,
               double min_iou, std::vector<bool>* truth_found = nullptr);

// Reads an RGB8 image from a file (PNG, JPEG); false when it cannot be read.
bool ReadRgbImage(const std::string& path, std::vector<uint8_t>* rgb, int* width, int* height);

// The boxes of a PASCAL annotation file (INRIA): "Bounding box for object N ... : (xmin, ymin) -
// (xmax, ymax)"; none when the file cannot be read.
std::vector<ImageBox> ReadPascalBoxes(const std::string& path);

}  // namespace vision_people
}  // namespace sarmap
