#include "log-tools/record_profile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>

#include "sarmap/image_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_detections_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

template <class T>
LogEvent Event(int64_t recv_us, const std::string& channel, T msg) {
  LogEvent e;
  e.timestamp_us = recv_us;
  e.channel = channel;
  e.data.resize(msg.getEncodedSize());
  msg.encode(e.data.data(), 0, static_cast<int>(e.data.size()));
  return e;
}

LogEvent Frame(int64_t recv_us, const std::string& channel, int64_t capture_us) {
  image_t image{};
  image.header.utime = capture_us;
  image.header.frame = "camera";
  return Event(recv_us, channel, image);
}

LogEvent Grid(int64_t recv_us) {
  occupancy_grid_t grid{};
  grid.header.utime = recv_us;
  grid.header.frame = "map";
  return Event(recv_us, "MAP", grid);
}

LogEvent Seen(int64_t recv_us, int64_t capture_us, int people) {
  people_detections_t msg{};
  msg.header.utime = capture_us;
  msg.header.frame = "camera";
  msg.sensor_id = "camera";
  for (int i = 0; i < people; ++i) {
    person_detection_t d{};
    d.track_id = i;
    d.cue = person_detection_t::CUE_SEEN_DEPTH;
    d.has_range = true;
    d.position_m[2] = 2.0;
    d.position_covariance[0] = d.position_covariance[4] = d.position_covariance[8] = 0.01;
    d.direction_covariance[0] = d.direction_covariance[3] = 0.001;
    d.height_m = 1.7f;
    d.confidence = 0.9f;
    msg.detections.push_back(d);
  }
  msg.num_detections = static_cast<int32_t>(msg.detections.size());
  return Event(recv_us, "PEOPLE_VISUAL", msg);
}

struct Kept {
  std::vector<LogEvent> events;
  std::set<int64_t> Captures(const std::string& channel) const {
    std::set<int64_t> out;
    for (const auto& e : events) {
      int64_t utime, seq;
      if (e.channel == channel && ReadSarmapHeader(e.data, &utime, &seq)) out.insert(utime);
    }
    return out;
  }
  int Count(const std::string& channel) const {
    return static_cast<int>(std::count_if(events.begin(), events.end(),
                                          [&](const LogEvent& e) { return e.channel == channel; }));
  }
};

constexpr int64_t kS = 1'000'000;

// 30 Hz depth and colour of the same capture instants (colour received 5 ms after depth), ODOM
// at 30 Hz, for `seconds`; `seen` adds a detection of the frame captured at that second,
// received 0.4 s later (the detector's latency); `detector_every` > 0: the detector reports on
// every this many frames (nobody seen) besides, 0.4 s later.
Kept RunCamera(const RecordProfileOptions& options, double seconds, double seen_s = -1,
               int detector_every = 0) {
  RecordThinner thinner(options);
  Kept kept;
  const int n = static_cast<int>(seconds * 30);
  const int64_t t0 = 100 * kS;
  for (int i = 0; i < n; ++i) {
    const int64_t capture = t0 + i * kS / 30;
    const int64_t recv = capture + 20'000;
    thinner.Add(Frame(recv, "DEPTH", capture));
    thinner.Release(recv, &kept.events);
    thinner.Add(Frame(recv + 5'000, "RGB", capture));
    thinner.Release(recv + 5'000, &kept.events);
    LogEvent odom;
    odom.timestamp_us = recv + 6'000;
    odom.channel = "ODOM";
    odom.data = {1, 2, 3};
    thinner.Add(odom);
    if (seen_s >= 0 && i == static_cast<int>(seen_s * 30 + 0.5) + 12) {
      thinner.Add(Seen(recv + 7'000, t0 + static_cast<int64_t>(seen_s * kS), 1));
    }
    if (detector_every > 0 && i >= 12 && (i - 12) % detector_every == 0) {
      thinner.Add(Seen(recv + 8'000, t0 + (i - 12) * kS / 30, 0));
    }
    thinner.Release(recv + 7'000, &kept.events);
  }
  thinner.Finish(&kept.events);
  EXPECT_EQ(thinner.held(), 0u);
  EXPECT_EQ(thinner.held_bytes(), 0);
  return kept;
}

TEST(RecordThinnerTest, KeepsOneFramePairPerPeriodAndEveryOtherMessage) {
  RecordProfileOptions options;  // 1 Hz
  const Kept kept = RunCamera(options, 10.0);
  const auto depth = kept.Captures("DEPTH"), rgb = kept.Captures("RGB");
  // One per second (the first of each second of capture time) and the last frame.
  EXPECT_EQ(depth.size(), 11u);
  EXPECT_EQ(depth, rgb) << "depth and colour of the same instants";
  EXPECT_EQ(kept.Count("ODOM"), 300);
  // Arrival order kept: receive times never go back.
  for (size_t i = 1; i < kept.events.size(); ++i) {
    ASSERT_GE(kept.events[i].timestamp_us, kept.events[i - 1].timestamp_us) << i;
  }
}

TEST(RecordThinnerTest, KeepsEveryFrameAroundAPersonSeen) {
  RecordProfileOptions options;  // 2 s around a detection
  options.frames.around_people_frames = "all";
  const Kept kept = RunCamera(options, 10.0, /*seen_s=*/5.0);
  const auto depth = kept.Captures("DEPTH");
  const int64_t t0 = 100 * kS;
  int around = 0;
  for (int64_t c : depth) {
    if (c >= t0 + 3 * kS && c <= t0 + 7 * kS) ++around;
  }
  // Every 30 Hz frame in [3 s, 7 s] of capture time: the 4 s window holds 120 or 121.
  EXPECT_GE(around, 120);
  EXPECT_EQ(kept.Captures("RGB"), depth);
  // Outside the window still one per second.
  EXPECT_LE(depth.size() - around, 8u);
}

// The detector looks at every other frame (15 of 30 a second) and sees someone at 5 s: around
// it, the frames it looked at are kept and the others are not.
TEST(RecordThinnerTest, AroundAPersonSeenKeepsTheFramesTheDetectorLookedAt) {
  RecordProfileOptions options;  // around_people_frames: processed
  const Kept kept = RunCamera(options, 10.0, /*seen_s=*/5.0, /*detector_every=*/2);
  const auto depth = kept.Captures("DEPTH");
  const int64_t t0 = 100 * kS;
  int around = 0, passed_over = 0;
  for (int64_t c : depth) {
    if (c < t0 + 3 * kS || c > t0 + 7 * kS) continue;
    ++around;
    if (((c - t0) * 30 + kS / 2) / kS % 2 == 1) ++passed_over;
  }
  // The 4 s window holds 60 or 61 of the detector's frames (the 1 Hz frames are among them).
  EXPECT_GE(around, 60);
  EXPECT_LE(around, 61);
  EXPECT_EQ(passed_over, 0);
  EXPECT_EQ(kept.Captures("RGB"), depth);
}

TEST(RecordThinnerTest, ADetectionWithNobodyKeepsNothingMore) {
  RecordProfileOptions options;
  RecordThinner thinner(options);
  std::vector<LogEvent> kept;
  for (int i = 0; i < 60; ++i) {
    const int64_t t = 100 * kS + i * kS / 30;
    thinner.Add(Frame(t, "DEPTH", t));
    thinner.Add(Seen(t + 1, t, 0));
  }
  thinner.Finish(&kept);
  // Two seconds: the first frame of each and the last.
  EXPECT_EQ(std::count_if(kept.begin(), kept.end(), [](auto& e) { return e.channel == "DEPTH"; }),
            3);
}

TEST(RecordThinnerTest, KeepsAGridPerPeriodAndTheLastOneEvenWhenPassed) {
  RecordProfileOptions options;  // one grid per 10 s, hold 3 s
  RecordThinner thinner(options);
  std::vector<LogEvent> kept;
  for (int s = 0; s < 40; ++s) {
    const int64_t t = 100 * kS + s * kS;
    if (s < 30) thinner.Add(Grid(t));  // the last grid at 29 s, passed over by 32 s
    LogEvent pose;
    pose.timestamp_us = t + 1;
    pose.channel = "POSE";
    pose.data = {7};
    thinner.Add(pose);
    thinner.Release(t + 1, &kept);
  }
  thinner.Finish(&kept);
  std::vector<int64_t> grids;
  for (const auto& e : kept) {
    if (e.channel == "MAP") grids.push_back((e.timestamp_us - 100 * kS) / kS);
  }
  EXPECT_EQ(grids, (std::vector<int64_t>{0, 10, 20, 29}));
  EXPECT_EQ(thinner.counts().at("MAP").kept, 4);
  EXPECT_EQ(thinner.counts().at("MAP").dropped, 26);
  EXPECT_EQ(thinner.counts().at("POSE").kept, 40);
}

TEST(RecordThinnerTest, AFrameWithoutAReadableHeaderIsKept) {
  RecordProfileOptions options;
  RecordThinner thinner(options);
  std::vector<LogEvent> kept;
  for (int i = 0; i < 30; ++i) {
    LogEvent junk;
    junk.timestamp_us = 100 * kS + i;
    junk.channel = "RGB";
    junk.data = {0, 1, 2};
    thinner.Add(junk);
  }
  thinner.Finish(&kept);
  EXPECT_EQ(kept.size(), 30u);
}

TEST(RecordThinnerTest, HoldsNoMoreThanItsMemoryBound) {
  RecordProfileOptions options;
  options.max_held_mb = 1.0;
  RecordThinner thinner(options);
  std::vector<LogEvent> kept;
  for (int i = 0; i < 100; ++i) {  // 100 kB each, all at one receive time
    LogEvent e;
    e.timestamp_us = 100 * kS;
    e.channel = "FLOOD";
    e.data.assign(100'000, 0);
    thinner.Add(std::move(e));
    thinner.Release(100 * kS, &kept);
    ASSERT_LE(thinner.held_bytes(), 1'000'000);
  }
  EXPECT_EQ(kept.size() + thinner.held(), 100u);
}

TEST(RecordThinnerTest, RefusesABadPattern) {
  RecordProfileOptions options;
  options.frames.channels = "DEPTH(";
  EXPECT_THROW(RecordThinner thinner(options), common::OptionsError);
}

TEST(RecordThinnerTest, OptionsAreValidated) {
  RecordProfileOptions options;
  options.hold_s = 1.0;  // shorter than around_people_s
  EXPECT_THROW(common::ValidateOptions(options), common::OptionsError);
  options.hold_s = 3.0;
  options.frames.pair_tolerance_s = 0.6;  // half a 1 Hz period or more: every frame a pair
  EXPECT_THROW(common::ValidateOptions(options), common::OptionsError);
}

TEST(RecordThinnerTest, TheShippedProfileLoads) {
  const auto options = common::LoadOptions<RecordProfileOptions>(
      std::string(SARMAP_SOURCE_DIR) + "/config/record_long.yaml", {"frames.rate_hz=2"});
  EXPECT_EQ(options.frames.rate_hz, 2.0);
  EXPECT_EQ(options.frames.channels, "DEPTH|RGB");
  EXPECT_GE(options.hold_s, options.frames.around_people_s);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
