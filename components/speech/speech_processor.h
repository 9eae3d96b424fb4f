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
#include "sound_localisation/stft.h"
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
  // One talker is heard on every beam: a beam at a steady noise source (whose post-filter
  // removes that noise) passes the talker's speech leaking through its side lobes, and the
  // keyword spotter finds the talker's words there too, with the noise source's direction
  // (open-area mission: 63 of 136 keyword directions pointed at the generator). Keyword hits of
  // different beams that overlap in time are one utterance: only the hit of the beam whose
  // direction gained the most power is kept. The gain is measured on the raw microphones with a
  // delay-and-sum beam (its gain off its own direction is at most 1, unlike MVDR's and the
  // post-filter's): speech-band power over the hit less the direction's floor (10th percentile
  // over the 5 s before it), in linear power, so a loud steady source does not win. Hits wait
  // this long after their end for the other beams' (0: off).
  double beam_arbitration_s = 2.0;
  template <class V>
  void Visit(V& v) {
    v("enhancer", enhancer, "beamformer and post-filter");
    v("vad", vad, "voice activity detection");
    v("keywords", keywords, "PocketSphinx keyword spotting");
    v("max_sources", max_sources, "most sources enhanced at once");
    v("track_timeout_s", track_timeout_s, "forget a direction not refreshed for this long");
    v("untracked_beam", untracked_beam, "without tracks, listen on one beam (track_id -1, no direction)");
    v("beam_arbitration_s", beam_arbitration_s,
      "keyword hits on several beams at once are one talker leaking: keep the loudest beam's; hits wait this "
      "long (s) for the other beams' (0: off)");
  }
  void Validate(common::Validator& check) const {
    check.That(max_sources >= 1, "max_sources", "must be >= 1");
    check.Positive("track_timeout_s", track_timeout_s);
    check.InRange("beam_arbitration_s", beam_arbitration_s, 0, 10);
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
  double gain_power = 0;  // speech-band power its direction gained over [start, end) (BeamArbiter)
};

// Keeps, of keyword hits on different beams that overlap in time, only the one with the largest
// gain_power (see SpeechOptions::beam_arbitration_s). Results without a keyword pass at once.
class BeamArbiter {
 public:
  explicit BeamArbiter(int64_t hold_samples) : hold_samples_(hold_samples) {}
  // Takes `fresh` and appends to `out` what is decided at stream sample `now` (all with `flush`).
  void Push(std::vector<SpeechResult>* fresh, int64_t now, bool flush, std::vector<SpeechResult>* out);
  int64_t dropped() const { return dropped_; }

 private:
  int64_t hold_samples_;
  std::vector<SpeechResult> held_, decided_;  // decided_: recent ones, for later overlaps
  int64_t dropped_ = 0;
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
  // Keyword hits dropped as another beam's louder hit of the same utterance.
  int64_t leaked_hits_dropped() const { return arbiter_.dropped(); }

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
  BeamArbiter arbiter_;
  std::vector<SpeechResult> fresh_;
  // Speech-band spectra of the raw microphones (no overlap), kept a few seconds for GainPower.
  struct BandFrame {
    int64_t end_sample = 0;
    Eigen::MatrixXcf bins;  // band bins x mics
  };
  std::unique_ptr<sound::MultichannelStft> band_stft_;
  std::vector<BandFrame> band_frames_;  // oldest first
  int band_lo_ = 0, band_hi_ = 0;
  // Delay-and-sum power of frames ending in (begin, end] towards `direction`, mean per frame.
  std::vector<double> BeamPowers(const sound::Direction& direction, int64_t begin, int64_t end) const;
  double GainPower(const sound::Direction& direction, int64_t start_sample, int64_t end_sample) const;
};

}  // namespace speech
}  // namespace sarmap
