#pragma once
// Synthetic depth frames for tests and benchmarks: a floor, optional back wall, box-and-
// cylinder people and furniture, ray cast into an organized Kinect-like depth image with
// depth noise sigma_z = c z^2 and millimetre quantisation. Plain C++/Eigen.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

// World frame: x forward, y left, z up, floor at z = 0, camera at (0, 0, camera_height_m).
struct SyntheticPerson {
  double x_m = 3, y_m = 0;  // feet centre on the floor (lying: body centre)
  double height_m = 1.75;   // standing height
  double yaw_rad = 0;       // facing direction (0: facing away from the camera, along +x);
                            // lying: the head points along yaw
  enum Posture { kStanding, kSitting, kLying } posture = kStanding;  // sitting: on a 0.45 m seat
  double arm_raised_m = 0;  // standing: the left arm held up, its hand this far above the head
};
struct SyntheticObject {
  enum Kind {
    kChair,
    kTable,
    kCabinet,
    kPole,
    kBox,
    kSlab
  } kind = kChair;  // slab: 1.7 x 0.45 m, 0.25 m high
  double x_m = 2, y_m = 0, yaw_rad = 0;
  double height_m = 0;  // kBox / kCabinet / kPole: overall height; kChair: top of an office
                        // chair's headrest (0: default, a plain back 0.94 m high)
};

struct SyntheticScene {
  int width = 640, height = 480;
  PinholeIntrinsics intrinsics;
  double camera_height_m = 0.55;
  double camera_pitch_rad = 0.0;  // positive: looking up
  double back_wall_m = 0;         // > 0: a wall across the view at this forward distance
  double depth_noise_coeff = 0.0015;
  double min_range_m = 0.5, max_range_m = 8.0;
  std::vector<SyntheticPerson> people;
  std::vector<SyntheticObject> objects;

  // Rotation and translation of the camera optical frame in the world frame.
  Eigen::Matrix3d world_R_camera() const;
  Eigen::Vector3d world_t_camera() const { return Eigen::Vector3d(0, 0, camera_height_m); }
  GroundPlane ground() const;
  // A person's body centre (half height) in the camera frame.
  Eigen::Vector3d PersonInCamera(const SyntheticPerson& p) const;

  // Fraction of person `index`'s pixels not hidden by anything else; 0 when its head or feet
  // are outside the image (or within 15 px of its edge) or the depth range.
  double VisibleFraction(size_t index) const;

  // Depth in millimetres (0 = no return), width*height, noise from `seed`.
  std::vector<uint16_t> RenderDepth(uint32_t seed) const;
};

// Fills `frame` from the rendered depth; colour (if `dark_color`) is a nearly black image
// with sensor noise, as a camera in a dark room gives.
void RenderFrame(const SyntheticScene& scene, uint32_t seed, bool dark_color, RgbdFrame* frame);

}  // namespace vision_people
}  // namespace sarmap
