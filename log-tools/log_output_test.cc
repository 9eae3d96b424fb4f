// sarmap-log output on a log of an attacked bus: deputies sign PM_OUTPUT, so with --key only
// their own output is written (forged lines of a real command too are skipped); without --key
// a forged deputy's output is written under a plain, short file name inside the directory.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "log-tools/lcm_log_writer.h"
#include "procman/order_auth.h"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_output_t.hpp"
#include "tests/process.h"

namespace {

sarmap::pm_output_t Output(const std::string& deputy, const std::string& command,
                           const std::string& text) {
  sarmap::pm_output_t out{};
  out.header.frame = "procman";
  out.deputy_id = deputy;
  out.num_commands = 1;
  out.command_ids = {command};
  out.text = {text};
  return out;
}

std::set<std::string> Files(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.insert(entry.path().filename().string());
  return names;
}

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream all;
  all << in.rdbuf();
  return all.str();
}

TEST(LogOutput, ForgedOutputIsSkippedWithTheKeyAndNamedPlainlyWithout) {
  const std::string dir = ::testing::TempDir() + "/log_output_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string key_path = dir + "/procman.key";
  {
    std::ofstream key(key_path, std::ios::binary);
    key << std::string(32, 'k');
  }
  ASSERT_EQ(chmod(key_path.c_str(), 0600), 0);
  const sarmap::procman::Key key = sarmap::procman::LoadKeyFile(key_path);
  const std::string log_path = dir + "/attacked.lcmlog";
  {
    sarmap::logtools::LcmLogWriter log(log_path);
    sarmap::pm_info_t info{};
    info.header.frame = "procman";
    info.deputy_id = "robot";
    info.host = "robot";
    sarmap::pm_command_status_t c{};
    c.command_id = "sarmap-slam";
    info.commands = {c};
    info.num_commands = 1;
    sarmap::procman::SignInfo(key, &info);
    sarmap::pm_output_t genuine = Output("robot", "sarmap-slam", "mapping\n");
    sarmap::procman::SignOutput(key, &genuine);
    log.Write("PM_OUTPUT", genuine, 1000000);
    log.Write("PM_INFO", info, 1100000);
    // Forged lines of a real command, unsigned and signed with another key.
    log.Write("PM_OUTPUT", Output("robot", "sarmap-slam", "forged: diverged\n"), 1150000);
    sarmap::pm_output_t other_key = Output("robot", "sarmap-slam", "forged: stopping\n");
    sarmap::procman::SignOutput(sarmap::procman::Key(32, 'x'), &other_key);
    log.Write("PM_OUTPUT", other_key, 1160000);
    log.Write("PM_OUTPUT", Output("../../evil", "<script>alert(1)</script>", "forged\n"), 1200000);
    log.Write("PM_OUTPUT", Output(std::string(60000, 'C'), "x", "forged\n"), 1300000);
  }
  const std::string signed_dir = dir + "/signed", all_dir = dir + "/all";
  sarmap::testing::Process with_key(
      {"sarmap-log-output", log_path, "-o", signed_dir, "--key", key_path}, dir + "/with_key.txt");
  ASSERT_EQ(with_key.Wait(30), 0) << with_key.Output();
  EXPECT_EQ(Files(signed_dir), std::set<std::string>{"robot-sarmap-slam.txt"});
  EXPECT_EQ(Read(signed_dir + "/robot-sarmap-slam.txt"), "mapping\n");
  EXPECT_NE(with_key.Output().find("4 unsigned or forged output messages skipped"),
            std::string::npos)
      << with_key.Output();

  sarmap::testing::Process without_key({"sarmap-log-output", log_path, "-o", all_dir},
                                       dir + "/without_key.txt");
  ASSERT_EQ(without_key.Wait(30), 0) << without_key.Output();
  const std::set<std::string> names = Files(all_dir);
  EXPECT_EQ(names.size(), 3u);
  for (const std::string& name : names) {
    EXPECT_LE(name.size(), 124u) << name;
    EXPECT_EQ(name.find_first_not_of(
                  "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-._[]+"),
              std::string::npos)
        << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/evil-_script_alert_1___script_.txt"));
  std::filesystem::remove_all(dir);
}

}  // namespace
