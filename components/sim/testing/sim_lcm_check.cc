// Test helper: listens on LCM to a running sarmap-sim and checks that every channel arrives
// at its rate with valid headers (the Node drops and counts malformed messages).
//   sim_lcm_check --seconds 4   (simulated seconds to wait for; exits 0 when all is well)
#include <chrono>
#include <cstdio>
#include <map>

#include "common/args.h"
#include "common/node.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/image_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sarmap/velocity_command_t.hpp"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunMain("sim_lcm_check", [&] {
    common::ArgParser args("sim_lcm_check", "Checks what sarmap-sim publishes.");
    double seconds = 4, timeout = 60, cmd_vel = 0;
    args.AddFlag("--seconds", &seconds, "simulated seconds to receive");
    args.AddFlag("--timeout", &timeout, "give up after this many wall seconds");
    args.AddFlag("--cmd-vel", &cmd_vel,
                 "publish CMD_VEL at this speed (m/s) and check the robot moves");
    if (!args.Parse(argc, argv)) return 0;
    common::Node node("sim_lcm_check");
    struct Seen {
      long count = 0;
      int64_t first = 0, last = 0;
      bool ordered = true;
    };
    std::map<std::string, Seen> seen;
    auto note = [&](const std::string& channel, const sarmap::header_t& h) {
      Seen& s = seen[channel];
      if (s.count == 0)
        s.first = h.utime;
      else
        s.ordered = s.ordered && h.utime > s.last;
      s.last = h.utime;
      ++s.count;
    };
    node.Subscribe<sarmap::odometry_t>(
        "ODOM", [&](const auto& m, const auto&) { note("ODOM", m.header); }, 100);
    node.Subscribe<sarmap::image_t>(
        "DEPTH", [&](const auto& m, const auto&) { note("DEPTH", m.header); }, 100);
    node.Subscribe<sarmap::image_t>(
        "RGB", [&](const auto& m, const auto&) { note("RGB", m.header); }, 100);
    node.Subscribe<sarmap::audio_frame_t>(
        "AUDIO", [&](const auto& m, const auto&) { note("AUDIO", m.header); }, 200);
    bool done = false;
    double first_x = 0, last_x = 0;
    node.Subscribe<sarmap::sim_truth_t>(
        "SIM_TRUTH",
        [&](const auto& m, const auto&) {
          if (seen["SIM_TRUTH"].count == 0) first_x = m.robot_position_m[0];
          last_x = m.robot_position_m[0];
          note("SIM_TRUTH", m.header);
          done = done || m.header.utime - seen["SIM_TRUTH"].first >=
                             static_cast<int64_t>((seconds - 0.15) * 1e6);
        },
        100);
    auto cmd_pub = node.Advertise<sarmap::velocity_command_t>("CMD_VEL");
    const auto start = std::chrono::steady_clock::now();
    while (!done &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() <
               timeout) {
      node.SpinOnce(0.05);
      if (cmd_vel != 0) {
        sarmap::velocity_command_t cmd;
        cmd.header.frame = "base";
        cmd.linear_mps = cmd_vel;
        cmd.angular_radps = 0;
        cmd.source = "sim_lcm_check";
        cmd_pub.Publish(&cmd);
      }
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::map<std::string, double> rates = {
        {"ODOM", 20}, {"DEPTH", 30}, {"RGB", 30}, {"AUDIO", 31.25}, {"SIM_TRUTH", 10}};
    bool ok = done;
    for (const auto& [channel, rate] : rates) {
      const Seen& s = seen[channel];
      const double span = (s.last - s.first) * 1e-6;
      const double measured = span > 0 ? (s.count - 1) / span : 0;
      const auto& stats = node.stats().at(channel);
      const bool good = s.count > 0 && s.ordered && std::abs(measured - rate) < 0.1 * rate &&
                        stats.dropped_malformed == 0;
      std::printf(
          "%-10s %5ld messages, %6.2f Hz (expected %.2f), in order %s, malformed %ld, lost %ld -> "
          "%s\n",
          channel.c_str(), s.count, measured, rate, s.ordered ? "yes" : "no",
          static_cast<long>(stats.dropped_malformed), static_cast<long>(stats.sequence.gaps()),
          good ? "ok" : "BAD");
      ok = ok && good;
    }
    std::printf("received %.1f simulated s in %.1f wall s\n", seconds, wall);
    if (cmd_vel != 0) {
      const double moved = last_x - first_x;
      std::printf("CMD_VEL %.2f m/s: the robot moved %.2f m along x\n", cmd_vel, moved);
      ok = ok && moved > 0.5 * cmd_vel * (seconds - 0.5);
    }
    return ok ? 0 : 1;
  });
}
