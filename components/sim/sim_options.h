#pragma once
// Options of sarmap-sim (config/sim.yaml). The world itself is a separate file
// (config/worlds/*.yaml), read by world.h.

#include <string>

#include "common/options.h"

namespace sarmap {
namespace sim {

using common::Validator;

// A Kinect-like RGB-D camera. Depth is registered to the colour camera (as OpenNI's
// registration mode does): both images share the colour intrinsics, and pixels outside the
// narrower depth field of view read 0.
struct CameraOptions {
  bool enabled = true;
  double rate_hz = 30.0;
  int width = 640;
  int height = 480;
  double color_hfov_deg = 62.0;
  double color_vfov_deg = 48.0;
  double depth_hfov_deg = 58.0;
  double depth_vfov_deg = 45.0;
  double min_range_m = 0.5;
  double max_range_m = 4.6;
  // Axial noise sigma = depth_noise_k * z^2 (Khoshelham & Elberink 2012: ~1.4e-3 /m).
  double depth_noise_k = 1.425e-3;
  double baseline_m = 0.075;      // projector-camera baseline (disparity and shadows)
  double depth_fx_px = 580.0;     // IR camera focal length (disparity quantisation)
  int disparity_subpixel = 8;     // disparity steps per pixel
  double dropout = 0.003;         // random invalid pixels
  double grazing_limit_deg = 84;  // no return beyond this incidence angle
  bool shadows = true;            // projector shadows beside foreground edges
  double color_noise = 0.008;     // colour noise sigma (fraction of full scale), lit
  double dark_gain = 0.04;        // lights off: fraction of the lit brightness reaching the sensor
  double dark_noise = 0.035;      // lights off: noise sigma (sensor gain turned up)
  int jpeg_quality = 85;          // 0 sends raw RGB8
  bool compress_depth = true;
  // Surface texture: the world's flat colours modulated by +-this fraction in cubes of
  // surface_texture_cell_m fixed in the map (posters, tiles, stains). 0: flat colours. Visual
  // odometry needs image gradients that flat walls do not give.
  double surface_texture = 0.0;
  double surface_texture_cell_m = 0.08;
  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "publish DEPTH and RGB");
    v("rate_hz", rate_hz, "frame rate", Positive());
    v("width", width, "image width (pixels)");
    v("height", height, "image height (pixels)");
    v("color_hfov_deg", color_hfov_deg, "colour camera horizontal field of view", InRange(10, 170));
    v("color_vfov_deg", color_vfov_deg, "colour camera vertical field of view", InRange(10, 170));
    v("depth_hfov_deg", depth_hfov_deg, "depth camera horizontal field of view", InRange(10, 170));
    v("depth_vfov_deg", depth_vfov_deg, "depth camera vertical field of view", InRange(10, 170));
    v("min_range_m", min_range_m, "nearest valid depth", Positive());
    v("max_range_m", max_range_m, "farthest valid depth");
    v("depth_noise_k", depth_noise_k, "depth noise sigma = k * z^2 (1/m)", NonNegative());
    v("baseline_m", baseline_m, "projector-camera baseline", Positive());
    v("depth_fx_px", depth_fx_px, "IR camera focal length for disparity quantisation", Positive());
    v("disparity_subpixel", disparity_subpixel, "disparity steps per pixel", AtLeast(0));
    v("dropout", dropout, "fraction of random invalid depth pixels", InRange(0, 1));
    v("grazing_limit_deg", grazing_limit_deg, "no depth return beyond this incidence angle",
      InRange(0, 90));
    v("shadows", shadows, "projector shadows beside foreground edges");
    v("color_noise", color_noise, "colour noise sigma when lit (fraction of full scale)",
      InRange(0, 1));
    v("dark_gain", dark_gain, "lights off: brightness fraction", InRange(0, 1));
    v("dark_noise", dark_noise, "lights off: colour noise sigma", InRange(0, 1));
    v("jpeg_quality", jpeg_quality, "RGB JPEG quality 1..100, 0 = raw RGB8", InRange(0, 100));
    v("compress_depth", compress_depth, "lossless depth compression");
    v("surface_texture", surface_texture,
      "modulate surface colours by +- this fraction in map-fixed cubes (0: flat; visual odometry "
      "needs texture)",
      InRange(0, 1));
    v("surface_texture_cell_m", surface_texture_cell_m, "size of the texture cubes", Positive());
  }
  void Validate(Validator& check) const {
    check.That(width >= 16 && height >= 16, "width", "image must be at least 16x16");
    check.That(max_range_m > min_range_m, "max_range_m", "must exceed min_range_m");
    check.That(max_range_m < 65.0, "max_range_m", "must fit 16-bit millimetres");
  }
};

struct AudioOptions {
  bool enabled = true;
  std::string mic_array;            // config/arrays/<name>.yaml; "" = the robot's array
  int block_samples = 512;          // samples per published frame (per channel)
  int convolve_block_samples = 2048;
  double full_scale_db_spl = 100.0; // sound pressure level that reads int16 full scale (RMS of a sine)
  double sensor_noise_db_spl = 28.0;
  bool reverb = true;               // image-source reverberation (world acoustics)
  double rir_max_length_s = 0.5;    // impulse responses are cut here
  double rir_update_distance_m = 0.04;  // recompute responses when a mic moved this much
  int exact_order = 2;              // reflections up to this order get full fractional delays
  int sinc_half_width = 16;         // windowed-sinc fractional delay half width (taps)
  double motor_noise_db_spl = 52.0; // robot's motors at the array at 0.5 m/s
  bool asynchronous = false;        // each microphone its own sound card (AUDIO_<DEVICE>)
  double timestamp_jitter_s = 0.001;  // asynchronous: host timestamp jitter
  bool espeak = true;               // render "espeak:" clips with espeak-ng
  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "publish AUDIO");
    v("mic_array", mic_array, "array in config/arrays/<name>.yaml; empty: the robot's");
    v("block_samples", block_samples, "samples per channel per audio_frame_t", InRange(16, 16384));
    v("convolve_block_samples", convolve_block_samples, "internal FFT convolution block",
      InRange(64, 16384));
    v("full_scale_db_spl", full_scale_db_spl, "SPL that reads full scale");
    v("sensor_noise_db_spl", sensor_noise_db_spl, "self noise of each microphone");
    v("reverb", reverb, "image-source reverberation (also needs acoustics.reverb in the world)");
    v("rir_max_length_s", rir_max_length_s, "room impulse responses are truncated here",
      Positive());
    v("rir_update_distance_m", rir_update_distance_m, "recompute responses after this mic motion",
      Positive());
    v("exact_order", exact_order, "reflection order with full windowed-sinc delays", AtLeast(0));
    v("sinc_half_width", sinc_half_width, "windowed-sinc half width (taps)", InRange(2, 64));
    v("motor_noise_db_spl", motor_noise_db_spl, "motor noise at the array at 0.5 m/s");
    v("asynchronous", asynchronous, "one sound card per microphone (AUDIO_<DEVICE> channels)");
    v("timestamp_jitter_s", timestamp_jitter_s, "asynchronous: host timestamp jitter",
      NonNegative());
    v("espeak", espeak, "render espeak: phrases with espeak-ng");
  }
  void Validate(Validator& check) const {
    check.That(rir_max_length_s <= 2.0, "rir_max_length_s", "must be <= 2 s");
  }
};

struct OdometryOptions {
  double rate_hz = 20.0;
  // Random walks: the error std after driving d metres is trans_noise * sqrt(d / 1 m) metres
  // (a fraction trans_noise of the first metre); likewise per radian turned, and heading
  // drift per metre driven.
  double trans_noise = 0.02;
  double rot_noise = 0.02;
  double rot_per_trans_rad_per_m = 0.005;
  double slip = 0.0;              // mean fraction of commanded motion lost to slip (unseen by odometry)
  double slip_noise = 0.0;        // sigma of that fraction
  template <class V>
  void Visit(V& v) {
    v("rate_hz", rate_hz, "ODOM rate", Positive());
    v("trans_noise", trans_noise,
      "distance error: std after 1 m as a fraction (grows with sqrt(distance))", InRange(0, 1));
    v("rot_noise", rot_noise,
      "heading error: std after turning 1 rad as a fraction (grows with sqrt(angle))",
      InRange(0, 1));
    v("rot_per_trans_rad_per_m", rot_per_trans_rad_per_m,
      "heading drift std after driving 1 m (rad)", NonNegative());
    v("slip", slip, "mean fraction of motion lost to wheel slip", InRange(0, 1));
    v("slip_noise", slip_noise, "sigma of the slip fraction", InRange(0, 1));
  }
};

struct ChannelOptions {
  std::string odom = "ODOM";
  std::string depth = "DEPTH";
  std::string rgb = "RGB";
  std::string audio = "AUDIO";  // asynchronous arrays: AUDIO_<DEVICE>
  std::string truth = "SIM_TRUTH";
  std::string cmd_vel = "CMD_VEL";
  std::string floor = "SIM_FLOOR";
  template <class V>
  void Visit(V& v) {
    v("odom", odom, "odometry out");
    v("depth", depth, "depth images out");
    v("rgb", rgb, "colour images out");
    v("audio", audio, "audio out (prefix for asynchronous devices)");
    v("truth", truth, "ground truth out");
    v("cmd_vel", cmd_vel, "velocity commands in");
    v("floor", floor, "reachable floor out (occupancy grid, at start and every 5 simulated s)");
  }
};

struct SimOptions {
  std::string world = "config/worlds/lab_lit.yaml";
  std::string robot_config = "config/robot.yaml";
  std::string data_dir = "../shared/data";  // relative paths: from the repository root
  int64_t seed = 1;
  double speed = 1.0;                   // simulated seconds per wall second; 0 = flat out
  int64_t start_utime = 1700000000000000;  // simulated clock at t = 0; 0 = wall clock
  double duration_s = 0.0;              // stop after this much simulated time; 0 = run on
  std::string drive = "auto";           // auto | cmd_vel | path
  double cmd_vel_timeout_s = 0.5;
  std::string command_key_file;  // CMD_VEL obeyed only when signed with it (common/command_auth.h)
  double physics_rate_hz = 200.0;
  double truth_rate_hz = 10.0;
  double robot_radius_m = 0.25;
  double floor_period_s = 5.0;          // SIM_FLOOR period (first at start); 0 = never
  CameraOptions camera;
  AudioOptions audio;
  OdometryOptions odometry;
  ChannelOptions channels;
  template <class V>
  void Visit(V& v) {
    v("world", world, "world file (config/worlds/*.yaml; --world FILE)");
    v("robot_config", robot_config, "robot description (camera and array extrinsics)");
    v("data_dir", data_dir, "shared data (people photos, voices); relative: from the repository root");
    v("seed", seed, "random seed: the same seed gives the same run (--seed N)");
    v("speed", speed,
      "simulated seconds per wall-clock second; 0 = as fast as possible (--speed X)",
      NonNegative());
    v("start_utime", start_utime, "simulated time at start (us since epoch); 0 = wall clock",
      AtLeast(0));
    v("duration_s", duration_s,
      "stop after this many simulated seconds; 0 = until stopped (--duration S)", NonNegative());
    v("drive", drive, "auto (path until CMD_VEL arrives), cmd_vel, or path",
      OneOf({"auto", "cmd_vel", "path"}));
    v("cmd_vel_timeout_s", cmd_vel_timeout_s, "stop when CMD_VEL is older than this", Positive());
    v("command_key_file", command_key_file,
      "key (>= 16 random bytes, mode 600) that must sign CMD_VEL; empty: any CMD_VEL is obeyed");
    v("physics_rate_hz", physics_rate_hz, "robot integration rate", InRange(10, 10000));
    v("truth_rate_hz", truth_rate_hz, "SIM_TRUTH rate", Positive());
    v("robot_radius_m", robot_radius_m, "robot footprint radius for collisions", Positive());
    v("floor_period_s", floor_period_s,
      "publish the reachable floor (SIM_FLOOR) this often; 0 = never", NonNegative());
    v("camera", camera, "RGB-D camera");
    v("audio", audio, "microphone array");
    v("odometry", odometry, "odometry noise");
    v("channels", channels, "channel names");
  }
};

}  // namespace sim
}  // namespace sarmap
