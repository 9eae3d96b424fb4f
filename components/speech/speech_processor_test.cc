#include "speech/speech_processor.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

#include "audio_capture/audio_file.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"
#include "speech/testing/kws_evaluation.h"

namespace sarmap {
namespace speech {
namespace {

// The whole multichannel path: a call for help from azimuth 60 deg (ReSpeaker geometry, room
// with RT60 0.3 s, noise), its track given as the localiser would -> MVDR beam -> VAD ->
// keywords -> a result with the keyword, the track id and the direction.
// Renders "help me" from azimuth 60 deg after `lead` samples of silence and runs the processor,
// with the track known from sample `track_from` on (the localiser's DOA updates).
std::vector<SpeechResult> RunCall(size_t lead, size_t track_from, double* az_out) {
  const auto call = RenderEspeak("help me", "en-us", 150, 50);
  EXPECT_FALSE(call.empty());
  const auto g = sound::testing_util::LoadArray("respeaker4");
  sound::Room room;
  room.rt60_s = 0.3;
  room.max_rir_s = 0.2;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const size_t n = lead + call.size() + 16000;
  std::vector<float> sig(n, 0.0f);
  for (size_t i = 0; i < call.size(); ++i) sig[lead + i] = call[i] * 8;
  const double az = sound::DegToRad(60), el = sound::DegToRad(15);
  const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const auto mics = sound::SimulateRoom(room, g.positions_m.colwise() + centre, {{centre + 1.5 * u, sig}}, n, 0.003, 5);
  const auto pcm = audio::ToInterleavedInt16(mics, 0, n);
  SpeechOptions o;
  o.keywords.thresholds = {1e-40};
  o.keywords.min_confidence = 0.5;
  SpeechProcessor p(g, sound::DoaKind::kAzimuthElevation, o);
  std::vector<SpeechResult> results;
  for (size_t i = 0; i < n; i += 512) {
    if (i >= track_from) p.UpdateTrack(4, {az, el}, Eigen::Matrix2d::Identity() * 0.003, static_cast<int64_t>(i));
    p.Push(pcm.data() + i * 4, static_cast<int>(std::min<size_t>(512, n - i)), 4, &results);
  }
  p.Flush(&results);
  *az_out = az;
  return results;
}

TEST(SpeechProcessor, CallForHelpFromATrackedDirection) {
  if (!EspeakAvailable()) GTEST_SKIP() << "espeak-ng not installed";
  const size_t lead = 24000;
  double az = 0;
  const auto results = RunCall(lead, 0, &az);
  bool found = false;
  for (const auto& r : results) {
    std::printf("result: track %lld keyword '%s' conf %.2f az %.1f deg, %.2f-%.2f s\n", static_cast<long long>(r.track_id),
                r.keyword.c_str(), r.confidence, sound::RadToDeg(r.direction.azimuth_rad), r.start_sample / 16000.0,
                r.end_sample / 16000.0);
    if (r.keyword == "help" && r.track_id == 4 && r.has_direction) {
      found = true;
      EXPECT_NEAR(r.direction.azimuth_rad, az, 1e-9);
      EXPECT_NEAR(r.start_sample / 16000.0, lead / 16000.0, 1.0);
    }
  }
  EXPECT_TRUE(found);
}

// A track born mid-stream starts its beam and voice-activity detector late; the keyword's
// stream samples (and so its time on the wire) must still be where the call was said.
TEST(SpeechProcessor, KeywordTimeIsRightForATrackBornMidStream) {
  if (!EspeakAvailable()) GTEST_SKIP() << "espeak-ng not installed";
  const size_t lead = 64000, track_from = 56000;  // call at 4.0 s, track from 3.5 s
  double az = 0;
  bool found = false;
  for (const auto& r : RunCall(lead, track_from, &az)) {
    if (r.keyword != "help") continue;
    found = true;
    // "help" is the first word: it starts within a few tenths of a second of the call.
    EXPECT_NEAR(r.start_sample / 16000.0, lead / 16000.0, 0.3);
    EXPECT_GT(r.end_sample, r.start_sample);
    EXPECT_LT(r.end_sample / 16000.0, lead / 16000.0 + 1.5);
  }
  EXPECT_TRUE(found);
}

// Call-shape rule over joined segments (call_join_s): "help me" alone is a call; the same
// "help me" followed 0.4 s later by a sentence is the start of a longer stretch of talk, not a
// call. Without joining, the rule looks at each voice-activity segment alone and keeps it.
bool HeardHelp(const std::vector<float>& mono, double call_join_s) {
  const auto g = sound::testing_util::LoadArray("respeaker4");
  sound::Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const double az = sound::DegToRad(60), el = sound::DegToRad(15);
  const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const size_t n = mono.size();
  const auto mics = sound::SimulateRoom(room, g.positions_m.colwise() + centre, {{centre + 1.5 * u, mono}}, n, 0.003, 5);
  const auto pcm = audio::ToInterleavedInt16(mics, 0, n);
  SpeechOptions o;
  o.keywords.keywords = {"help"};
  o.keywords.thresholds = {1e-40};
  o.keywords.min_confidence = 0.5;
  o.keywords.call_join_s = call_join_s;
  SpeechProcessor p(g, sound::DoaKind::kAzimuthElevation, o);
  std::vector<SpeechResult> results;
  for (size_t i = 0; i < n; i += 512) {
    p.UpdateTrack(4, {az, el}, Eigen::Matrix2d::Identity() * 0.003, static_cast<int64_t>(i));
    p.Push(pcm.data() + i * 4, static_cast<int>(std::min<size_t>(512, n - i)), 4, &results);
  }
  p.Flush(&results);
  for (const auto& r : results)
    if (r.keyword == "help") return true;
  return false;
}

TEST(SpeechProcessor, CallJoinDropsHelpThatStartsALongerStretchOfTalk) {
  if (!EspeakAvailable()) GTEST_SKIP() << "espeak-ng not installed";
  const auto call = RenderEspeak("help me", "en-us", 150, 50);
  const auto more = RenderEspeak("we walked along the river in the evening", "en-us", 150, 50);
  ASSERT_FALSE(call.empty());
  ASSERT_FALSE(more.empty());
  auto scene = [&](bool with_more) {
    const size_t lead = 24000, pause = 6400;  // 1.5 s of noise, 0.4 s between call and sentence
    std::vector<float> x(lead + call.size() + pause + more.size() + 24000, 0.0f);
    for (size_t i = 0; i < call.size(); ++i) x[lead + i] = call[i] * 8;
    if (with_more)
      for (size_t i = 0; i < more.size(); ++i) x[lead + call.size() + pause + i] = more[i] * 8;
    return x;
  };
  EXPECT_TRUE(HeardHelp(scene(false), 0.5));
  EXPECT_TRUE(HeardHelp(scene(true), 0.0));   // each segment alone: the call's segment is short
  EXPECT_FALSE(HeardHelp(scene(true), 0.5));  // joined: a 3 s stretch of talk
}

// The arbiter alone: overlapping hits of two beams keep the louder; hits that do not overlap,
// hits of one beam and results without a keyword all pass; nothing is decided before the hold.
// 20 000 DOAs with new track ids over 2 s of audio (a broken localiser, a hostile publisher):
// the tracks kept stay bounded, the evictions are counted, and a real track updated all along
// keeps its place. Also a DOA stamped far ahead of the audio is dropped.
TEST(SpeechProcessor, ADoaFloodOfNewTrackIdsIsBounded) {
  const auto g = sound::testing_util::LoadArray("respeaker4");
  SpeechOptions o;
  SpeechProcessor p(g, sound::DoaKind::kAzimuthElevation, o);
  const int block = 512, blocks = 63;  // ~2 s at 16 kHz
  std::vector<int16_t> noise(static_cast<size_t>(block) * 4);
  uint32_t seed = 1;
  for (auto& v : noise)
    v = static_cast<int16_t>(((seed = seed * 1664525u + 1013904223u) >> 20) % 200) - 100;
  std::vector<SpeechResult> results;
  int64_t id = 1000;
  const auto start = std::chrono::steady_clock::now();
  // The real track, heard for 0.3 s before the flood and all through it.
  const int pre_blocks = 10;
  for (int b = 0; b < pre_blocks + blocks; ++b) {
    const int64_t now = static_cast<int64_t>(b) * block;
    p.UpdateTrack(7, {0.5, 0.1}, Eigen::Matrix2d::Identity() * 0.003, now);
    for (int k = 0; k < (b < pre_blocks ? 0 : 20000 / blocks); ++k, ++id) {
      p.UpdateTrack(id, {0.01 * (id % 600), 0.0}, Eigen::Matrix2d::Identity() * 0.003, now);
      EXPECT_LE(p.num_tracks(), static_cast<size_t>(o.max_tracks));
    }
    p.Push(noise.data(), block, 4, &results);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%lld new track ids over %.1f s of audio: %.2f s of CPU, %zu tracks kept, %lld evicted\n",
      static_cast<long long>(id - 1000), blocks * block / 16000.0, seconds, p.num_tracks(),
      static_cast<long long>(p.tracks_evicted()));
  EXPECT_TRUE(p.has_track(7));
  EXPECT_EQ(p.tracks_evicted(), id - 1000 + 1 - o.max_tracks);
  EXPECT_FALSE(p.UpdateTrack(8, {0.5, 0.1}, Eigen::Matrix2d::Identity(),
                             p.samples_seen() + static_cast<int64_t>(3600 * 16000.0)));
  EXPECT_EQ(p.doas_ahead_dropped(), 1);
}

TEST(BeamArbiter, KeepsTheLoudestBeamOfOneUtterance) {
  auto hit = [](int64_t track, int64_t start, int64_t end, double level, const char* keyword = "help") {
    SpeechResult r;
    r.track_id = track;
    r.start_sample = start;
    r.end_sample = end;
    r.direction_score = level;
    r.keyword = keyword;
    return r;
  };
  BeamArbiter arbiter(32000);
  std::vector<SpeechResult> fresh{hit(1, 1000, 9000, -30), hit(2, 2000, 8000, -24), hit(2, 3000, 9000, -24, "here"),
                                  hit(3, 50000, 60000, -40), hit(1, 1000, 9000, -30, "")},
      out;
  arbiter.Push(&fresh, 20000, false, &out);
  ASSERT_EQ(out.size(), 1u);  // the text-only result, at once
  EXPECT_TRUE(out[0].keyword.empty());
  out.clear();
  // Track 1's hit arrives late from its own beam; it still meets track 2's.
  std::vector<SpeechResult> none;
  arbiter.Push(&none, 45000, false, &out);
  ASSERT_EQ(out.size(), 2u);  // track 2's two hits (one beam may say two keywords)
  for (const auto& r : out) EXPECT_EQ(r.track_id, 2);
  out.clear();
  std::vector<SpeechResult> late{hit(1, 4000, 9500, -35)};
  arbiter.Push(&late, 46000, false, &out);
  EXPECT_TRUE(out.empty());
  arbiter.Push(&none, 0, true, &out);
  ASSERT_EQ(out.size(), 1u);  // track 3's, which overlaps nothing
  EXPECT_EQ(out[0].track_id, 3);
  EXPECT_EQ(arbiter.dropped(), 2);
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
