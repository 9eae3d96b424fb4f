// Cross-process tests over real LCM UDP multicast. Run by CTest inside a private network
// namespace (tests/harness/sarmap-netns); they refuse to run outside one.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <random>
#include <regex>
#include <thread>

#include "common/channels.h"
#include "common/node.h"
#include "common/testing/isolated_network.h"
#include "sarmap/message_samples.h"
#include "tests/fuzz/samples.h"
#include "tests/process.h"

namespace sarmap {
namespace testing {
namespace {

class MultiProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sarmap::IsolatedNetwork()) {
      GTEST_FAIL() << "run through tests/harness/sarmap-netns (ctest does): multi-process tests "
                      "must not use a real network";
    }
    dir_ = ::testing::TempDir() + "/mp-" + std::to_string(getpid());
    std::string ignored;
    RunCapture({"mkdir", "-p", dir_}, &ignored);
  }
  std::string dir_;
};

// Raw receiver in the test process: stores the last payload per channel.
class RawSink {
 public:
  explicit RawSink(lcm::LCM* lcm, const std::string& regex) : lcm_(lcm) {
    lcm_->subscribe(regex, &RawSink::Handle, this);
  }
  void Handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    last_[channel].assign(p, p + rbuf->data_size);
    ++counts_[channel];
  }
  // Handles messages until `done` or the timeout.
  template <class Pred>
  bool SpinUntil(Pred done, double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      lcm_->handleTimeout(20);
    }
    return true;
  }
  std::map<std::string, std::vector<uint8_t>> last_;
  std::map<std::string, int> counts_;

 private:
  lcm::LCM* lcm_;
};

TEST_F(MultiProcessTest, EveryMessageTypeRoundTripsBetweenTwoProcesses) {
  Process echo({"sarmap-test-peer", "echo", "--prefix", "RT_"}, dir_ + "/echo.log");
  lcm::LCM lcm(common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  RawSink sink(&lcm, "RT_ECHO_.*");
  // Wait until the echo process is subscribed: ping with a header until it answers.
  sarmap::header_t ping{};
  ping.frame = "ping";
  sarmap::pose_t probe{};
  probe.orientation[0] = 1;
  ASSERT_TRUE(sink.SpinUntil(
      [&] {
        lcm.publish("RT_pose_t", &probe);
        return sink.counts_.count("RT_ECHO_pose_t") > 0;
      },
      10))
      << echo.Output();

  std::mt19937_64 rng(42);
  int types = 0;
#define SARMAP_ROUND_TRIP(T)                                                            \
  for (int i = 0; i < 3; ++i) {                                                         \
    sarmap::T m;                                                                        \
    sarmap::samples::Fill(m, rng);                                                      \
    m.header.utime = std::abs(m.header.utime);                                          \
    m.header.seq = i;                                                                   \
    /* only messages that pass the receiver's checks are echoed; make them sane */      \
    const auto sent = Encode(m);                                                        \
    lcm.publish("RT_" #T, sent.data(), static_cast<unsigned>(sent.size()));             \
    const bool plausible = common::CheckMessage(m).empty();                             \
    if (plausible) {                                                                    \
      ASSERT_TRUE(sink.SpinUntil([&] { return sink.last_["RT_ECHO_" #T] == sent; }, 5)) \
          << #T << " did not come back intact";                                         \
    }                                                                                   \
  }                                                                                     \
  ++types;
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_ROUND_TRIP)
#undef SARMAP_ROUND_TRIP
  EXPECT_GE(types, 20);
}

// Random samples are often implausible (random enums, counts); this checks that sane,
// hand-made instances of every type do round-trip, so none is only ever filtered out.
TEST_F(MultiProcessTest, SaneInstancesOfEveryTypeRoundTrip) {
  Process echo({"sarmap-test-peer", "echo", "--prefix", "RS_"}, dir_ + "/echo2.log");
  lcm::LCM lcm(common::DefaultLcmUrl());
  RawSink sink(&lcm, "RS_ECHO_.*");
  sarmap::pose_t probe{};
  probe.orientation[0] = 1;
  ASSERT_TRUE(sink.SpinUntil(
      [&] {
        lcm.publish("RS_pose_t", &probe);
        return sink.counts_.count("RS_ECHO_pose_t") > 0;
      },
      10));
  std::mt19937_64 rng(1);
  int sane = 0;
  // Draw samples until one passes the checks, per type, with fixes for enum/count fields.
#define SARMAP_SANE(T)                                                                         \
  {                                                                                            \
    bool done = false;                                                                         \
    for (int attempt = 0; attempt < 2000 && !done; ++attempt) {                                \
      sarmap::T m;                                                                             \
      sarmap::samples::Fill(m, rng);                                                           \
      SaneUp(&m);                                                                              \
      if (!common::CheckMessage(m).empty()) continue;                                          \
      const auto sent = Encode(m);                                                             \
      lcm.publish("RS_" #T, sent.data(), static_cast<unsigned>(sent.size()));                  \
      ASSERT_TRUE(sink.SpinUntil([&] { return sink.last_["RS_ECHO_" #T] == sent; }, 5)) << #T; \
      done = true;                                                                             \
      ++sane;                                                                                  \
    }                                                                                          \
    EXPECT_TRUE(done) << "no sane sample of " #T;                                              \
  }
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_SANE)
#undef SARMAP_SANE
  int expected = 0;
#define SARMAP_COUNT(T) ++expected;
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_COUNT)
#undef SARMAP_COUNT
  EXPECT_EQ(sane, expected);
}

TEST_F(MultiProcessTest, DepthAndRgbAt30HzFor10sArriveWithZeroLoss) {
  Process sink({"sarmap-test-peer", "sink", "--seconds", "30"}, dir_ + "/sink.log");
  for (int i = 0; i < 200 && sink.Output().find("ready") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  Process stream({"sarmap-test-peer", "stream", "--seconds", "10", "--rate", "30"},
                 dir_ + "/stream.log");
  ASSERT_EQ(stream.Wait(30), 0) << stream.Output();
  ASSERT_EQ(sink.Wait(30), 0) << sink.Output();
  const std::string out = sink.Output();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m,
                                std::regex("depth (\\d+) rgb (\\d+) depth_gaps (\\d+) rgb_gaps "
                                           "(\\d+) decode_errors (\\d+) dropped (\\d+)")))
      << out;
  EXPECT_EQ(std::stoi(m[1]), 300) << out;
  EXPECT_EQ(std::stoi(m[2]), 300) << out;
  EXPECT_EQ(std::stoi(m[3]), 0);
  EXPECT_EQ(std::stoi(m[4]), 0);
  EXPECT_EQ(std::stoi(m[5]), 0);
  EXPECT_EQ(std::stoi(m[6]), 0);
}

TEST_F(MultiProcessTest, NodeSurvivesMalformedStreamsAndCountsWhatItDropped) {
  Process monitor({"sarmap-monitor", "--set", "print_period_s=0"}, dir_ + "/monitor.log");
  lcm::LCM lcm(common::DefaultLcmUrl());
  // Listen to the monitor's own status to know it is up.
  int64_t dropped = -1, received = -1;
  struct StatusSink {
    int64_t* dropped;
    int64_t* received;
    void Handle(const lcm::ReceiveBuffer*, const std::string&, const sarmap::node_status_t* s) {
      if (s->node_name != "sarmap-monitor") return;
      *dropped = 0;
      *received = 0;
      for (const auto& c : s->channels) {
        *dropped += c.dropped_malformed;
        *received += c.received;
      }
    }
  } status_sink{&dropped, &received};
  lcm.subscribe("NODE_STATUS", &StatusSink::Handle, &status_sink);
  const auto spin_until = [&](auto pred, double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!pred() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);
    return pred();
  };
  ASSERT_TRUE(spin_until([&] { return dropped == 0; }, 10)) << monitor.Output();

  std::string fuzz_out;
  ASSERT_EQ(RunCapture({"sarmap-test-peer", "fuzz", "--count", "20"}, &fuzz_out), 0) << fuzz_out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(fuzz_out, m, std::regex("sent (\\d+)")));
  const int64_t sent = std::stoll(m[1]);
  EXPECT_GT(sent, 20 * 2 * 20);
  ASSERT_TRUE(monitor.Running()) << monitor.Output();
  ASSERT_TRUE(spin_until([&] { return dropped == sent; }, 10))
      << "monitor reports " << dropped << " dropped of " << sent << " sent";
  EXPECT_EQ(received, 0);

  // Still works: a valid message is received.
  sarmap::odometry_t odom{};
  odom.orientation[0] = 1;
  lcm.publish("ODOM", &odom);
  EXPECT_TRUE(spin_until([&] { return received == 1; }, 10));
  // And it stops cleanly on SIGINT.
  monitor.Signal(SIGINT);
  EXPECT_EQ(monitor.Wait(10), 0);
  EXPECT_NE(monitor.Output().find("dropped a message on"), std::string::npos);
}

TEST_F(MultiProcessTest, LogInfoReportsWhatWasSentAndWhereATruncatedLogBreaks) {
  const std::string log = dir_ + "/info.lcmlog";
  Process logger({"sarmap-log-record", "-o", log, "--force"}, dir_ + "/logger.log");
  lcm::LCM lcm(common::DefaultLcmUrl());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // logger subscribed
  for (int i = 0; i < 40; ++i) {
    sarmap::pose_t pose{};
    pose.orientation[0] = 1;
    pose.header.utime = 1000000 + 50000 * i;
    pose.header.seq = i < 20 ? i : i + 3;  // 3 lost messages
    lcm.publish("POSE", &pose);
    if (i % 2 == 0) {
      sarmap::velocity_command_t cmd{};
      cmd.header.seq = i / 2;
      lcm.publish("CMD_VEL", &cmd);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  logger.Signal(SIGINT);
  ASSERT_GE(logger.Wait(10), 0) << logger.Output();

  std::string out;
  ASSERT_EQ(RunCapture({"sarmap-log", "info", log}, &out), 0) << out;
  EXPECT_TRUE(
      std::regex_search(out, std::regex("POSE\\s+pose_t\\s+40\\s+[0-9.]+\\s+[0-9.]+\\s+3\\s")))
      << out;
  EXPECT_TRUE(std::regex_search(out, std::regex("CMD_VEL\\s+velocity_command_t\\s+20\\s"))) << out;
  EXPECT_TRUE(std::regex_search(out, std::regex("events\\s+60"))) << out;

  // A copy cut in the middle of an event: the readable part and the break are reported.
  std::ifstream in(log, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string cut = dir_ + "/cut.lcmlog";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3 + 7);
  ASSERT_EQ(RunCapture({"sarmap-log", "info", cut}, &out), 3) << out;
  EXPECT_NE(out.find("the log is damaged"), std::string::npos) << out;
  EXPECT_TRUE(
      std::regex_search(out, std::regex("breaks at byte \\d+ \\(after event \\d+\\): truncated")))
      << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("events\\s+(\\d+)"))) << out;
  EXPECT_GT(std::stoi(m[1]), 30);
  EXPECT_LT(std::stoi(m[1]), 60);

  EXPECT_EQ(RunCapture({"sarmap-log", "info", dir_ + "/missing.lcmlog"}, &out), 1);
  EXPECT_NE(out.find("cannot open"), std::string::npos) << out;
}

}  // namespace
}  // namespace testing
}  // namespace sarmap
