// The real sarmap-explore on a signed bus (common/bus_auth.h), over real LCM in a private network
// namespace. The test is the rest of the stack: it publishes signed SCANs of open space and
// reads the explorer's signed CMD_VEL. Then another host, without the key, publishes what would
// stop the robot (an emergency stop on TELEOP, and SCANs with a wall 0.5 m away all round):
// the explorer drives on as before and logs what it refused. Without --bus-key-file the same
// forged messages stop it, so the test measures the key, not the explorer's other checks.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "common/command_auth.h"
#include "common/node.h"
#include "common/time.h"
#include "explore/explore_process_test_util.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/teleop_t.hpp"
#include "sarmap/velocity_command_t.hpp"
#include "tests/process.h"

namespace sarmap {
namespace {

using testing::Process;

struct AttackRun {
  std::vector<velocity_command_t> before, during;
  std::string output;
};

// sarmap-explore (reactive) with or without the bus key; the stack's side is keyed the same.
AttackRun DriveThroughAnAttack(const std::string& dir, bool signed_bus) {
  const std::string key_path = testing_util::WriteKeyFile(dir + "/bus.key", 'b');

  common::Node stack("signed_bus_stack");
  if (signed_bus) stack.SetBusKey(common::LoadAuthKeyFile(key_path));
  common::Node attacker("signed_bus_attacker");  // another host: no key
  std::vector<velocity_command_t> commands;
  stack.Subscribe<velocity_command_t>(
      "CMD_VEL",
      [&](const velocity_command_t& m, const common::ReceiveInfo&) { commands.push_back(m); });
  auto scan_pub = stack.Advertise<laser_scan_t>("SCAN");
  auto forged_scan_pub = attacker.Advertise<laser_scan_t>("SCAN");
  auto forged_teleop_pub = attacker.Advertise<teleop_t>("TELEOP");
  laser_scan_t open = testing_util::UniformScan(3.0f), wall = testing_util::UniformScan(0.5f);
  double next_scan_s = 0;
  // Signed open-space SCANs at 10 Hz; with `attack`, forged ones between them at 50 Hz.
  auto pump = [&](double limit_s, bool attack, const std::function<bool()>& done) {
    const double end_s = common::SteadySeconds() + limit_s;
    double next_attack_s = 0;
    while (common::SteadySeconds() < end_s) {
      if (common::SteadySeconds() >= next_scan_s) {
        open.header.utime = common::WallClockUtime();
        scan_pub.Publish(&open);
        next_scan_s = common::SteadySeconds() + 0.1;
      }
      if (attack && common::SteadySeconds() >= next_attack_s) {
        wall.header.utime = common::WallClockUtime();
        forged_scan_pub.Publish(&wall);
        teleop_t stop{};
        stop.header.utime = common::WallClockUtime();
        stop.header.frame = "";
        stop.operator_id = "attacker";
        stop.emergency_stop = true;
        forged_teleop_pub.Publish(&stop);
        next_attack_s = common::SteadySeconds() + 0.02;
      }
      stack.SpinOnce(0.01);
      if (done && done()) return;
    }
  };

  std::vector<std::string> args = {"sarmap-explore", "--set", "explore.mode=reactive"};
  if (signed_bus) {
    args.push_back("--bus-key-file");
    args.push_back(key_path);
  }
  Process explore(args, dir + (signed_bus ? "/signed.txt" : "/open.txt"));
  pump(20, false, [&] { return commands.size() >= 5; });
  AttackRun run;
  EXPECT_GE(commands.size(), 5u) << explore.Output();
  commands.clear();
  pump(1.0, false, nullptr);
  run.before = commands;
  commands.clear();
  pump(1.5, true, nullptr);
  run.during = commands;
  explore.Signal(SIGINT);
  EXPECT_EQ(explore.Wait(10), 0) << explore.Output();
  run.output = explore.Output();
  return run;
}

double MeanSpeed(const std::vector<velocity_command_t>& commands) {
  double sum = 0;
  for (const auto& c : commands) sum += c.linear_mps;
  return commands.empty() ? 0 : sum / commands.size();
}

TEST(SignedBusExplore, ForgedScansAndStopsDoNotReachTheExplorer) {
  const std::string dir = "/tmp/sarmap_signed_bus_explore_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);

  const AttackRun keyed = DriveThroughAnAttack(dir, true);
  ASSERT_FALSE(keyed.before.empty()) << keyed.output;
  ASSERT_FALSE(keyed.during.empty()) << keyed.output;
  EXPECT_GT(MeanSpeed(keyed.before), 0.05) << keyed.output;
  // The robot drives through the attack as before it.
  EXPECT_NEAR(MeanSpeed(keyed.during), MeanSpeed(keyed.before), 0.02) << keyed.output;
  for (const auto& c : keyed.during) EXPECT_NE(c.source, "stop");
  EXPECT_NE(keyed.output.find("not signed with the bus key"), std::string::npos) << keyed.output;

  // The same attack on an open bus: the forged messages are obeyed.
  const AttackRun open = DriveThroughAnAttack(dir, false);
  ASSERT_FALSE(open.during.empty()) << open.output;
  EXPECT_LT(MeanSpeed(open.during), 0.5 * MeanSpeed(open.before)) << open.output;

  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sarmap
