// NodeReplay: a node adapter fed from a log decides on the log's clock, in the log's order,
// and what it publishes is captured during the input that caused it.
#include "log-tools/node_replay.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "common/decode.h"
#include "common/stamp_gate.h"
#include "log-tools/lcm_log_writer.h"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

constexpr int64_t kStartUs = 1700000000000000;  // receive time of the first event

// `n` POSE events 0.5 s apart (receive time = stamp, except event `far` whose stamp is an hour
// ahead of its arrival), each followed by an OTHER event; bytes of damage after event `n/2`.
std::string WriteLog(int n, int far) {
  const std::string path = ::testing::TempDir() + "/node_replay_test_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           std::to_string(getpid()) + ".lcmlog";
  {
    logtools::LcmLogWriter log(path);
    for (int i = 0; i < n; ++i) {
      sarmap::pose_t pose{};
      const int64_t receive_us = kStartUs + i * 500000;
      pose.header.utime = receive_us + (i == far ? 3600 * 1000000LL : 0);
      pose.header.seq = i;
      pose.header.frame = "map";
      pose.position_m[0] = i;
      pose.orientation[0] = 1;
      for (const char* channel : {"POSE", "OTHER"}) log.Write(channel, pose, receive_us);
    }
  }
  // Damage in the middle: what follows is still read.
  std::vector<char> bytes;
  {
    FILE* f = fopen(path.c_str(), "rb");
    fseek(f, 0, SEEK_END);
    bytes.resize(static_cast<size_t>(ftell(f)));
    fseek(f, 0, SEEK_SET);
    EXPECT_EQ(fread(bytes.data(), 1, bytes.size(), f), bytes.size());
    fclose(f);
  }
  const size_t middle = bytes.size() / 2;
  for (size_t k = middle; k < middle + 40; ++k) bytes[k] = 0x5a;
  FILE* f = fopen(path.c_str(), "wb");
  fwrite(bytes.data(), 1, bytes.size(), f);
  fclose(f);
  return path;
}

// A small adapter as the nodes are written: POSE through a stamp gate on the receive time, a
// 1 s timer that publishes how many poses it took.
class CountingNode {
 public:
  explicit CountingNode(common::Node* node)
      : node_(node), count_pub_(node->Advertise<sarmap::pose_t>("COUNT")) {
    node->Subscribe<sarmap::pose_t>("POSE", [this](const sarmap::pose_t& m,
                                                   const common::ReceiveInfo& info) {
      receive_s.push_back(info.receive_time_s);
      if (!gates_.Accept(0, m.header.utime, info.receive_time_s)) return;
      positions.push_back(m.position_m[0]);
    });
    node->AddTimer(1.0, [this] {
      sarmap::pose_t count{};
      count.header.utime = static_cast<int64_t>(node_->Now() * 1e6);
      count.header.frame = "map";
      count.orientation[0] = 1;
      count.position_m[0] = static_cast<double>(positions.size());
      count_pub_.Publish(&count);
    });
  }
  std::vector<double> receive_s, positions;

 private:
  common::Node* node_;
  common::StampGates gates_{common::StampGateOptions{}};
  common::Node::Publisher<sarmap::pose_t> count_pub_;
};

TEST(NodeReplay, TheAdapterDecidesOnTheLogsClockInTheLogsOrder) {
  const int n = 40, far = 7;
  common::Node node("node-replay-test", "memq://");
  CountingNode counting(&node);
  NodeReplay replay(&node);
  std::vector<std::pair<int64_t, double>> counts;  // (log time when published, poses so far)
  replay.Capture("COUNT", [&](const std::string& channel, const std::vector<uint8_t>& data) {
    sarmap::pose_t count;
    std::string why;
    ASSERT_TRUE(common::DecodeMessage(data.data(), data.size(), &count, &why)) << channel << why;
    counts.emplace_back(replay.now_us(), count.position_m[0]);
  });
  const NodeReplay::Stats stats = replay.Run(
      WriteLog(n, far), [](LogEvent* e) { return e->channel == "POSE"; }, false);

  EXPECT_FALSE(stats.problems.empty());  // the damage was read past...
  EXPECT_GT(stats.events_read, n);       // ... and both channels were read
  EXPECT_EQ(stats.events_fed, static_cast<int64_t>(counting.receive_s.size()));
  EXPECT_GE(stats.events_fed, n - 2);    // at most the damaged event or two are lost
  // Receive times are the log's, in order.
  for (size_t i = 0; i < counting.receive_s.size(); ++i) {
    EXPECT_GE(counting.receive_s[i], kStartUs * 1e-6);
    if (i > 0) {
      EXPECT_GT(counting.receive_s[i], counting.receive_s[i - 1]);
    }
  }
  // The stamp an hour ahead of its arrival is refused, as live; the others pass in order.
  for (size_t i = 0; i < counting.positions.size(); ++i) {
    EXPECT_NE(counting.positions[i], far);
    if (i > 0) {
      EXPECT_GT(counting.positions[i], counting.positions[i - 1]);
    }
  }
  EXPECT_EQ(counting.positions.size() + 1, counting.receive_s.size());
  // The timer runs on log time: one COUNT per second of the log (19.5 s), not per wall second,
  // each captured at the input that made it due, showing the poses taken by then.
  ASSERT_GE(counts.size(), 18u);
  EXPECT_LE(counts.size(), 20u);
  for (size_t k = 1; k < counts.size(); ++k) {
    EXPECT_NEAR((counts[k].first - counts[k - 1].first) * 1e-6, 1.0, 0.5 + 1e-9);
    EXPECT_GE(counts[k].second, counts[k - 1].second);
  }
  EXPECT_NEAR(counts.back().second, static_cast<double>(counting.positions.size()), 2.0);
}

// Inputs that are not in the log (poses from a file, the truth) go in at the present log time,
// between the log's own, as `feed` sees the events.
TEST(NodeReplay, InjectedInputsArriveAtTheirPlaceAmongTheLogs) {
  common::Node node("node-replay-test", "memq://");
  CountingNode counting(&node);
  NodeReplay replay(&node);
  int injected = 0;
  replay.Run(
      WriteLog(10, -1),
      [&](LogEvent* e) {
        if (e->channel != "OTHER") return e->channel == "POSE";
        sarmap::pose_t pose{};
        pose.header.utime = e->timestamp_us;
        pose.header.frame = "map";
        pose.orientation[0] = 1;
        pose.position_m[0] = 100 + injected++;
        std::vector<uint8_t> data(pose.getEncodedSize());
        pose.encode(data.data(), 0, static_cast<int>(data.size()));
        replay.Inject("POSE", data);
        return false;
      },
      false);
  ASSERT_GE(injected, 8);
  ASSERT_EQ(counting.positions.size(), counting.receive_s.size());
  // Log pose i, then the injected one made at the OTHER event after it.
  int next_log = 0, next_injected = 100;
  for (double x : counting.positions) {
    if (x >= 100) {
      EXPECT_EQ(x, next_injected++);
    } else {
      EXPECT_GE(x, next_log);
      next_log = static_cast<int>(x) + 1;
      EXPECT_EQ(next_injected - 100, static_cast<int>(x));  // before its own injected pose
    }
  }
  EXPECT_EQ(next_injected, 100 + injected);
}

// A replay that feeds none of the log's events itself, only injects them or inputs made from
// them, still runs on the log's clock from the first one.
TEST(NodeReplay, InjectedInputsAloneRunOnTheLogsClock) {
  common::Node node("node-replay-test", "memq://");
  CountingNode counting(&node);
  NodeReplay replay(&node);
  int counts = 0;
  replay.Capture("COUNT", [&](const std::string&, const std::vector<uint8_t>&) { ++counts; });
  const auto stats = replay.Run(
      WriteLog(10, -1),
      [&](LogEvent* e) {
        if (e->channel == "OTHER") replay.Inject("POSE", e->data);
        return false;
      },
      false);
  EXPECT_EQ(stats.events_fed, 0);
  ASSERT_GE(counting.receive_s.size(), 8u);
  EXPECT_DOUBLE_EQ(counting.receive_s.front(), kStartUs * 1e-6);
  for (size_t k = 1; k < counting.receive_s.size(); ++k)
    EXPECT_GE(counting.receive_s[k], counting.receive_s[k - 1]);
  EXPECT_EQ(counting.positions.size(), counting.receive_s.size());  // none held off the clock
  EXPECT_GE(counts, 3);  // its 1 s timer ran on the log's 4.5 s
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
