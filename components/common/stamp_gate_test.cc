#include "common/stamp_gate.h"

#include <gtest/gtest.h>

#include <vector>

#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace common {
namespace {

constexpr Utime kYearUs = 365LL * 24 * 3600 * 1000000;

// A 10 Hz stream: stamp and receive time advance together.
struct Stream {
  Utime utime = 1000000;
  double receive_s = 50.0;
  void Step(double dt_s = 0.1) {
    utime += SecondsToUtime(dt_s);
    receive_s += dt_s;
  }
};

TEST(StampGateTest, OneFutureStampIsDroppedCountedAndNotAdopted) {
  StampGate gate;
  Stream s;
  for (int i = 0; i < 10; ++i, s.Step())
    EXPECT_TRUE(StampGate::Accepted(gate.Check(s.utime, s.receive_s)));
  EXPECT_EQ(gate.Check(s.utime + kYearUs, s.receive_s), StampGate::Verdict::kAhead);
  EXPECT_EQ(gate.dropped_ahead(), 1);
  EXPECT_LT(gate.clock_utime(), s.utime + kYearUs);
  // The stream goes on as if nothing happened.
  for (int i = 0; i < 20; ++i) {
    s.Step();
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  }
  EXPECT_NEAR(gate.ExpectedUtime(s.receive_s), static_cast<double>(s.utime), 1000.0);
  EXPECT_EQ(gate.dropped(), 1);
  EXPECT_EQ(gate.reanchors(), 0);
}

TEST(StampGateTest, StrayFutureStampsMixedIntoAStreamNeverReanchor) {
  StampGateOptions options;
  options.reanchor_count = 3;
  StampGate gate(options);
  Stream s;
  for (int i = 0; i < 50; ++i, s.Step()) {
    EXPECT_TRUE(StampGate::Accepted(gate.Check(s.utime, s.receive_s)));
    // Two agreeing future stamps between every pair of good ones: one short of re-anchoring.
    gate.Check(s.utime + kYearUs, s.receive_s);
    gate.Check(s.utime + kYearUs + 1000, s.receive_s);
  }
  EXPECT_EQ(gate.dropped_ahead(), 100);
  EXPECT_EQ(gate.reanchors(), 0);
  EXPECT_LT(gate.clock_utime(), kYearUs);
}

TEST(StampGateTest, AWholeStreamThatStepsForwardIsFollowedAfterTheReanchorCount) {
  StampGateOptions options;
  options.reanchor_count = 4;
  options.reanchor_min_s = 0;  // the count alone
  StampGate gate(options);
  Stream s;
  for (int i = 0; i < 10; ++i, s.Step()) gate.Check(s.utime, s.receive_s);
  s.utime += SecondsToUtime(3600.0);  // the source's clock is set an hour forward
  for (int i = 0; i < options.reanchor_count - 1; ++i, s.Step()) {
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAhead);
  }
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kReanchored);
  EXPECT_EQ(gate.clock_utime(), s.utime);
  for (int i = 0; i < 10; ++i) {
    s.Step();
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  }
  EXPECT_EQ(gate.dropped_ahead(), options.reanchor_count - 1);
  EXPECT_EQ(gate.reanchors(), 1);
}

TEST(StampGateTest, AWholeStreamThatStepsIsFollowedOnlyAfterTheReanchorTime) {
  StampGateOptions options;
  options.reanchor_count = 2;
  options.reanchor_min_s = 1.0;
  StampGate gate(options);
  Stream s;
  for (int i = 0; i < 10; ++i) s.Step(0.25), gate.Check(s.utime, s.receive_s);
  s.utime += SecondsToUtime(3600.0);
  const double first_s = s.receive_s;
  // Every stamp of the stepped stream agrees with the previous one; the count is reached on the
  // second, the time only after a second of them.
  while (s.receive_s - first_s < options.reanchor_min_s) {
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAhead);
    s.Step(0.25);
  }
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kReanchored);
  EXPECT_EQ(gate.reanchors(), 1);
}

TEST(StampGateTest, AStampSentAgainAndAgainNeverReanchors) {
  StampGate gate;
  Stream s;
  for (int i = 0; i < 10; ++i, s.Step()) gate.Check(s.utime, s.receive_s);
  // The stream stops; one forged message a year ahead is sent 200 times over 20 s.
  const Utime forged = s.utime + kYearUs;
  for (int i = 0; i < 200; ++i) {
    s.receive_s += 0.1;
    EXPECT_EQ(gate.Check(forged, s.receive_s), StampGate::Verdict::kAhead);
  }
  EXPECT_EQ(gate.reanchors(), 0);
  EXPECT_LT(gate.clock_utime(), forged);
}

TEST(StampGateTest, ASecondPublisherInterleavedWithALiveStreamNeverReanchors) {
  StampGate gate;
  Stream s;
  for (int i = 0; i < 10; ++i, s.Step()) gate.Check(s.utime, s.receive_s);
  // A forger runs a clock of its own an hour ahead at 100 Hz, its stamps advancing with the
  // receive time: runs of 9 agreeing stamps (past reanchor_count) between two of the live
  // stream's, for 30 s.
  Utime forged = s.utime + SecondsToUtime(3600.0);
  for (int i = 0; i < 300; ++i) {
    for (int k = 1; k < 10; ++k) {
      forged += 10000;
      EXPECT_EQ(gate.Check(forged, s.receive_s + 0.01 * k), StampGate::Verdict::kAhead);
    }
    forged += 10000;
    s.Step();
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  }
  EXPECT_EQ(gate.reanchors(), 0);
  EXPECT_NEAR(gate.ExpectedUtime(s.receive_s), static_cast<double>(s.utime), 1000.0);
}

// Replies stamped with the time of the data they answer (SLAM_ANCHORS for a request, stamped
// with the newest SLAM node's time while the robot stands still) arrive long after their
// stamp; they do not pull the clock back, so the next current stamp is not "ahead".
TEST(StampGateTest, StampsBehindTheClockDoNotHoldItBack) {
  StampGate gate;
  Stream s;
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  const Utime data_time = s.utime;
  for (int i = 0; i < 4; ++i) {
    s.Step(4.0);  // a reply every 4 s, all stamped with the same data time
    EXPECT_EQ(gate.Check(data_time, s.receive_s), StampGate::Verdict::kAccepted);
  }
  s.Step(1.0);  // 17 s on: a current stamp
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  EXPECT_EQ(gate.dropped(), 0);
  // Ahead of the clock by more than max_ahead_s is still dropped.
  EXPECT_EQ(gate.Check(s.utime + SecondsToUtime(6.0), s.receive_s), StampGate::Verdict::kAhead);
}

TEST(StampGateTest, APauseInTheStreamIsCoveredByTheReceiveClock) {
  StampGate gate;
  Stream s;
  for (int i = 0; i < 5; ++i, s.Step()) gate.Check(s.utime, s.receive_s);
  s.Step(60.0);  // a minute of silence, on both clocks
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  EXPECT_EQ(gate.dropped(), 0);
}

TEST(StampGateTest, AFastReplayIsAccepted) {
  StampGate gate;
  Stream s;
  // Ten times real time: 0.1 s of stamps per 0.01 s received.
  for (int i = 0; i < 200; ++i) {
    s.utime += 100000;
    s.receive_s += 0.01;
    EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
  }
}

TEST(StampGateTest, BackwardsStampsPassUnlessBounded) {
  Stream s;
  StampGate open;
  for (int i = 0; i < 5; ++i, s.Step()) open.Check(s.utime, s.receive_s);
  // Behind: the node's own late-input handling decides; the clock does not move back.
  const Utime newest = open.clock_utime();
  EXPECT_EQ(open.Check(s.utime - kYearUs, s.receive_s), StampGate::Verdict::kAccepted);
  EXPECT_EQ(open.clock_utime(), newest);

  StampGateOptions options;
  options.max_behind_s = 10.0;
  options.reanchor_count = 3;
  options.reanchor_min_s = 0;
  StampGate bounded(options);
  Stream t;
  for (int i = 0; i < 5; ++i, t.Step()) bounded.Check(t.utime, t.receive_s);
  EXPECT_EQ(bounded.Check(t.utime - kYearUs, t.receive_s), StampGate::Verdict::kBehind);
  EXPECT_EQ(bounded.Check(t.utime - 2000000, t.receive_s), StampGate::Verdict::kAccepted);
  EXPECT_EQ(bounded.dropped_behind(), 1);
  // A whole stream stepping back an hour is followed too.
  t.utime -= SecondsToUtime(3600.0);
  EXPECT_EQ(bounded.Check(t.utime, t.receive_s), StampGate::Verdict::kBehind);
  t.Step();
  EXPECT_EQ(bounded.Check(t.utime, t.receive_s), StampGate::Verdict::kBehind);
  t.Step();
  EXPECT_EQ(bounded.Check(t.utime, t.receive_s), StampGate::Verdict::kReanchored);
  EXPECT_EQ(bounded.clock_utime(), t.utime);
}

TEST(StampGateTest, ExtremeStampsDoNotOverflow) {
  StampGate gate;
  Stream s;
  for (int i = 0; i < 5; ++i, s.Step()) gate.Check(s.utime, s.receive_s);
  EXPECT_EQ(gate.Check(INT64_MAX, s.receive_s), StampGate::Verdict::kAhead);
  EXPECT_EQ(gate.Check(INT64_MIN, s.receive_s),
            StampGate::Verdict::kAccepted);  // behind, unbounded
  s.Step();
  EXPECT_EQ(gate.Check(s.utime, s.receive_s), StampGate::Verdict::kAccepted);
}

TEST(StampGatesTest, StreamsKeepTheirOwnClocks) {
  StampGates gates(StampGateOptions{});
  // Stream 1 is stamped 3 s behind stream 0 (published late); both are fine.
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(gates.Accept(0, 10000000 + i * 100000, 1.0 + 0.1 * i));
    EXPECT_TRUE(gates.Accept(1, 7000000 + i * 100000, 1.0 + 0.1 * i));
  }
  EXPECT_FALSE(gates.Accept(1, 10000000 + kYearUs, 2.0));
  EXPECT_TRUE(gates.Accept(0, 11000000, 2.0));
  EXPECT_EQ(gates.dropped_ahead(), 1);
}

TEST(StampGatesTest, AStreamsFirstStampIsCheckedAgainstTheNodesClock) {
  StampGates gates(StampGateOptions{});
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(gates.Accept(0, 10000000 + i * 100000, 1.0 + 0.1 * i));
  // The first message ever on stream 1 is stamped a year ahead (forged): dropped, not its clock.
  EXPECT_FALSE(gates.Accept(1, 11000000 + kYearUs, 2.0));
  EXPECT_TRUE(gates.Accept(1, 11000000, 2.0));
  // A stream that is genuinely on another clock (an hour ahead) is followed after the
  // re-anchor count.
  StampGateOptions options;
  options.reanchor_min_s = 0;
  StampGates other(options);
  EXPECT_TRUE(other.Accept(0, 10000000, 1.0));
  const Utime hour_us = 3600LL * 1000000;
  int accepted = 0;
  for (int i = 0; i < 10; ++i) accepted += other.Accept(1, 10000000 + hour_us + i * 100000, 1.0 + 0.1 * i);
  EXPECT_EQ(accepted, 10 - (options.reanchor_count - 1));
  EXPECT_EQ(other.reanchors(), 1);
}

TEST(StampGateTest, TheHeaderStampIsReadFromTheEncodedMessage) {
  sarmap::pose_t pose{};
  pose.header.utime = 1234567890123;
  pose.header.frame = "map";
  std::vector<uint8_t> wire(static_cast<size_t>(pose.getEncodedSize()));
  pose.encode(wire.data(), 0, static_cast<int>(wire.size()));
  Utime utime = 0;
  ASSERT_TRUE(EncodedHeaderUtime(wire.data(), static_cast<int64_t>(wire.size()), &utime));
  EXPECT_EQ(utime, pose.header.utime);
  EXPECT_FALSE(EncodedHeaderUtime(wire.data(), 15, &utime));
  EXPECT_FALSE(EncodedHeaderUtime(nullptr, 100, &utime));
}

}  // namespace
}  // namespace common
}  // namespace sarmap
