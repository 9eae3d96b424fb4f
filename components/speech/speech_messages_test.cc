// SpeechResult -> SPEECH and PEOPLE_AUDIO: every field where the consumers read it, a heard
// person without a range, and no direction written as NaN, never as 0.

#include "speech/speech_messages.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/message_checks.h"

namespace sarmap {
namespace speech {
namespace {

SpeechResult Heard() {
  SpeechResult r;
  r.track_id = 7;
  r.has_direction = true;
  r.direction.azimuth_rad = 0.8;
  r.direction.elevation_rad = 0.1;
  r.covariance << 0.01, 0.002, 0.002, 0.04;
  r.keyword = "help";
  r.text = "help me";
  r.confidence = 0.9;
  return r;
}

TEST(SpeechMessagesTest, ASpeechEventCarriesTheResultAndItsTimes) {
  const speech_event_t e = ToSpeechEvent(Heard(), 1000, 2500);
  EXPECT_EQ(e.header.utime, 1000);
  EXPECT_EQ(e.start_utime, 1000);
  EXPECT_EQ(e.end_utime, 2500);
  EXPECT_EQ(e.track_id, 7);
  EXPECT_EQ(e.keyword, "help");
  EXPECT_EQ(e.text, "help me");
  EXPECT_FLOAT_EQ(e.confidence, 0.9f);
  EXPECT_DOUBLE_EQ(e.azimuth_rad, 0.8);
  EXPECT_DOUBLE_EQ(e.elevation_rad, 0.1);
  EXPECT_TRUE(e.is_final);
  SpeechResult untracked = Heard();
  untracked.has_direction = false;
  const speech_event_t u = ToSpeechEvent(untracked, 1000, 2500);
  EXPECT_TRUE(std::isnan(u.azimuth_rad) && std::isnan(u.elevation_rad));
}

TEST(SpeechMessagesTest, AHeardPersonIsADirectionWithItsCovarianceAndNoRange) {
  const people_detections_t d = ToPeopleAudio(Heard(), "respeaker", 4242);
  ASSERT_EQ(d.num_detections, 1);
  ASSERT_EQ(d.detections.size(), 1u);
  const person_detection_t& p = d.detections[0];
  EXPECT_EQ(d.header.utime, 4242);
  EXPECT_EQ(d.sensor_id, "respeaker");
  EXPECT_EQ(p.cue, +person_detection_t::CUE_HEARD);  // (+: a value, not the static member)
  EXPECT_FALSE(p.has_range);
  EXPECT_DOUBLE_EQ(p.azimuth_rad, 0.8);
  EXPECT_DOUBLE_EQ(p.elevation_rad, 0.1);
  EXPECT_DOUBLE_EQ(p.direction_covariance[0], 0.01);  // row-major (azimuth, elevation)
  EXPECT_DOUBLE_EQ(p.direction_covariance[1], 0.002);
  EXPECT_DOUBLE_EQ(p.direction_covariance[3], 0.04);
  EXPECT_EQ(p.keyword, "help");
  EXPECT_EQ(p.track_id, 7);
  // What a receiving node's decode check accepts.
  EXPECT_EQ(common::CheckMessage(d), "");
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
