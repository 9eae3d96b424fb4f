#include "speech/speech_processor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "common/logging.h"

namespace sarmap {
namespace speech {

SpeechProcessor::SpeechProcessor(sound::ArrayGeometry geometry, sound::DoaKind kind,
                                 SpeechOptions options)
    : geometry_(geometry),
      kind_(kind),
      options_(options),
      enhancer_(geometry, options.enhancer),
      spotter_(options.keywords),
      full_decoding_(options.keywords.full_decoding),
      arbiter_(static_cast<int64_t>(options.beam_arbitration_s * geometry.sample_rate_hz)) {
  if (geometry_.sample_rate_hz != 16000)
    throw std::invalid_argument("the PocketSphinx en-us model needs 16 kHz audio; array '" +
                                geometry_.name + "' is " +
                                std::to_string(geometry_.sample_rate_hz) + " Hz");
  output_offset_ = options.enhancer.fft_size - options.enhancer.hop_size;
  if (options_.beam_arbitration_s > 0) {
    constexpr int kFft = 512;
    band_stft_ = std::make_unique<sound::MultichannelStft>(geometry_.num_mics(), kFft, kFft);
    band_lo_ = static_cast<int>(300.0 * kFft / geometry_.sample_rate_hz);
    band_hi_ = static_cast<int>(3400.0 * kFft / geometry_.sample_rate_hz);
  }
}

double SpeechProcessor::SpeechDirectionScore(const sound::Direction& direction,
                                             int64_t start_sample, int64_t end_sample) const {
  if (band_frames_.empty()) return 0;
  const int n = band_hi_ - band_lo_ + 1, mics = geometry_.num_mics();
  const int64_t floor_span = 5 * geometry_.sample_rate_hz;
  // Per-bin floor: a low percentile of the mics' mean power over the 5 s before the hit.
  std::vector<std::vector<float>> history(n);
  for (const BandFrame& f : band_frames_) {
    if (f.end_sample <= start_sample - floor_span || f.end_sample > start_sample) continue;
    for (int b = 0; b < n; ++b) history[b].push_back(f.bins.row(b).squaredNorm() / mics);
  }
  std::vector<float> floor(n, 0.0f);
  for (int b = 0; b < n; ++b) {
    if (history[b].empty()) continue;
    auto q = history[b].begin() + history[b].size() / 5;
    std::nth_element(history[b].begin(), q, history[b].end());
    floor[b] = *q;
  }
  const Eigen::VectorXd tau = geometry_.Delays(geometry_.Unit(kind_, direction));
  double score = 0;
  int used = 0;
  for (const BandFrame& f : band_frames_) {
    if (f.end_sample <= start_sample || f.end_sample > end_sample + band_stft_->fft_size())
      continue;
    for (int b = 0; b < n; ++b) {
      if (f.bins.row(b).squaredNorm() / mics < 4.0f * floor[b])
        continue;  // not 6 dB over its floor
      const double w = 2 * M_PI * (band_lo_ + b) * static_cast<double>(geometry_.sample_rate_hz) /
                       band_stft_->fft_size();
      // PHAT: each mic's phase only, aligned for the direction; |sum|^2 is mics^2 when they agree.
      std::complex<double> sum = 0;
      for (int m = 0; m < mics; ++m) {
        const std::complex<double> x(f.bins(b, m).real(), f.bins(b, m).imag());
        if (std::abs(x) < 1e-12) continue;
        sum += x / std::abs(x) * std::polar(1.0, w * tau[m]);
      }
      score += std::norm(sum) / (mics * mics);
      ++used;
    }
  }
  return used ? score / used : 0;
}

bool SpeechProcessor::UpdateTrack(int64_t id, const sound::Direction& d, const Eigen::Matrix2d& cov,
                                  int64_t sample) {
  if (sample - samples_seen_ >
      static_cast<int64_t>(options_.max_doa_ahead_s * geometry_.sample_rate_hz)) {
    ++doas_ahead_dropped_;
    return false;
  }
  auto it = tracks_.find(id);
  if (it == tracks_.end()) {
    if (static_cast<int>(tracks_.size()) >= options_.max_tracks) {
      // Least recently updated first; of equals, the one with fewer updates.
      auto oldest =
          std::min_element(tracks_.begin(), tracks_.end(), [](const auto& a, const auto& b) {
            return a.second.last_sample != b.second.last_sample
                       ? a.second.last_sample < b.second.last_sample
                       : a.second.updates < b.second.updates;
          });
      tracks_.erase(oldest);
      ++tracks_evicted_;
    }
    it = tracks_.emplace(id, TrackedSource{}).first;
  }
  TrackedSource& t = it->second;
  t.id = id;
  t.direction = d;
  t.covariance = cov;
  t.last_sample = sample;
  ++t.updates;
  return true;
}

void SpeechProcessor::Push(const int16_t* data, int frames, int block_channels,
                           std::vector<SpeechResult>* out) {
  std::vector<SpeechResult>* results = &fresh_;
  samples_seen_ += frames;
  if (band_stft_) {
    band_stft_->PushInterleaved(
        data, frames, block_channels, geometry_.channel_map,
        [&](const Eigen::MatrixXcf& spectra, int64_t end_sample) {
          band_frames_.push_back(
              {end_sample, spectra.middleRows(band_lo_, band_hi_ - band_lo_ + 1)});
        });
    // Kept: the floor span before the oldest hit still waiting, and that hit.
    const int64_t keep =
        static_cast<int64_t>((options_.beam_arbitration_s + 12.0) * geometry_.sample_rate_hz);
    size_t old = 0;
    while (old < band_frames_.size() && samples_seen_ - band_frames_[old].end_sample > keep) ++old;
    band_frames_.erase(band_frames_.begin(), band_frames_.begin() + old);
  }
  const int64_t timeout = static_cast<int64_t>(options_.track_timeout_s * geometry_.sample_rate_hz);
  for (auto it = tracks_.begin(); it != tracks_.end();)
    it = samples_seen_ - it->second.last_sample > timeout ? tracks_.erase(it) : std::next(it);
  // Most recently updated tracks first.
  std::vector<const TrackedSource*> order;
  for (const auto& [id, t] : tracks_) {
    if (t.updates >= options_.min_track_updates) order.push_back(&t);
  }
  std::sort(order.begin(), order.end(),
            [](auto* a, auto* b) { return a->last_sample > b->last_sample; });
  std::vector<Beam> beams;
  for (size_t i = 0; i < order.size() && static_cast<int>(i) < options_.max_sources; ++i)
    beams.push_back({order[i]->id, geometry_.Unit(kind_, order[i]->direction)});
  if (beams.empty() && options_.untracked_beam) {
    // Omnidirectional: broadside of the array (delay-and-sum of nearly aligned mics for
    // nearby talkers) is as good as any guess without a direction.
    beams.push_back(
        {-1, geometry_.is_linear() ? geometry_.axis.unitOrthogonal() : geometry_.normal});
  }
  for (auto& [id, buf] : enhanced_) buf.clear();
  enhancer_.Push(data, frames, block_channels, beams, &enhanced_);
  for (auto& [id, buf] : enhanced_) {
    if (buf.empty()) continue;
    auto& vad = vads_[id];
    if (!vad) {
      vad = std::make_unique<VoiceActivityDetector>(geometry_.sample_rate_hz, options_.vad);
      vad_origins_[id] = std::max<int64_t>(0, enhancer_.FirstOutputIndex(id));
    }
    std::vector<Utterance> done;
    vad->Push(buf.data(), buf.size(), &done);
    for (const auto& u : done) Handle(id, u, results);
    // A call ends when no new speech began within call_join_s of its last segment.
    auto c = calls_.find(id);
    if (c != calls_.end() && c->second.open && !vad->in_speech() &&
        vad->position() - c->second.end_sample >=
            static_cast<int64_t>(options_.keywords.call_join_s * geometry_.sample_rate_hz))
      FinishCall(id, results);
  }
  // Beams that ended: flush their VAD.
  for (auto it = vads_.begin(); it != vads_.end();) {
    bool active = false;
    for (const Beam& b : beams) active |= b.id == it->first;
    if (active) {
      ++it;
      continue;
    }
    std::vector<Utterance> done;
    it->second->Flush(&done);
    for (const auto& u : done) Handle(it->first, u, results);
    FinishCall(it->first, results);
    enhanced_.erase(it->first);
    vad_origins_.erase(it->first);
    it = vads_.erase(it);
  }
  arbiter_.Push(&fresh_, samples_seen_, false, out);
}

void SpeechProcessor::Flush(std::vector<SpeechResult>* out) {
  for (auto& [id, vad] : vads_) {
    std::vector<Utterance> done;
    vad->Flush(&done);
    for (const auto& u : done) Handle(id, u, &fresh_);
    FinishCall(id, &fresh_);
  }
  arbiter_.Push(&fresh_, samples_seen_, true, out);
}

void BeamArbiter::Push(std::vector<SpeechResult>* fresh, int64_t now, bool flush,
                       std::vector<SpeechResult>* out) {
  for (SpeechResult& r : *fresh) {
    if (hold_samples_ <= 0 || r.keyword.empty())
      out->push_back(std::move(r));
    else
      held_.push_back(std::move(r));
  }
  fresh->clear();
  if (held_.empty()) return;
  // A louder hit of another beam over the same stretch of the stream: this one is its leak.
  auto louder_elsewhere = [](const SpeechResult& r, const std::vector<SpeechResult>& others) {
    for (const SpeechResult& o : others)
      if (o.track_id != r.track_id && o.start_sample < r.end_sample &&
          r.start_sample < o.end_sample && o.direction_score > r.direction_score)
        return true;
    return false;
  };
  std::vector<SpeechResult> waiting, now_decided;
  for (SpeechResult& r : held_) {
    if (!flush && now - r.end_sample < hold_samples_) {
      waiting.push_back(std::move(r));
      continue;
    }
    now_decided.push_back(std::move(r));
  }
  for (const SpeechResult& r : now_decided) {
    if (louder_elsewhere(r, now_decided) || louder_elsewhere(r, waiting) ||
        louder_elsewhere(r, decided_))
      ++dropped_;
    else
      out->push_back(r);
  }
  decided_.insert(decided_.end(), now_decided.begin(), now_decided.end());
  held_ = std::move(waiting);
  // Decided hits matter only to hits that end at most hold_samples_ after them.
  decided_.erase(
      std::remove_if(decided_.begin(), decided_.end(),
                     [&](const SpeechResult& d) { return now - d.end_sample > 4 * hold_samples_; }),
      decided_.end());
}

bool SpeechProcessor::joins_calls() const {
  return options_.keywords.call_join_s > 0 && options_.keywords.max_utterance_s > 0;
}

void SpeechProcessor::FinishCall(int64_t id, std::vector<SpeechResult>* results) {
  auto it = calls_.find(id);
  if (it == calls_.end() || !it->second.open) return;
  PendingCall& c = it->second;
  const double call_s =
      static_cast<double>(c.end_sample - c.samples_start) / geometry_.sample_rate_hz;
  if (call_s <= options_.keywords.max_utterance_s)
    results->insert(results->end(), c.results.begin(), c.results.end());
  calls_.erase(it);
}

void SpeechProcessor::Handle(int64_t id, const Utterance& u, std::vector<SpeechResult>* results) {
  ++utterances_;
  SARMAP_LOG(DEBUG) << "segment: beam " << id << ", "
                    << u.start_sample / static_cast<double>(geometry_.sample_rate_hz) << "-"
                    << u.end_sample / static_cast<double>(geometry_.sample_rate_hz) << " s";
  const DecodeResult d = spotter_.Decode(
      u.samples.data(), u.samples.size(), full_decoding_,
      static_cast<double>(u.start_sample - u.samples_start) / geometry_.sample_rate_hz,
      static_cast<double>(u.end_sample - u.samples_start) / geometry_.sample_rate_hz);
  SpeechResult base;
  base.track_id = id;
  auto it = tracks_.find(id);
  if (it != tracks_.end()) {
    base.has_direction = true;
    base.direction = it->second.direction;
    base.covariance = it->second.covariance;
  }
  // VAD sample counts -> stream samples: where this beam's VAD started, less the enhancer's delay.
  const auto origin_it = vad_origins_.find(id);
  const int64_t to_stream =
      (origin_it == vad_origins_.end() ? 0 : origin_it->second) - output_offset_;
  base.start_sample = u.start_sample + to_stream;
  base.end_sample = u.end_sample + to_stream;
  base.text = d.text;
  // With joined calls, keyword results wait for the end of their call (text does not).
  std::vector<SpeechResult>* keyword_out = results;
  if (joins_calls()) {
    const int64_t join =
        static_cast<int64_t>(options_.keywords.call_join_s * geometry_.sample_rate_hz);
    auto c = calls_.find(id);
    if (c != calls_.end() && c->second.open && u.start_sample - c->second.end_sample >= join)
      FinishCall(id, results);
    PendingCall& call = calls_[id];
    if (!call.open) {
      call.open = true;
      call.samples_start = u.samples_start;
    }
    call.end_sample = u.end_sample;
    keyword_out = &call.results;
  }
  bool any = false;
  for (const KeywordHit& h : d.keywords) {
    if (h.confidence < options_.keywords.min_confidence) continue;
    SpeechResult r = base;
    r.keyword = h.keyword;
    r.confidence = h.confidence;
    const int64_t s0 = u.samples_start + to_stream;
    r.start_sample = s0 + static_cast<int64_t>(h.start_s * geometry_.sample_rate_hz);
    r.end_sample = s0 + static_cast<int64_t>(h.end_s * geometry_.sample_rate_hz);
    if (band_stft_) {
      // The hit belongs to the tracked direction its speech came from (SpeechDirectionScore),
      // which need not be the beam that decoded it (a talker leaks into every beam, and his own
      // track may have no beam when more than max_sources are tracked).
      if (r.has_direction)
        r.direction_score = SpeechDirectionScore(r.direction, r.start_sample, r.end_sample);
      for (const auto& [track_id, track] : tracks_) {
        if (track_id == r.track_id) continue;
        const double g = SpeechDirectionScore(track.direction, r.start_sample, r.end_sample);
        if (g > r.direction_score) {
          r.direction_score = g;
          r.track_id = track_id;
          r.has_direction = true;
          r.direction = track.direction;
          r.covariance = track.covariance;
          ++reattributed_;
        }
      }
    }
    keyword_out->push_back(r);
    any = true;
  }
  if (!any && !d.text.empty()) {
    base.confidence = d.text_confidence;
    results->push_back(base);
  }
}

}  // namespace speech
}  // namespace sarmap
