#include "log-tools/stack_perf.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace logtools {
namespace {

TEST(StackPerfTest, MeansPerProcessAndExcludesTheSimulator) {
  StackPerf perf;
  for (int i = 0; i < 10; ++i) {
    perf.AddCommandSample("localhost", "sarmap-slam", true, 20.0 + i, 100000000 + i, 0);
    perf.AddCommandSample("localhost", "sarmap-sim", true, 80.0, 50000000, 0);
    // Stopped samples do not count towards the mean.
    perf.AddCommandSample("localhost", "sarmap-speech", i < 5, i < 5 ? 10.0 : 99.0, 1000, i < 5 ? 0 : 1);
    perf.AddMachineLoad(0.5);
  }
  const StackPerfSummary s = perf.Summarise();
  ASSERT_EQ(s.processes.size(), 3u);
  const ProcessUsage& sim = s.processes[0];
  const ProcessUsage& slam = s.processes[1];
  const ProcessUsage& speech = s.processes[2];
  EXPECT_EQ(sim.command, "localhost/sarmap-sim");
  EXPECT_TRUE(sim.excluded);
  EXPECT_NEAR(slam.mean_cpu_percent, 24.5, 1e-9);
  EXPECT_NEAR(slam.p95_cpu_percent, 29.0, 1e-9);
  EXPECT_NEAR(slam.max_rss_mb, 100.000009, 1e-9);
  EXPECT_EQ(speech.samples, 5);
  EXPECT_NEAR(speech.mean_cpu_percent, 10.0, 1e-9);
  EXPECT_EQ(speech.restarts, 1);
  EXPECT_NEAR(s.stack_cpu_percent, 34.5, 1e-9);
  EXPECT_NEAR(s.excluded_cpu_percent, 80.0, 1e-9);
  EXPECT_NEAR(s.machine_load_percent, 50.0, 1e-9);
}

TEST(StackPerfTest, WindowsOfALongMission) {
  StackPerf perf;
  perf.SetPeriod(10.0, 12.0);
  const int64_t start_us = 1700000000000000;
  // 25 s of reports, one per second: SLAM's CPU is 10 % in the first window, 30 % after; its
  // memory grows by 1 MB a second. The simulator (excluded) runs at 90 %.
  for (int i = 0; i < 25; ++i) {
    const int64_t t = start_us + i * 1000000 + 3000;  // a report's jitter stays in its second
    perf.AddCommandSample("localhost", "sarmap-slam", true, i < 10 ? 10.0 : 30.0,
                          (100 + i) * 1000000LL, 0, t);
    perf.AddCommandSample("localhost", "sarmap-sim", true, 90.0, 5000000, 0, t);
    // The speech node is stopped from 15 s on: its samples do not count.
    perf.AddCommandSample("localhost", "sarmap-speech", i < 15, i < 15 ? 5.0 : 99.0, 1000000, 0, t);
  }
  const StackPerfSummary s = perf.Summarise();
  ASSERT_EQ(s.windows.size(), 3u);
  EXPECT_DOUBLE_EQ(s.windows[0].start_s, 0.0);
  EXPECT_DOUBLE_EQ(s.windows[1].start_s, 10.0);
  EXPECT_NEAR(s.windows[2].end_s, 24.0, 1e-9);
  const auto find = [&](const PerfWindow& w, const std::string& name) -> const WindowUsage* {
    for (const auto& p : w.processes)
      if (p.command == name) return &p;
    return nullptr;
  };
  const WindowUsage* slam0 = find(s.windows[0], "localhost/sarmap-slam");
  const WindowUsage* slam1 = find(s.windows[1], "localhost/sarmap-slam");
  ASSERT_NE(slam0, nullptr);
  ASSERT_NE(slam1, nullptr);
  EXPECT_EQ(slam0->samples, 10);
  EXPECT_NEAR(slam0->mean_cpu_percent, 10.0, 1e-9);
  EXPECT_NEAR(slam1->mean_cpu_percent, 30.0, 1e-9);
  EXPECT_NEAR(slam0->rss_end_mb, 109.0, 1e-9);
  EXPECT_NEAR(slam1->rss_end_mb, 119.0, 1e-9);
  EXPECT_TRUE(find(s.windows[0], "localhost/sarmap-sim")->excluded);
  // Window 2 (20-24 s): the speech node is not running.
  EXPECT_EQ(find(s.windows[2], "localhost/sarmap-speech"), nullptr);
  const WindowUsage* speech1 = find(s.windows[1], "localhost/sarmap-speech");
  ASSERT_NE(speech1, nullptr);
  EXPECT_EQ(speech1->samples, 5);
  // The stack without the simulator: 15 % per second in window 0, 35 % then 30 % in window 1.
  EXPECT_NEAR(s.windows[0].stack_cpu_mean_percent, 15.0, 1e-9);
  EXPECT_NEAR(s.windows[0].stack_cpu_p95_percent, 15.0, 1e-9);
  EXPECT_NEAR(s.windows[1].stack_cpu_mean_percent, 32.5, 1e-9);
  EXPECT_NEAR(s.windows[1].stack_cpu_p95_percent, 35.0, 1e-9);
  EXPECT_NEAR(s.windows[2].stack_cpu_mean_percent, 30.0, 1e-9);
  // Memory from 12 s on: SLAM 112 -> 124 MB.
  EXPECT_DOUBLE_EQ(s.compare_from_s, 12.0);
  bool found_slam = false;
  for (const auto& g : s.rss_growth)
    if (g.command == "localhost/sarmap-slam") {
      found_slam = true;
      EXPECT_NEAR(g.rss_then_mb, 112.0, 1e-9);
      EXPECT_NEAR(g.rss_end_mb, 124.0, 1e-9);
    }
  EXPECT_TRUE(found_slam);
  EXPECT_NE(StackPerfText(s).find("memory at 12 s and at the end"), std::string::npos);
}

TEST(StackPerfTest, InputsLostAreCountedPerNodeAcrossRestartsAndPerWindow) {
  StackPerf perf;
  perf.SetPeriod(10.0, 3600.0);
  const int64_t start_us = 1000000;
  for (int i = 0; i < 20; ++i) {
    const int64_t t = start_us + i * 1000000LL;
    perf.AddCommandSample("localhost", "sarmap-slam", true, 10.0, 1000000, 0, t);
    // SLAM (pid 10) receives 30 scans a second and loses 2 at 5 s; it restarts at 12 s as pid 11
    // and counts from zero again, losing 1 more at 15 s.
    if (i < 12)
      perf.AddNodeInput("sarmap-slam", 10, "SCAN", 30 * (i + 1), 0, 0, i >= 5 ? 2 : 0, t);
    else
      perf.AddNodeInput("sarmap-slam", 11, "SCAN", 30 * (i - 11), 0, 0, i >= 15 ? 1 : 0, t);
    perf.AddNodeInput("sarmap-people-map", 20, "PEOPLE_VISUAL", 10 * (i + 1), i >= 3 ? 1 : 0, 0, 0,
                      t);
  }
  const StackPerfSummary s = perf.Summarise();
  ASSERT_EQ(s.inputs.size(), 2u);
  const InputUsage& map = s.inputs[0];
  const InputUsage& slam = s.inputs[1];
  EXPECT_EQ(map.node, "sarmap-people-map");
  EXPECT_EQ(map.received, 200);
  EXPECT_EQ(map.dropped_malformed, 1);
  EXPECT_EQ(map.sequence_gaps, 0);
  EXPECT_EQ(slam.channel, "SCAN");
  EXPECT_EQ(slam.received, 360 + 240);
  EXPECT_EQ(slam.sequence_gaps, 3);
  ASSERT_EQ(s.windows.size(), 2u);
  EXPECT_EQ(s.windows[0].input_sequence_gaps, 2);
  EXPECT_EQ(s.windows[1].input_sequence_gaps, 1);
  EXPECT_EQ(s.windows[0].inputs_received + s.windows[1].inputs_received, 600 + 200);
  EXPECT_NE(StackPerfText(s).find("3 messages never handled"), std::string::npos);
  // Each window shows each node's last summary in it.
  StackPerf texts;
  texts.SetPeriod(10.0, 3600.0);
  for (int i = 0; i < 15; ++i) {
    const int64_t t = start_us + i * 1000000LL;
    texts.AddCommandSample("localhost", "sarmap-slam", true, 10.0, 1000000, 0, t);
    texts.AddNodeStatusText("sarmap-slam", "nodes " + std::to_string(i), t);
  }
  const StackPerfSummary st = texts.Summarise();
  ASSERT_EQ(st.windows.size(), 2u);
  ASSERT_EQ(st.windows[0].node_status.size(), 1u);
  EXPECT_EQ(st.windows[0].node_status[0].second, "nodes 9");
  EXPECT_EQ(st.windows[1].node_status[0].second, "nodes 14");
}

TEST(StackPerfTest, NoWindowsWithoutAPeriodOrBeforeTheComparisonTime) {
  StackPerf plain;
  plain.AddCommandSample("localhost", "sarmap-slam", true, 10.0, 1000000, 0, 5000000);
  EXPECT_TRUE(plain.Summarise().windows.empty());
  StackPerf short_log;
  short_log.SetPeriod(600.0, 3600.0);
  for (int i = 0; i < 3; ++i)
    short_log.AddCommandSample("localhost", "sarmap-slam", true, 10.0, 1000000, 0, i * 1000000LL);
  const StackPerfSummary s = short_log.Summarise();
  EXPECT_EQ(s.windows.size(), 1u);
  EXPECT_TRUE(s.rss_growth.empty());
}

TEST(StackPerfTest, LatencyMatchesFramesByCaptureTimeAndKeepsTheFirstUpdate) {
  StackPerf perf;
  for (int i = 0; i < 100; ++i) {
    const int64_t capture = 1000000 + i * 33333;
    const int64_t received = 5000000 + i * 33333;
    perf.AddDepthFrame(capture, received);
    perf.AddPeopleVisual(capture, received + 1000 * (10 + i % 10));  // 10..19 ms
    if (i % 2 == 0) {
      perf.AddPeopleMap(capture, received + 50000);        // 50 ms
      perf.AddPeopleMap(capture, received + 1500000);      // a later periodic re-publish: ignored
    }
  }
  perf.AddPeopleMap(42, 43);  // no frame with this capture time: not matched
  // A frame in which nobody was seen, whose time the people map took from another input later.
  perf.AddDepthFrame(9000000, 9000000);
  perf.AddPeopleVisual(9000000, 9010000, 0);
  perf.AddPeopleMap(9000000, 12000000);
  const StackPerfSummary s = perf.Summarise();
  EXPECT_EQ(s.depth_frames, 101);
  EXPECT_EQ(s.depth_to_people_visual.count, 101);
  EXPECT_NEAR(s.depth_to_people_visual.median_ms, 14.0, 1e-9);
  EXPECT_NEAR(s.depth_to_people_visual.max_ms, 19.0, 1e-9);  // the empty frame's 10 ms too
  EXPECT_EQ(s.depth_to_people_map.count, 50);
  EXPECT_NEAR(s.depth_to_people_map.p99_ms, 50.0, 1e-9);
  EXPECT_NE(StackPerfText(s).find("latency DEPTH -> PEOPLE_MAP: 50 frames"), std::string::npos);
}

TEST(StackPerfTest, PeopleKeptAcrossAPeopleMapRestart) {
  StackPerf perf;
  perf.AddPeopleMapSnapshot(0, {{1.0, 2.0}});
  perf.AddPeopleMapSnapshot(1, {{1.0, 2.0}, {4.0, 0.0}});
  perf.AddPeopleMapSnapshot(2, {{1.0, 2.0}, {4.0, 0.0}});
  perf.AddPeopleMapSnapshot(0, {{1.1, 2.1}});              // restarted: the second person is gone
  perf.AddPeopleMapSnapshot(1, {{1.1, 2.1}, {4.0, 0.1}});
  perf.AddPeopleMapSnapshot(0, {{1.1, 2.1}, {4.0, 0.1}});  // restarted again: both kept
  const StackPerfSummary s = perf.Summarise();
  EXPECT_EQ(s.people_map_restarts, 2);
  EXPECT_EQ(s.people_before_restarts, 4);
  EXPECT_EQ(s.people_kept_across_restarts, 3);
  EXPECT_NE(StackPerfText(s).find("3 of the 4 people"), std::string::npos);
}

// A log of an attacked bus: forged PEOPLE_MAP messages (random sequence numbers) between the
// node's own are not taken for restarts.
TEST(StackPerfTest, ForgedPeopleMapsAreNotRestarts) {
  StackPerf perf;
  for (int64_t seq = 0; seq < 20; ++seq) {
    perf.AddPeopleMapSnapshot(seq, {{1.0, 2.0}});
    perf.AddPeopleMapSnapshot(seq % 2 ? 8377426615063428000 : 4611686018427387904, {});
  }
  perf.AddPeopleMapSnapshot(23, {{1.0, 2.0}});  // three lost
  const StackPerfSummary s = perf.Summarise();
  EXPECT_EQ(s.people_map_restarts, 0);
}

TEST(StackPerfTest, SaysSoWhenTheLogHasNoLauncherReports) {
  StackPerf perf;
  const std::string text = StackPerfText(perf.Summarise());
  EXPECT_NE(text.find("no launcher reports"), std::string::npos);
  EXPECT_NE(text.find("no matched frames"), std::string::npos);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
