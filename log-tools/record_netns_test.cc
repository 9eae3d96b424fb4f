// sarmap-log record as a process over real LCM (run in a private network namespace by CTest):
// it records POSE messages, survives LCM fragments with hostile headers (sarmap-net-fuzz
// --raw-lcm: among them the 57-byte fragment whose offset wraps past 2^32, which crashes an
// unguarded liblcm 1.3.1 receiver subscribed to the channel, as Debian's lcm-logger is), keeps
// recording after them, stops cleanly on SIGINT, and leaves a log that both lcm::LogFile (the
// reader of lcm-logplayer) and the sarmap log reader read to the end.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <set>
#include <string>
#include <thread>

#include "common/decode.h"
#include "common/node.h"
#include "common/testing/isolated_network.h"
#include "log-tools/lcm_log_reader.h"
#include "sarmap/image_t.hpp"
#include "sarmap/pose_t.hpp"
#include "tests/process.h"

namespace {

using sarmap::testing::Process;

void PublishPoses(lcm::LCM* lcm, int64_t first_seq, int count) {
  for (int i = 0; i < count; ++i) {
    sarmap::pose_t pose{};
    pose.header.seq = first_seq + i;
    pose.header.utime = 1000000 + pose.header.seq;
    pose.header.frame = "map";
    pose.child_frame = "base";
    pose.orientation[0] = 1;
    pose.node_id = -1;
    lcm->publish("POSE", &pose);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool WaitFor(const std::function<bool()>& done, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

class RecordTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sarmap::IsolatedNetwork())
      GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
    dir_ = ::testing::TempDir() + "/record-test-" + std::to_string(getpid());
    std::string ignored;
    sarmap::testing::RunCapture({"mkdir", "-p", dir_}, &ignored);
  }
  void TearDown() override {
    std::string ignored;
    if (!HasFailure() && !dir_.empty()) sarmap::testing::RunCapture({"rm", "-rf", dir_}, &ignored);
  }
  std::string dir_;
};

TEST_F(RecordTest, KeepsRecordingThroughHostileLcmFragmentsAndWritesAReadableLog) {
  const std::string log = dir_ + "/rec.lcmlog";
  Process recorder({"sarmap-log-record", "-o", log}, dir_ + "/recorder.txt");
  ASSERT_TRUE(WaitFor([&] { return recorder.Output().find("writing") != std::string::npos; }, 10))
      << recorder.Output();

  lcm::LCM lcm(sarmap::common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  constexpr int kBatch = 20;
  PublishPoses(&lcm, 0, kBatch);
  Process fuzz({"sarmap-net-fuzz", "--raw-lcm", "--seconds", "2", "--rate", "200", "--channels",
                "^(POSE|SCAN|ODOM|PEOPLE_MAP)$"},
               dir_ + "/net-fuzz.txt");
  ASSERT_EQ(fuzz.Wait(30), 0) << fuzz.Output();
  PublishPoses(&lcm, 1000, kBatch);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));

  ASSERT_TRUE(recorder.Running()) << "the recorder died in the raw datagrams (exit "
                                  << recorder.Wait(0) << "):\n"
                                  << recorder.Output() << "\nsent:\n"
                                  << fuzz.Output();
  recorder.Signal(SIGINT);
  EXPECT_EQ(recorder.Wait(10), 0) << recorder.Output();

  // The sarmap reader: no damage, and the poses of both batches decode.
  sarmap::logtools::LcmLogReader reader(log);
  sarmap::logtools::LogEvent event;
  std::set<int64_t> before, after;
  int64_t events = 0;
  while (reader.Next(&event)) {
    ++events;
    if (event.channel != "POSE") continue;
    sarmap::pose_t pose;
    if (!sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &pose)) continue;
    (pose.header.seq < 1000 ? before : after).insert(pose.header.seq);
  }
  EXPECT_TRUE(reader.problems().empty()) << reader.problems().front().what;
  // Loopback multicast loses nothing in practice; a margin keeps a busy machine from failing it.
  EXPECT_GE(static_cast<int>(before.size()), kBatch * 3 / 4);
  EXPECT_GE(static_cast<int>(after.size()), kBatch * 3 / 4) << "nothing recorded after the attack";

  // lcm::LogFile (what lcm-logplayer reads with) reads the same events to the end.
  lcm::LogFile file(log, "r");
  ASSERT_TRUE(file.good());
  int64_t lcm_events = 0;
  while (file.readNextEvent() != nullptr) ++lcm_events;
  EXPECT_EQ(lcm_events, events);
}

TEST_F(RecordTest, RefusesToOverwriteAndNumbersFilesWithIncrement) {
  const std::string log = dir_ + "/exists.lcmlog";
  std::string ignored;
  sarmap::testing::RunCapture({"touch", log}, &ignored);
  Process refused({"sarmap-log-record", "-o", log}, dir_ + "/refused.txt");
  EXPECT_NE(refused.Wait(10), 0) << refused.Output();
  EXPECT_NE(refused.Output().find("--force"), std::string::npos) << refused.Output();

  for (const char* name : {"/exists.lcmlog.00", "/exists.lcmlog.01"}) {
    Process numbered({"sarmap-log-record", "-o", log, "--increment"}, dir_ + "/numbered.txt");
    ASSERT_TRUE(WaitFor([&] { return access((dir_ + name).c_str(), F_OK) == 0; }, 10))
        << name << " not written:\n"
        << numbered.Output();
    numbered.Signal(SIGINT);
    EXPECT_EQ(numbered.Wait(10), 0) << numbered.Output();
  }
}

TEST_F(RecordTest, SplitMbStartsTheNextNumberedFileAndLosesNothing) {
  const std::string base = dir_ + "/split.lcmlog";
  Process recorder({"sarmap-log-record", "-o", base, "--split-mb", "0.002"}, dir_ + "/split.txt");
  ASSERT_TRUE(WaitFor([&] { return recorder.Output().find("writing") != std::string::npos; }, 10))
      << recorder.Output();
  lcm::LCM lcm(sarmap::common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  constexpr int kPoses = 20;  // about 400 bytes each: 2 kB files hold 5
  PublishPoses(&lcm, 0, kPoses);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  recorder.Signal(SIGINT);
  ASSERT_EQ(recorder.Wait(10), 0) << recorder.Output();
  int files = 0;
  std::set<int64_t> seqs;
  for (;; ++files) {
    char suffix[16];
    std::snprintf(suffix, sizeof(suffix), ".%02d", files);
    if (access((base + suffix).c_str(), F_OK) != 0) break;
    sarmap::logtools::LcmLogReader reader(base + suffix);
    sarmap::logtools::LogEvent event;
    int64_t bytes = 0;
    while (reader.Next(&event)) {
      bytes += 28 + event.channel.size() + event.data.size();
      sarmap::pose_t pose;
      if (event.channel == "POSE" &&
          sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &pose)) {
        EXPECT_EQ(seqs.count(pose.header.seq), 0u) << "pose " << pose.header.seq << " twice";
        seqs.insert(pose.header.seq);
      }
    }
    EXPECT_TRUE(reader.problems().empty()) << suffix;
    EXPECT_LE(bytes, static_cast<int64_t>(0.002 * 1024 * 1024)) << suffix << " past --split-mb";
  }
  EXPECT_GE(files, 3) << recorder.Output();
  EXPECT_GE(static_cast<int>(seqs.size()), kPoses * 3 / 4);
}

// With a profile: camera frames thinned by capture time (one per second, and the last), every
// other message whole, and the held messages written when the recorder stops.
TEST_F(RecordTest, AProfileThinsTheFramesAndKeepsEverythingElse) {
  const std::string log = dir_ + "/thin.lcmlog";
  Process recorder({"sarmap-log-record", "-o", log, "--profile", "config/record_long.yaml", "--set",
                    "hold_s=0.5", "--set", "frames.around_people_s=0"},
                   dir_ + "/thin.txt");
  ASSERT_TRUE(WaitFor([&] { return recorder.Output().find("writing") != std::string::npos; }, 10))
      << recorder.Output();
  lcm::LCM lcm(sarmap::common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  constexpr int kFrames = 60;  // capture times over 2 s: kept the first of each second and the last
  for (int i = 0; i < kFrames; ++i) {
    sarmap::image_t image{};
    image.header.seq = i;
    image.header.utime = 1000000 + i * 1000000 / 30;
    image.header.frame = "camera";
    lcm.publish("DEPTH", &image);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  PublishPoses(&lcm, 0, 20);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  recorder.Signal(SIGINT);
  ASSERT_EQ(recorder.Wait(10), 0) << recorder.Output();
  EXPECT_NE(recorder.Output().find("DEPTH"), std::string::npos) << recorder.Output();
  sarmap::logtools::LcmLogReader reader(log);
  sarmap::logtools::LogEvent event;
  std::set<int64_t> frames;
  int poses = 0;
  while (reader.Next(&event)) {
    int64_t utime, seq;
    if (event.channel == "DEPTH" && sarmap::logtools::ReadSarmapHeader(event.data, &utime, &seq))
      frames.insert(seq);
    if (event.channel == "POSE") ++poses;
  }
  EXPECT_TRUE(reader.problems().empty());
  EXPECT_EQ(frames, (std::set<int64_t>{0, 30, kFrames - 1})) << recorder.Output();
  EXPECT_GE(poses, 15);
}

}  // namespace
