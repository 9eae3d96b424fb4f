#pragma once
// Ground-based RGB-D people detection (Munaro et al. 2012, as used by Sales 2014), plus a
// depth-only shape classifier for darkness and glare and a lying-body test.
//
// Pipeline for one frame (an organized cloud in the camera optical frame, optional colour):
//   1. the floor found in the data (ground_estimator.h: RANSAC + weighted least squares, the
//      mounting file and the tracked floor as extra hypotheses);
//   2. voxel grid (0.06 m) in that floor's frame, without flying pixels; the floor polished on
//      voxels with free space above them and tracked over frames (a mounting file that
//      disagrees is reported);
//   3. voxels within 0.06 m of the ground removed;
//   4. Euclidean clustering (centroids closer than 2 x voxel are connected);
//   5. clusters whose ground-plane centroids are closer than 0.4 m merged (vertically aligned
//      pieces of one occluded person); clusters lower than 1 m go to the lying-body test (low,
//      long, narrow, on the floor, a body's relief along it); arms held up above the head
//      removed;
//   6. head-based sub-clustering: a height map along the axis perpendicular to the viewing
//      ray; its local maxima at least 0.3 m apart are heads, each head takes the points
//      within 0.3 m of it (ground-plane distance);
//   7. each sub-cluster is scored by a depth-only shape model (height, head-shoulder profile,
//      width, vertical fill, feet on the ground) and, when the colour image is usable, by HOG +
//      linear SVM on the colour patch of its theoretical box (head to ground), as long as it
//      stands on something (feet on the floor, or its bottom hidden by something nearer);
//   8. accepted candidates get a 3D position in the camera frame with a covariance from the
//      Kinect depth-noise model (sigma_z = c z^2).
// No OpenCV, PCL or LCM in this header: HOG lives behind HogClassifier (hog_classifier.h).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "vision_people/ground_estimator.h"

namespace sarmap {
namespace vision_people {

class HogClassifier;
struct DetectorWorkspace;

// Pinhole intrinsics of the image the cloud is registered to.
struct PinholeIntrinsics {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
};

// An organized cloud (row-major, camera optical frame: z forward, x right, y down; metres;
// NaN where there is no depth) and, optionally, the registered colour image (RGB8, same size).
struct RgbdFrame {
  int64_t utime = 0;
  int width = 0;
  int height = 0;
  PinholeIntrinsics intrinsics;
  std::vector<float> xyz;    // 3 * width * height
  std::vector<uint8_t> rgb;  // 3 * width * height, or empty when there is no colour
  bool has_color() const { return !rgb.empty(); }
};

// Fills `frame->xyz` from a depth image (depth units * unit_m = metres along z; 0 = none).
void CloudFromDepth(const uint16_t* depth, int width, int height, double unit_m,
                    const PinholeIntrinsics& intrinsics, RgbdFrame* frame);

struct DepthShapeOptions {
  double min_height_m = 1.15;  // standing person: top of the head above the floor
  double max_height_m = 2.1;
  double height_margin_m = 0.15;      // soft edge of the height membership
  double max_bottom_m = 0.35;         // lowest point above the floor when the feet are in view
  double min_visible_fraction = 0.8;  // of the head-to-floor span inside the image
  double min_width_m = 0.25;          // torso width (at 50..80 % of the height)
  double max_width_m = 0.9;
  double max_depth_extent_m = 0.8;
  double head_drop_m = 0.2;            // head = bins within this of the top
  double shoulder_drop_m = 0.5;        // head + shoulders = bins within this of the top
  double max_head_to_shoulder = 0.85;  // head footprint / head-and-shoulders footprint
  double max_head_width_m = 0.35;
  double head_radius_m = 0.18;          // beyond this from the top point (on the floor) ...
  double head_depth_m = 0.12;           // (plus this along the viewing ray) ...
  double min_head_prominence_m = 0.15;  // ... everything is at least this much lower
  double max_head_prominence_m = 0.5;   // ... but not this much: shoulders are near
  double max_sitting_height_m = 1.5;    // a top this low with a lap beside the head: sitting
  double min_fill = 0.6;                // occupied fraction of the height column
  double accept = 0.5;                  // depth-only decision threshold on the shape score
  template <class V>
  void Visit(V& v) {
    v("min_height_m", min_height_m, "lowest standing person", Positive());
    v("max_height_m", max_height_m, "tallest standing person");
    v("height_margin_m", height_margin_m, "soft margin on the height limits");
    v("max_bottom_m", max_bottom_m,
      "lowest cluster point above the floor when the feet are in view");
    v("min_visible_fraction", min_visible_fraction,
      "depth-only: fraction of the head-to-floor span that must be in the image", InRange(0, 1));
    v("min_width_m", min_width_m, "narrowest torso");
    v("max_width_m", max_width_m, "widest torso");
    v("max_depth_extent_m", max_depth_extent_m, "largest extent along the viewing ray");
    v("head_drop_m", head_drop_m, "height map bins within this of the top form the head");
    v("shoulder_drop_m", shoulder_drop_m,
      "height map bins within this of the top form head and shoulders");
    v("max_head_to_shoulder", max_head_to_shoulder,
      "largest head / head-and-shoulders floor footprint ratio (1.0: zero)");
    v("head_radius_m", head_radius_m,
      "points farther than this from the top (on the floor, across the viewing ray) are not head");
    v("head_depth_m", head_depth_m,
      "along the viewing ray the head reaches head_radius_m + this (its side, range noise)");
    v("min_head_prominence_m", min_head_prominence_m,
      "the top must stand this far above all non-head points (-0.06 m: zero)");
    v("max_head_prominence_m", max_head_prominence_m,
      "... and at most this far: a person's shoulders are there (+0.1 m: zero; a pole or a sliver "
      "of furniture has none)");
    v("max_sitting_height_m", max_sitting_height_m,
      "tallest sitting person: below this top, when the highest non-head point is in the lower "
      "half (a lap), the shoulders are looked for beyond head_radius_m in every direction (seen "
      "side-on they lie along the viewing ray)");
    v("max_head_width_m", max_head_width_m, "widest head across the viewing ray (+0.15 m: zero)");
    v("min_fill", min_fill, "smallest occupied fraction of the 6 cm height slices", InRange(0, 1));
    v("accept", accept, "depth-only: accept when the shape score reaches this", InRange(0, 1));
  }
  void Validate(common::Validator& check) const {
    check.That(max_height_m > min_height_m, "max_height_m", "must exceed min_height_m");
  }
};

// People lying on the floor (victims): a cluster whose top is low, touching the floor, long
// and narrow like a body, with a body's relief along its length (head, chest and legs differ
// in height; a slab, a box or a bag of debris has a flat top). Depth only: HOG's upright
// window does not fit a lying person.
struct LyingOptions {
  bool enabled = true;
  double min_top_m = 0.15;  // top of the body above the floor
  double max_top_m = 0.55;
  double max_bottom_m = 0.15;  // the body lies on the floor
  double min_length_m = 1.1;   // visible extent along the body (a child, a bent knee)
  double max_length_m = 2.1;
  double min_width_m = 0.2;
  double max_width_m = 0.65;
  double min_relief_m = 0.06;  // spread of the highest point along the body (inner 80 %)
  double min_fill = 0.85;      // occupied 0.1 m bins along the body
  double accept = 0.5;
  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "look for people lying on the floor");
    v("min_top_m", min_top_m, "lowest top of a lying body above the floor");
    v("max_top_m", max_top_m, "highest top of a lying body above the floor");
    v("max_bottom_m", max_bottom_m, "a lying body's lowest point is at most this above the floor");
    v("min_length_m", min_length_m, "shortest lying body (visible extent along it)");
    v("max_length_m", max_length_m, "longest lying body");
    v("min_width_m", min_width_m, "narrowest lying body (visible extent across it)");
    v("max_width_m", max_width_m, "widest lying body");
    v("min_relief_m", min_relief_m,
      "a body's top varies at least this much along it (a box's does not)");
    v("min_fill", min_fill, "occupied fraction of the 0.1 m bins along the body", InRange(0, 1));
    v("accept", accept, "accept when the lying shape score reaches this", InRange(0, 1));
  }
  void Validate(common::Validator& check) const {
    check.That(max_top_m > min_top_m, "max_top_m", "must exceed min_top_m");
    check.That(max_length_m > min_length_m, "max_length_m", "must exceed min_length_m");
    check.That(max_width_m > min_width_m, "max_width_m", "must exceed min_width_m");
  }
};

struct ColorOptions {
  std::string hog = "opencv";  // opencv (Dalal-Triggs INRIA SVM) | pcl (PCL's trained SVM) | none
  std::string pcl_svm_file =
      "../shared/data/vision/pcl_people/trainedLinearSVMForPeopleDetectionWithHOG.yaml";
  double hog_threshold = 0.0;     // SVM score at which the colour cue is 50/50
  double hog_scale = 1.0;         // SVM score units per logistic unit
  int search_steps = 1;           // +-steps of 1/8 window in x and y and one scale step each way
  double dark_mean = 25;          // grey mean below this: too dark for colour (0..255)
  double min_contrast = 10;       // grey standard deviation below this: no contrast
  double max_saturated = 0.5;     // fraction of pixels >= 250: glare
  double color_weight = 0.6;      // weight of the HOG probability in the combined confidence
  double min_depth_score = 0.15;  // with colour, candidates must still look somewhat like a person
  double accept = 0.5;            // combined confidence to accept
  template <class V>
  void Visit(V& v) {
    v("hog", hog, "colour classifier: opencv, pcl or none", OneOf({"opencv", "pcl", "none"}));
    v("pcl_svm_file", pcl_svm_file,
      "PCL's trained HOG SVM (for hog: pcl), relative to the working directory");
    v("hog_threshold", hog_threshold, "SVM score where the colour cue gives probability 0.5");
    v("hog_scale", hog_scale, "SVM score units per logistic unit", Positive());
    v("search_steps", search_steps,
      "HOG windows tried around the theoretical box: +-steps of 1/8 window in x, y and scale",
      InRange(0, 4));
    v("dark_mean", dark_mean, "image (or patch) grey mean below which colour is unusable");
    v("min_contrast", min_contrast, "image (or patch) grey std below which colour is unusable");
    v("max_saturated", max_saturated,
      "fraction of saturated pixels above which colour is unusable (glare)");
    v("color_weight", color_weight,
      "weight of HOG in the combined confidence (depth gets the rest)", InRange(0, 1));
    v("min_depth_score", min_depth_score, "with colour: lowest depth shape score still considered");
    v("accept", accept, "with colour: accept when the combined confidence reaches this",
      InRange(0, 1));
  }
};

struct NoiseOptions {
  double depth_coeff =
      0.0015;                // sigma_z = depth_coeff * z^2 (Kinect v1, Khoshelham & Elberink 2012)
  double pixel_sigma = 1.0;  // lateral pixel noise
  double body_sigma_m = 0.08;  // spread of the cluster centroid about the body centre
  // A camera sees the near side of a body: the centroid of the visible surface of an elliptic
  // cross-section of thickness t lies (pi/4)(t/2) = (pi/8) t in front of its centre (the
  // surface's mean depth, weighted by its projected width cos(theta)). 0.25 m: an adult's chest
  // depth.
  double body_thickness_m = 0.25;
  template <class V>
  void Visit(V& v) {
    v("depth_coeff", depth_coeff, "depth noise: sigma_z = depth_coeff * z^2 (1/m)", NonNegative());
    v("pixel_sigma", pixel_sigma, "lateral noise in pixels", NonNegative());
    v("body_sigma_m", body_sigma_m,
      "uncertainty of the body centre about the visible surface centroid", NonNegative());
    v("body_thickness_m", body_thickness_m,
      "front-to-back thickness of a body: the position is (pi/8) of it beyond the visible "
      "surface's centroid, along the line of sight on the floor (0: the centroid)",
      InRange(0, 1));
  }
};

struct DetectorOptions {
  double voxel_size_m = 0.06;
  int pixel_stride = 1;  // use every n-th pixel in x and y before the voxel grid
  double min_range_m = 0.4;
  double max_range_m = 8.0;  // Kinect depth noise beyond this is > 10 cm
  double max_lateral_m = 6.0;
  double top_cut_m = 2.6;             // voxels higher than this above the prior floor are ignored
  double cluster_tolerance_m = 0.12;  // 2 x voxel
  int min_cluster_voxels = 30;
  int max_cluster_voxels = 5000;
  bool split_walls = true;        // a cluster too large or tall for a person loses its walls
  double merge_distance_m = 0.4;  // ground-plane centroid distance for merging clusters
  double min_head_distance_m = 0.3;
  double min_head_dip_m = 0.1;  // the height map must dip this much between two heads
  int min_subcluster_voxels = 30;
  double candidate_min_height_m = 1.0;  // candidates outside these never reach a classifier
  double candidate_max_height_m = 2.3;
  GroundOptions ground;
  DepthShapeOptions shape;
  LyingOptions lying;
  ColorOptions color;
  NoiseOptions noise;
  template <class V>
  void Visit(V& v) {
    v("voxel_size_m", voxel_size_m, "voxel grid edge (Munaro: 0.06)", Positive());
    v("pixel_stride", pixel_stride, "take every n-th pixel in x and y (1: all)", InRange(1, 8));
    v("min_range_m", min_range_m, "nearer points are ignored");
    v("max_range_m", max_range_m, "farther points are ignored (along the floor)", Positive());
    v("max_lateral_m", max_lateral_m, "points farther sideways are ignored", Positive());
    v("top_cut_m", top_cut_m, "points higher above the prior floor are ignored", Positive());
    v("cluster_tolerance_m", cluster_tolerance_m, "Euclidean clustering distance (2 x voxel)",
      Positive());
    v("min_cluster_voxels", min_cluster_voxels, "smallest cluster");
    v("max_cluster_voxels", max_cluster_voxels, "largest cluster");
    v("split_walls", split_walls,
      "search a cluster too large or too tall for a person for walls and cluster the rest again "
      "(a person in front of a wall)");
    v("merge_distance_m", merge_distance_m,
      "merge clusters whose ground-plane centroids are closer");
    v("min_head_distance_m", min_head_distance_m, "height-map maxima closer than this are one head",
      Positive());
    v("min_head_dip_m", min_head_dip_m, "the height map must dip this much between two heads");
    v("min_subcluster_voxels", min_subcluster_voxels, "smallest sub-cluster");
    v("candidate_min_height_m", candidate_min_height_m, "lowest candidate top above the floor");
    v("candidate_max_height_m", candidate_max_height_m, "highest candidate top above the floor");
    v("ground", ground, "ground plane");
    v("shape", shape, "depth-only shape classifier");
    v("lying", lying, "people lying on the floor (depth shape)");
    v("color", color, "colour (HOG) classifier and its fusion with depth");
    v("noise", noise, "depth noise model for the position covariance");
  }
  void Validate(common::Validator& check) const {
    check.That(max_range_m > min_range_m, "max_range_m", "must exceed min_range_m");
    check.That(cluster_tolerance_m <= 2 * voxel_size_m + 1e-9, "cluster_tolerance_m",
               "at most 2 x voxel_size_m (the neighbourhood searched is +-2 voxels)");
    check.That(candidate_max_height_m > candidate_min_height_m, "candidate_max_height_m",
               "must exceed candidate_min_height_m");
  }
};

// Why colour was or was not used for a frame.
enum class ColorState { kNone, kUsable, kDark, kLowContrast, kGlare };
const char* ColorStateName(ColorState state);

struct PersonCandidate {
  Eigen::Vector3d position_camera = Eigen::Vector3d::Zero();  // centroid of the sub-cluster
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  Eigen::Vector3d head_camera = Eigen::Vector3d::Zero();  // top of the head
  double height_m = 0;
  double bottom_m = 0;
  double width_m = 0;
  double depth_extent_m = 0;
  double head_width_m = 0;       // across the viewing ray
  double shoulder_width_m = 0;   // head and shoulders, across the viewing ray
  double head_prominence_m = 0;  // top above everything outside the head radius
  double head_area_m2 = 0;       // floor footprint of the head
  double shoulder_area_m2 = 0;   // floor footprint of head and shoulders
  double fill = 0;
  double visible_fraction = 0;
  bool truncated_top = false;   // the top may be cut by the field of view
  bool truncated_side = false;  // the left or right image border cuts it
  int num_voxels = 0;
  // Image box of the theoretical person (head to floor), pixels.
  double box_u_center = 0, box_v_top = 0, box_v_bottom = 0;
  double depth_score = 0;  // 0..1
  bool hog_used = false;
  double hog_score = 0;   // SVM margin (when hog_used)
  double confidence = 0;  // 0..1
  bool accepted = false;
  bool depth_only = false;  // decided by the depth shape alone
  bool lying = false;       // a lying body (height_m: its top; length_m: along it)
  double length_m = 0;
  double relief_m = 0;    // lying: spread of the top along the body
  bool supported = true;  // touches the floor, or its bottom is hidden by something nearer
};

// One line of a candidate's verdict and measurements (no newline), for diagnostic output.
std::string DescribeCandidate(const PersonCandidate& c);

struct DetectionStats {
  int num_points = 0;  // finite points used
  int num_voxels = 0;
  int num_ground_voxels = 0;       // voxels of the least-squares polish
  int num_ground_points = 0;       // RANSAC inliers among the sampled points
  bool ground_refined = false;     // the floor was found in this frame's data
  bool ground_reset = false;       // the floor track restarted (a jump or a gap in time)
  bool ground_held_off = false;    // this frame's floor jumped away from the track: not used
  bool mounting_mismatch = false;  // the tracked floor disagrees with the configured mounting
  int num_clusters = 0;
  int num_candidates = 0;
  ColorState color_state = ColorState::kNone;
  double color_mean = 0, color_std = 0;
};

struct DetectionResult {
  std::vector<PersonCandidate> people;    // accepted
  std::vector<PersonCandidate> rejected;  // candidates that failed classification
  GroundPlane ground;                     // used for this frame
  CameraMounting camera;                  // the camera over that floor
  DetectionStats stats;
};

class PeopleDetector {
 public:
  // `mounting_ground`: the floor as seen from the mounted camera (GroundFromMounting).
  // `hog`: colour classifier, or null for depth only (options.color.hog = "none").
  PeopleDetector(const DetectorOptions& options, const GroundPlane& mounting_ground,
                 std::shared_ptr<const HogClassifier> hog);
  ~PeopleDetector();

  // Detects people in one frame. Bad frames (empty, wrong sizes, no finite point) give an
  // empty result and `*error` set; they never throw.
  DetectionResult Detect(const RgbdFrame& frame, std::string* error = nullptr);

  // Forget the tracked floor (unrelated frames follow; a jump or a time gap does this too).
  void ResetGround();
  const GroundTracker& ground_tracker() const { return tracker_; }
  const DetectorOptions& options() const { return options_; }

 private:
  DetectorOptions options_;
  GroundPlane mounting_;
  GroundTracker tracker_;
  std::shared_ptr<const HogClassifier> hog_;
  std::unique_ptr<DetectorWorkspace> ws_;
};

// Creates the colour classifier named by options.hog (null for "none"); throws
// std::runtime_error when the SVM file cannot be read.
std::shared_ptr<const HogClassifier> MakeHogClassifier(const ColorOptions& options);

// Grey mean / std / saturated fraction of an RGB8 image (every `step`-th pixel).
void ImageStatistics(const uint8_t* rgb, int width, int height, int step, double* mean,
                     double* stddev, double* saturated);

}  // namespace vision_people
}  // namespace sarmap
