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
  // Tracks kept at once: a new track beyond this evicts the least recently updated one (counted).
  // A flood of DOAs with new track ids (a broken localiser, a hostile publisher) then costs a
  // bounded map, not a sort of every id ever heard on each audio block.
  int max_tracks = 16;
  // A beam is given only to a track updated at least this many times: a track id heard once (a
  // flood of new ids) starts no beam, voice-activity detector or MVDR weights.
  int min_track_updates = 2;
  // DOAs stamped further ahead of the audio than this are dropped (counted): a far-future stamp
  // would keep its track "most recent" for ever.
  double max_doa_ahead_s = 1.0;
  bool untracked_beam = true;   // with no track, spot keywords on an omnidirectional beam (track -1)
  // One talker is heard on every beam: a beam at a steady noise source (whose post-filter
  // removes that noise) passes the talker's speech leaking through its side lobes, and the
  // keyword spotter finds the talker's words there too, with the noise source's direction
  // (open-area mission: 63 of 136 keyword directions pointed at the generator). Keyword hits of
  // different beams that overlap in time are one utterance. Each hit is given to the tracked
  // direction (beam or not) its speech came from: on the raw microphones, the time-frequency
  // bins (300-3400 Hz) 6 dB above their floor, i.e. the speech and not a steady source, and
  // the SRP-PHAT of those bins towards each tracked direction (PHAT: a 4.6 cm array's power
  // beams are nearly omnidirectional at speech frequencies, its phases are not). Of overlapping
  // hits only the best-scoring one is kept. Hits wait this long after their end (0: off).
  double beam_arbitration_s = 2.0;
  template <class V>
  void Visit(V& v) {
    v("enhancer", enhancer, "beamformer and post-filter");
    v("vad", vad, "voice activity detection");
    v("keywords", keywords, "PocketSphinx keyword spotting");
    v("max_sources", max_sources, "most sources enhanced at once", AtLeast(1));
    v("track_timeout_s", track_timeout_s, "forget a direction not refreshed for this long",
      Positive());
    v("max_tracks", max_tracks,
      "tracks kept at once; a new one beyond this evicts the least recently updated (counted)");
    v("min_track_updates", min_track_updates, "DOA updates a track needs before it is given a beam",
      AtLeast(1));
    v("max_doa_ahead_s", max_doa_ahead_s,
      "DOAs stamped further ahead of the audio than this are dropped (counted)", Positive());
    v("untracked_beam", untracked_beam, "without tracks, listen on one beam (track_id -1, no direction)");
    v("beam_arbitration_s", beam_arbitration_s,
      "keyword hits go to the tracked direction their speech came from; of hits of several tracks "
      "at once "
      "(one talker leaking into other beams) the best-fitting is kept; hits wait this long (s) (0: "
      "off)",
      InRange(0, 10));
  }
  void Validate(common::Validator& check) const {
    check.That(max_tracks >= max_sources, "max_tracks", "must be >= max_sources");
  }
};

struct TrackedSource {
  int64_t id = -1;
  sound::Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  int64_t last_sample = 0;  // stream sample of the last DOA update
  int64_t updates = 0;
};

struct SpeechResult {
  int64_t track_id = -1;
  bool has_direction = false;
  sound::Direction direction;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  std::string text, keyword;
  double confidence = 0;
  int64_t start_sample = 0, end_sample = 0;  // stream samples
  double direction_score = 0;  // how well its speech fits its direction (SpeechDirectionScore; BeamArbiter)
};

// Keeps, of keyword hits on different beams that overlap in time, only the one with the largest
// direction_score (see SpeechOptions::beam_arbitration_s). Results without a keyword pass at once.
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
  // A DOA update for a track at stream sample `sample`. False (counted) when the sample is more
  // than max_doa_ahead_s ahead of the audio seen.
  bool UpdateTrack(int64_t id, const sound::Direction& direction, const Eigen::Matrix2d& covariance,
                   int64_t sample);
  size_t num_tracks() const { return tracks_.size(); }
  bool has_track(int64_t id) const { return tracks_.count(id) > 0; }
  // Tracks evicted by a new one beyond max_tracks.
  int64_t tracks_evicted() const { return tracks_evicted_; }
  int64_t doas_ahead_dropped() const { return doas_ahead_dropped_; }
  // Feeds audio; appends finished utterances' results (one per keyword hit, or one with text).
  void Push(const int16_t* data, int frames, int block_channels, std::vector<SpeechResult>* results);
  void Flush(std::vector<SpeechResult>* results);
  int64_t samples_seen() const { return samples_seen_; }
  bool full_decoding() const { return full_decoding_; }
  void set_full_decoding(bool on) { full_decoding_ = on; }
  int64_t utterances() const { return utterances_; }
  // Keyword hits dropped as another beam's louder hit of the same utterance.
  int64_t leaked_hits_dropped() const { return arbiter_.dropped(); }
  // Keyword hits given to another tracked direction than their beam's.
  int64_t hits_reattributed() const { return reattributed_; }

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
  int64_t reattributed_ = 0;
  int64_t tracks_evicted_ = 0, doas_ahead_dropped_ = 0;
  // Speech-band spectra of the raw microphones (no overlap), kept a few seconds for the scores.
  struct BandFrame {
    int64_t end_sample = 0;
    Eigen::MatrixXcf bins;  // band bins x mics
  };
  std::unique_ptr<sound::MultichannelStft> band_stft_;
  std::vector<BandFrame> band_frames_;  // oldest first
  int band_lo_ = 0, band_hi_ = 0;
  // How well the speech of [start, end) fits `direction`: over the time-frequency bins 6 dB above
  // their floor (20th percentile of the 5 s before), the mean SRP-PHAT towards it (0..1).
  double SpeechDirectionScore(const sound::Direction& direction, int64_t start_sample, int64_t end_sample) const;
};

}  // namespace speech
}  // namespace sarmap
