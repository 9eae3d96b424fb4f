// sarmap-teleop against the real sarmap-explore with a command key, over real LCM (run in a
// private network namespace): the test publishes SCAN, the explorer answers each with CMD_VEL.
// The tool's signed stop stops the robot and is confirmed; another key's release and an
// unsigned drive are refused (the robot stays stopped, the tool exits 1); the signed release
// lets the explorer drive again.
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
#include "sarmap/velocity_command_t.hpp"
#include "tests/process.h"

namespace sarmap {
namespace {

using testing::Process;

TEST(TeleopExplore, SignedStopStopsTheRobotAndOnlySignedCommandsMoveItAgain) {
  const std::string dir = "/tmp/sarmap_teleop_explore_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string key_path = testing_util::WriteKeyFile(dir + "/command.key", 'k');
  const std::string other_key_path = testing_util::WriteKeyFile(dir + "/other.key", 'o');
  const common::AuthKey key = common::LoadAuthKeyFile(key_path);

  common::Node node("teleop_explore_test");
  std::vector<velocity_command_t> commands;
  node.Subscribe<velocity_command_t>(
      "CMD_VEL",
      [&](const velocity_command_t& m, const common::ReceiveInfo&) { commands.push_back(m); });
  auto scan_pub = node.Advertise<laser_scan_t>("SCAN");
  laser_scan_t scan = testing_util::UniformScan(3.0f);  // open space all round
  double next_scan_s = 0;
  // Publishes SCAN at 10 Hz and handles what arrives until `done` or `limit_s`.
  auto pump = [&](double limit_s, const std::function<bool()>& done) {
    const double end_s = common::SteadySeconds() + limit_s;
    while (common::SteadySeconds() < end_s) {
      if (common::SteadySeconds() >= next_scan_s) {
        scan.header.utime = common::WallClockUtime();
        scan_pub.Publish(&scan);
        next_scan_s = common::SteadySeconds() + 0.1;
      }
      node.SpinOnce(0.02);
      if (done()) return true;
    }
    return false;
  };
  auto never = [] { return false; };

  Process explore(
      {"sarmap-explore", "--set", "command_key_file=" + key_path, "--set", "explore.mode=reactive"},
      dir + "/explore.txt");
  ASSERT_TRUE(pump(20, [&] { return !commands.empty(); })) << explore.Output();

  int run = 0;
  auto teleop = [&](std::vector<std::string> args, std::string* output) {
    args.insert(args.begin(), "sarmap-teleop");
    Process tool(args, dir + "/teleop" + std::to_string(++run) + ".txt");
    pump(20, [&] { return !tool.Running(); });
    const int code = tool.Wait(5);
    *output = tool.Output();
    return code;
  };
  // The robot's commands over the next half second.
  auto commands_now = [&] {
    commands.clear();
    pump(0.5, never);
    return commands;
  };
  std::string output;

  ASSERT_EQ(teleop({"--key-file", key_path, "stop"}, &output), 0) << output;
  EXPECT_NE(output.find("obeyed"), std::string::npos) << output;
  auto stopped = commands_now();
  ASSERT_FALSE(stopped.empty());
  for (const auto& c : stopped) {
    EXPECT_EQ(c.source, "stop");
    EXPECT_EQ(c.linear_mps, 0.0);
    EXPECT_TRUE(common::MessageSigned(key, c));  // what the base obeys
  }

  EXPECT_EQ(teleop({"--key-file", other_key_path, "release"}, &output), 1) << output;
  EXPECT_NE(output.find("not obeyed"), std::string::npos) << output;
  EXPECT_EQ(teleop({"--set", "confirm_timeout_s=1", "drive", "0.3", "0", "1"}, &output), 1)
      << output;
  for (const auto& c : commands_now()) EXPECT_EQ(c.source, "stop");

  ASSERT_EQ(teleop({"--key-file", key_path, "release"}, &output), 0) << output;
  auto released = commands_now();
  ASSERT_FALSE(released.empty());
  EXPECT_NE(released.back().source, "stop");
  EXPECT_NE(released.back().source, "teleop");

  explore.Signal(SIGINT);
  EXPECT_EQ(explore.Wait(10), 0) << explore.Output();
  EXPECT_NE(explore.Output().find("TELEOP not signed with the command key"), std::string::npos)
      << explore.Output();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sarmap
