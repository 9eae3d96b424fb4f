#pragma once
// The speech pipeline of one array (no LCM): multichannel audio + tracked directions ->
// per-source enhanced mono (MVDR + post-filter) -> voice activity -> utterances ->
// PocketSphinx keyword spotting (and full decoding on request) -> speech events.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sound_localisation/array_geometry.h"
#include "speech/enhancer.h"
#include "speech/keyword_spotter.h"

namespace sarmap {
namespace speech {

struct SpeechOptions {
  EnhancerOptions enhancer;
  VadOptions vad;
  KeywordOptions keywords;
  int max_sources = 3;          // beams at once (strongest/most recent tracks)
  double track_timeout_s = 3.0; // a direction not refreshed for this long is dropped
  bool untracked_beam = true;   // with no track, spot keywords on an omnidirectional beam (track -1)
  template <class V>
  void Visit(V& v) {
    v("enhancer", enhancer, "beamformer and post-filter");
    v("vad", vad, "voice activity detection");
    v("keywords", keywords, "PocketSphinx keyword spotting");
    v("max_sources", max_sources, "most sources enhanced at once");
    v("track_timeout_s", track_timeout_s, "forget a direction not refreshed for this long");
    v("untracked_beam", untracked_beam, "without tracks, listen on one beam (track_id -1, no direction)");
  }
  void Validate(common::Validator& check) const {
    check.That(max_sources >= 1, "max_sources", "must be >= 1");
    check.Positive("track_timeout_s", track_timeout_s);
  }
};

struct TrackedSource {
  int64_t id = -1;
  sound::Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  int64_t last_sample = 0;  // stream sample of the last DOA update
};

struct SpeechResult {
  int64_t track_id = -1;
  bool has_direction = false;
  sound::Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  std::string text, keyword;
  double confidence = 0;
  int64_t start_sample = 0, end_sample = 0;  // stream samples
};

class SpeechProcessor {
 public:
  // kind: how DOA directions are expressed (1-D for linear arrays).
  SpeechProcessor(sound::ArrayGeometry geometry, sound::DoaKind kind, SpeechOptions options);
  // A DOA update for a track at stream sample `sample`.
  void UpdateTrack(int64_t id, const sound::Direction& direction, const Eigen::Matrix2d& covariance, int64_t sample);
  // Feeds audio; appends finished utterances' results (one per keyword hit, or one with text).
  void Push(const int16_t* data, int frames, int block_channels, std::vector<SpeechResult>* results);
  void Flush(std::vector<SpeechResult>* results);
  int64_t samples_seen() const { return samples_seen_; }
  bool full_decoding() const { return full_decoding_; }
  void set_full_decoding(bool on) { full_decoding_ = on; }
  int64_t utterances() const { return utterances_; }

 private:
  void Handle(int64_t id, const Utterance& u, std::vector<SpeechResult>* results);
  // Call-shape rule over joined segments (keywords.call_join_s): keyword results of a beam wait
  // until its call ends, and are released only if the whole call is short enough.
  struct PendingCall {
    bool open = false;
    int64_t samples_start = 0, end_sample = 0;  // enhanced-stream samples (first segment with pre-roll, last end)
    std::vector<SpeechResult> results;
  };
  bool joins_calls() const;
  void FinishCall(int64_t id, std::vector<SpeechResult>* results);
  std::map<int64_t, PendingCall> calls_;
  sound::ArrayGeometry geometry_;
  sound::DoaKind kind_;
  SpeechOptions options_;
  MultiBeamEnhancer enhancer_;
  KeywordSpotter spotter_;
  std::map<int64_t, TrackedSource> tracks_;
  std::map<int64_t, std::unique_ptr<VoiceActivityDetector>> vads_;
  // Enhanced-stream index of each VAD's first sample: a VAD counts from its own start, and a
  // track born mid-stream starts its VAD late.
  std::map<int64_t, int64_t> vad_origins_;
  std::map<int64_t, std::vector<float>> enhanced_;
  int64_t samples_seen_ = 0, utterances_ = 0;
  int64_t output_offset_ = 0;  // enhanced stream delay (samples)
  bool full_decoding_;
};

}  // namespace speech
}  // namespace sarmap
