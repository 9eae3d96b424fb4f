// sarmap-log echo end to end: a log written with LcmLogWriter, printed by the tool through the
// sarmap-log front end.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "log-tools/lcm_log_writer.h"
#include "log-tools/lcm_schema.h"
#include "sarmap/image_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"

namespace {

using Json = nlohmann::json;
const std::string kBin = SARMAP_BIN_DIR;

struct ToolRun {
  int exit_code = -1;
  std::vector<std::string> lines;  // stdout
};

ToolRun RunTool(const std::string& args) {
  ToolRun run;
  const std::string err = ::testing::TempDir() + "/echo_stderr_" + std::to_string(getpid());
  FILE* pipe = popen((kBin + "/sarmap-log " + args + " 2>" + err).c_str(), "r");
  std::string out;
  char buf[65536];
  while (size_t n = fread(buf, 1, sizeof(buf), pipe)) out.append(buf, n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  size_t start = 0;
  for (size_t nl; (nl = out.find('\n', start)) != std::string::npos; start = nl + 1) {
    run.lines.push_back(out.substr(start, nl - start));
  }
  return run;
}

// The message encoded, its last `cut` bytes left out (a message cut short).
template <class T>
void Write(sarmap::logtools::LcmLogWriter* log, const std::string& channel, const T& msg,
           int64_t utime, int cut = 0) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  buf.resize(buf.size() - cut);
  log->WriteBytes(channel, buf, utime);
}

// 0 s: PEOPLE_VISUAL (one person), DEPTH (a VGA image), 1 s: JUNK (no sarmap type),
// 2 s: POSE cut short, 3 s: PEOPLE_VISUAL (nobody).
std::string WriteLog() {
  const std::string path = ::testing::TempDir() + "/echo_test_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           std::to_string(getpid()) + ".lcmlog";
  sarmap::logtools::LcmLogWriter log(path);
  const int64_t t0 = 1700000000000000;
  sarmap::people_detections_t people{};
  people.header.utime = t0 - 30000;
  people.header.frame = "camera";
  people.sensor_id = "camera";
  people.num_detections = 1;
  people.detections.resize(1);
  people.detections[0].track_id = 3;
  people.detections[0].cue = sarmap::person_detection_t::CUE_SEEN_DEPTH;
  people.detections[0].has_range = true;
  people.detections[0].position_m[0] = 0.4;
  people.detections[0].position_m[2] = 2.75;
  people.detections[0].height_m = 1.25f;
  people.detections[0].confidence = 0.875f;
  Write(&log, "PEOPLE_VISUAL", people, t0);
  sarmap::image_t depth{};
  depth.width = 640;
  depth.height = 480;
  depth.size = 640 * 480 * 2;
  depth.data.assign(depth.size, 7);
  Write(&log, "DEPTH", depth, t0 + 10000);
  const uint8_t junk[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  log.WriteBytes("JUNK", junk, sizeof(junk), t0 + 1000000);
  sarmap::pose_t pose{};
  pose.header.frame = "map";
  Write(&log, "POSE", pose, t0 + 2000000, 20);
  people.num_detections = 0;
  people.detections.clear();
  Write(&log, "PEOPLE_VISUAL", people, t0 + 3000000);
  return path;
}

TEST(LogEchoTest, PrintsEveryMessageAsOneJsonLineAndGoesOnAfterBadOnes) {
  const std::string log = WriteLog();
  const ToolRun run = RunTool("echo " + log);
  EXPECT_EQ(run.exit_code, 0);
  ASSERT_EQ(run.lines.size(), 5u);
  std::vector<Json> lines;
  for (const auto& l : run.lines) lines.push_back(Json::parse(l));

  EXPECT_EQ(lines[0]["channel"], "PEOPLE_VISUAL");
  EXPECT_EQ(lines[0]["type"], "sarmap.people_detections_t");
  EXPECT_EQ(lines[0]["recv_utime"], 1700000000000000);
  EXPECT_EQ(lines[0]["t_s"], 0);
  const Json& person = lines[0]["msg"]["detections"][0];
  EXPECT_EQ(person["position_m"], Json::parse("[0.4, 0, 2.75]"));
  EXPECT_EQ(person["cue_name"], "CUE_SEEN_DEPTH");
  EXPECT_EQ(person["height_m"], 1.25);
  EXPECT_EQ(person["confidence"], 0.875);

  // The depth payload is summarised by default, not printed.
  EXPECT_EQ(lines[1]["msg"]["data"]["length"], 614400);
  EXPECT_LT(run.lines[1].size(), 2000u);

  EXPECT_EQ(lines[2]["channel"], "JUNK");
  EXPECT_EQ(lines[2]["size"], 9);
  EXPECT_EQ(lines[2]["error"].get<std::string>().find("unknown type (fingerprint"), 0u);
  EXPECT_FALSE(lines[2].contains("msg"));
  EXPECT_FALSE(lines[0].contains("refused"));

  EXPECT_EQ(lines[3]["type"], "sarmap.pose_t");
  EXPECT_NE(lines[3]["error"].get<std::string>().find("left"), std::string::npos) << lines[3];

  EXPECT_EQ(lines[4]["t_s"], 3);
  EXPECT_EQ(lines[4]["msg"]["detections"], Json::array());
}

TEST(LogEchoTest, ADamagedLogIsReadPastTheDamageAndExitsThree) {
  const std::string log = WriteLog();
  std::filesystem::resize_file(log, std::filesystem::file_size(log) - 10);  // cut the last event
  const ToolRun run = RunTool("echo " + log);
  EXPECT_EQ(run.exit_code, 3);
  ASSERT_EQ(run.lines.size(), 4u);
  EXPECT_EQ(Json::parse(run.lines[3])["channel"], "POSE");
}

TEST(LogEchoTest, SelectsChannelsTimesAndCount) {
  const std::string log = WriteLog();
  ToolRun run = RunTool("echo " + log + " --channel PEOPLE_VISUAL");
  ASSERT_EQ(run.lines.size(), 2u);
  run = RunTool("echo " + log + " --channel 'PEOPLE_.*' --limit 1");
  ASSERT_EQ(run.lines.size(), 1u);
  EXPECT_EQ(Json::parse(run.lines[0])["t_s"], 0);
  run = RunTool("echo " + log + " --from 0.5 --to 2.5");
  ASSERT_EQ(run.lines.size(), 2u);
  EXPECT_EQ(Json::parse(run.lines[0])["channel"], "JUNK");
  EXPECT_EQ(Json::parse(run.lines[1])["channel"], "POSE");
  run = RunTool("echo " + log + " --channel DEPTH --full");
  ASSERT_EQ(run.lines.size(), 1u);
  EXPECT_EQ(Json::parse(run.lines[0])["msg"]["data"].size(), 614400u);
  run = RunTool("echo " + log + " --channel PEOPLE_VISUAL --limit 1 --pretty");
  EXPECT_GT(run.lines.size(), 20u);  // one object over many lines
  EXPECT_EQ(run.lines.front(), "{");
}

TEST(LogEchoTest, SaysWhyANodeWouldRefuseAMessage) {
  const std::string path =
      ::testing::TempDir() + "/echo_refused_" + std::to_string(getpid()) + ".lcmlog";
  {
    sarmap::logtools::LcmLogWriter log(path);
    sarmap::people_detections_t people{};
    people.header.frame = "camera";
    people.num_detections = 1;
    people.detections.resize(1);
    people.detections[0].cue = sarmap::person_detection_t::CUE_SEEN_RGBD;
    people.detections[0].confidence = 1.5f;  // not a probability
    Write(&log, "PEOPLE_VISUAL", people, 1000);
    people.detections[0].confidence = 0.5f;
    Write(&log, "PEOPLE_VISUAL", people, 2000);
  }
  ToolRun run = RunTool("echo " + path);
  ASSERT_EQ(run.lines.size(), 2u);
  const Json refused = Json::parse(run.lines[0]);
  EXPECT_EQ(refused["msg"]["detections"][0]["confidence"], 1.5);
  EXPECT_NE(refused["refused"].get<std::string>().find("confidence"), std::string::npos) << refused;
  EXPECT_FALSE(Json::parse(run.lines[1]).contains("refused"));
  run = RunTool("echo " + path + " --no-check");
  EXPECT_FALSE(Json::parse(run.lines[0]).contains("refused"));
}

TEST(LogEchoTest, ReadsTheLiveBusThroughLcm) {
  // LCM's file provider plays a log into the process as if it arrived on the bus.
  const std::string log = WriteLog();
  const ToolRun run = RunTool("echo --live --lcm-url 'file://" + log +
                              "?speed=0' --channel PEOPLE_VISUAL --limit 2");
  EXPECT_EQ(run.exit_code, 0);
  ASSERT_EQ(run.lines.size(), 2u);
  EXPECT_EQ(Json::parse(run.lines[0])["msg"]["detections"][0]["track_id"], 3);
  // Without --limit the played log's end ends the tool.
  const ToolRun all = RunTool("echo --live --lcm-url 'file://" + log + "?speed=0'");
  EXPECT_EQ(all.exit_code, 0);
  EXPECT_EQ(all.lines.size(), 5u);
}

TEST(LogEchoTest, ReadsTypesOfAnotherPackageFromTypesDir) {
  const std::string dir = ::testing::TempDir() + "/echo_types_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  const char kPing[] = "package demo;\nstruct ping_t {\n  int32_t n;\n  string s;\n}\n";
  std::ofstream(dir + "/ping_t.lcm") << kPing;
  sarmap::logtools::LcmTypeSet types;
  std::vector<std::string> errors;
  ASSERT_TRUE(types.AddText(kPing, "ping_t.lcm", &errors));
  ASSERT_TRUE(types.Resolve(&errors));
  // fingerprint, n = 5, s = "hi" (length with the NUL), big-endian.
  std::vector<uint8_t> bytes;
  const uint64_t fingerprint = types.Find("demo.ping_t")->fingerprint;
  for (int i = 7; i >= 0; --i) bytes.push_back(static_cast<uint8_t>(fingerprint >> (8 * i)));
  for (int b : {0, 0, 0, 5, 0, 0, 0, 3, int{'h'}, int{'i'}, 0})
    bytes.push_back(static_cast<uint8_t>(b));
  const std::string log = dir + "/ping.lcmlog";
  {
    sarmap::logtools::LcmLogWriter file(log);
    file.WriteBytes("PING", bytes, 1);
  }
  ToolRun run = RunTool("echo " + log + " --types " + dir);
  ASSERT_EQ(run.lines.size(), 1u);
  EXPECT_EQ(Json::parse(run.lines[0])["type"], "demo.ping_t");
  EXPECT_EQ(Json::parse(run.lines[0])["msg"], Json::parse(R"({"n": 5, "s": "hi"})"));
  // Not among sarmap's types.
  run = RunTool("echo " + log);
  ASSERT_EQ(run.lines.size(), 1u);
  EXPECT_TRUE(Json::parse(run.lines[0]).contains("error"));
}

TEST(LogEchoTest, BadArgumentsAndTypesAreClearErrors) {
  EXPECT_EQ(RunTool("echo /no/such.lcmlog").exit_code, 2);
  EXPECT_EQ(RunTool("echo").exit_code, 2);
  const std::string log = WriteLog();
  EXPECT_EQ(RunTool("echo " + log + " --live").exit_code, 2);
  EXPECT_EQ(RunTool("echo " + log + " --channel '('").exit_code, 2);
  EXPECT_EQ(RunTool("echo " + log + " --types /no/such/dir").exit_code, 2);
  // The front end lists the subcommand.
  const ToolRun help = RunTool("--help");
  bool listed = false;
  for (const auto& l : help.lines) listed = listed || l == "  echo";
  EXPECT_TRUE(listed);
}

}  // namespace
