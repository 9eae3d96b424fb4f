#pragma once
// What a sound source is (voice, alarm or tone, machinery or broadband noise, music), from its
// spectrum and its time pattern. No LCM.
//
// Per STFT frame, over the band [min_frequency_hz, max_frequency_hz] of the source's power
// spectrum P(k):
//   flatness  F = exp(mean_k ln P(k)) / mean_k P(k)          (1: white noise, -> 0: tones)
//   tonality  T = sum of P over the 3 strongest peaks (+-1 bin) / sum_k P(k)
//   flux      X = 1/2 sum_k (sqrt(p_t(k)) - sqrt(p_{t-1}(k)))^2, p = P / sum P  (0..1), over
//             the bins both frames hold
//   peak      the bin of max_k P(k)
// Over the last history_s of frames in which the source sounded (present frames):
//   level_std_db   standard deviation of 10 log10 sum_k P(k)
//   syllabic       RMS of the 2-8 Hz part of the energy envelope E(t) / mean E over the
//                  sounding stretch (syllables of speech at ~4 Hz; steady machines have little)
//   peak_share     share of present frames whose peak lies within +-1 bin of the two most
//                  frequent peak bins (an alarm repeats one or two pitches; music many notes)
//   steadiness     share of consecutive present frames whose peak stays in its bin (a tone or
//                  a note holds its pitch for many 16-ms frames; speech's pitch glides, and its
//                  strongest harmonic moves from frame to frame)
// and the means of F, T and X. Decision (SoundClassifier::Decide):
//   T >= tonal_min and X <= tonal_max_flux, or steadiness >= sustained_min
//                                  -> alarm if peak_share >= alarm_peak_share, else music
//   syllabic >= voice_syllabic_min and level_std_db >= steady_level_std_db
//                                  -> voice (speech rises and falls with its syllables)
//   otherwise                      -> machinery (steady broadband sound)
// Thresholds from synthesised sirens, beepers, tunes and machinery and the shared speech
// recordings (source_class_test): speech has T 0.29-0.47, syllabic 0.8-2.2, level std 6-10 dB;
// machinery and noise T 0.15, syllabic 0.05, level std 0.4 dB; tones and sirens T > 0.9. The
// flux keeps speech (X 0.19-0.28; T up to 0.57) out of the tonal classes (X 0.02-0.09).
// Steadiness: speech (recorded and espeak-ng) 0.00-0.24, with noise too; the synthesised tune
// 0.96, 0.83 in noise that makes it look like speech on T and X (0.60, 0.13); tones 0.93-0.98,
// a beeper in noise 0.50; machinery 0.02-0.04.
// A source heard for less than min_present_s is kUnknown, except a voice, decided from
// min_voice_present_s (a short call), and a clear alarm (T >= clear_alarm_tonal_min, peak share
// >= alarm_peak_share), decided as early; any other tonal or steady sound that short stays
// kUnknown. A frame
// sounds (is present) when its energy is within present_range_db of the loudest recent frame (one
// recording) or when the caller says so (a localiser reported the source in that block).
//
// DirectionalClassifier gives each direction reported by a localiser its own spectrum: a
// time-frequency bin belongs to the direction whose steering vector a explains it best,
// |a^H x|^2 / (M |x|^2) >= min_bin_coherence, by a margin over the next direction
// (bin_margin). A diffuse bin (no direction reaches min_bin_coherence) is shared by all as
// background for the spectral shape; the envelope uses a direction's own bins only.
// It keeps class tracks (directions in the array frame, followed as the
// localiser reports them) and classifies each from its own frames.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sound_localisation/array_geometry.h"
#include "sound_localisation/stft.h"

namespace sarmap {
namespace sound {

// Values as in doa_source_t / sound_source_t SOUND_CLASS_*.
enum class SoundClass : int8_t { kUnknown = 0, kVoice = 1, kAlarm = 2, kMachinery = 3, kMusic = 4 };
const char* SoundClassName(SoundClass c);

struct SourceClassOptions {
  int fft_size = 512;
  int hop_size = 256;
  // Small arrays tell directions apart only above ~1 kHz (the localiser's band), so the
  // features use the same band.
  double min_frequency_hz = 1000;
  double max_frequency_hz = 7000;
  double history_s = 4.0;       // features over this much of a source's recent frames
  double min_present_s = 0.75;  // less sound than this: kUnknown (voice: below)
  // A voice is decided from this much sound: a call for help may be half a second, while
  // alarms, music and machines sound for longer and wait for min_present_s.
  double min_voice_present_s = 0.25;
  // ... and so is a clear alarm: a tone or siren this tonal (speech stays below 0.6, the first
  // voiced 0.3 s of a vowel too; a pure tone or siren is above 0.9) on one or two pitches. A
  // robot hears an alarm in short pieces (bursts, other sources in between), and the tone
  // heard while driving through its standing waves rises and falls like speech.
  double clear_alarm_tonal_min = 0.9;
  double present_range_db = 20.0;  // one recording: frames this far below the loudest are pauses
  double tonal_min = 0.6;
  double tonal_max_flux = 0.15;
  double alarm_peak_share = 0.7;
  // A sound whose strongest peak stays in its bin over at least this share of consecutive frames
  // holds its pitch: an alarm or music, never a voice (> 1: off).
  double sustained_min = 0.5;
  double steady_level_std_db = 3.0;
  double voice_syllabic_min = 0.5;
  // DirectionalClassifier
  double min_bin_coherence = 0.6;
  double bin_margin = 0.05;
  // A frame also sounds for a direction that owns this share of its band energy, reported or
  // not (0: only reported blocks sound).
  double dominant_share = 0.0;
  // A new class track first takes the frames of the last replay_s that end after the start of
  // the block that reported it (the start of its sound).
  double replay_s = 1.0;
  double gate_deg = 20.0;  // a reported direction continues the nearest class track within this
  double forget_s = 20.0;  // a class track not reported for this long is dropped
  int max_tracks = 8;

  template <class V>
  void Visit(V& v) {
    v("fft_size", fft_size, "STFT frame length (samples)");
    v("hop_size", hop_size, "STFT hop (samples)");
    v("min_frequency_hz", min_frequency_hz, "lowest frequency of the features", Positive());
    v("max_frequency_hz", max_frequency_hz, "highest frequency of the features");
    v("history_s", history_s, "features over this much of a source's recent frames", Positive());
    v("min_present_s", min_present_s,
      "a source heard for less than this is unknown (a voice: min_voice_present_s)",
      InRange(0, history_s));
    v("min_voice_present_s", min_voice_present_s,
      "a voice is decided from this much sound (a short call)", InRange(0, min_present_s));
    v("clear_alarm_tonal_min", clear_alarm_tonal_min,
      "an alarm this tonal is decided from min_voice_present_s of sound (> 1: never)",
      NonNegative());
    v("present_range_db", present_range_db,
      "one recording: frames this far below the loudest are pauses", Positive());
    v("tonal_min", tonal_min, "mean tonality (3 peaks' share of the power) of alarms and music",
      InRange(0, 1));
    v("tonal_max_flux", tonal_max_flux,
      "mean spectral flux of alarms and music (speech changes faster)", InRange(0, 1));
    v("alarm_peak_share", alarm_peak_share,
      "tonal: share of frames on the two commonest pitches for an alarm", InRange(0, 1));
    v("sustained_min", sustained_min,
      "a sound whose strongest peak stays in its bin over this share of consecutive frames holds "
      "its pitch: alarm or music, never a voice (> 1: off)",
      NonNegative());
    v("steady_level_std_db", steady_level_std_db, "level std of a steady (machine) source, dB",
      NonNegative());
    v("voice_syllabic_min", voice_syllabic_min,
      "2-8 Hz RMS modulation of a voice's normalised energy envelope", NonNegative());
    v("min_bin_coherence", min_bin_coherence,
      "a bin belongs to a direction this coherent with it (0..1)", InRange(0, 1));
    v("bin_margin", bin_margin, "... by this margin over the next direction", InRange(0, 1));
    v("dominant_share", dominant_share,
      "a frame also sounds for a direction owning this share of its band energy, reported or not "
      "(0: off)",
      InRange(0, 1));
    v("replay_s", replay_s,
      "a new class track first takes the frames of its reporting block kept this long",
      NonNegative());
    v("gate_deg", gate_deg, "a reported direction continues the nearest class track within this",
      Positive());
    v("forget_s", forget_s, "a class track not reported for this long is dropped", Positive());
    v("max_tracks", max_tracks, "most class tracks kept", AtLeast(1));
  }
  void Validate(common::Validator& check) const {
    check.That(fft_size >= 64 && (fft_size & (fft_size - 1)) == 0, "fft_size",
               "must be a power of two >= 64");
    check.That(hop_size >= 1 && hop_size <= fft_size, "hop_size", "must be in [1, fft_size]");
    check.That(max_frequency_hz > min_frequency_hz, "max_frequency_hz",
               "must exceed min_frequency_hz");
  }
};

struct SoundClassFeatures {
  double present_s = 0;
  double flatness = 0, tonality = 0, flux = 0;
  double level_std_db = 0, syllabic = 0, peak_share = 0;
  double steadiness = 0;  // share of consecutive present frames whose peak stays in its bin
};

struct SoundClassEstimate {
  SoundClass sound_class = SoundClass::kUnknown;
  double confidence = 0;  // 0..1: how far the features are from the decision boundaries
  SoundClassFeatures features;
};

// One source's frames -> its class. Frames are power spectra of fft_size / 2 + 1 bins.
class SoundClassifier {
 public:
  SoundClassifier(const SourceClassOptions& options, int sample_rate_hz);
  // power: num_bins values (bins outside the band are ignored); a negative value marks a bin
  // that does not belong to this source (masked out). end_sample: the frame's stream position.
  // present < 0: the frame sounds when its band energy is within present_range_db of the
  // loudest recent frame (a single recording); 0 / 1: the caller decides (a
  // localiser's activity), or marks it later with MarkPresent.
  // envelope_energy >= 0: the frame's energy for the envelope (level, syllabic, presence)
  // instead of the band energy of `power` (a direction's own bins, without the shared
  // background).
  void AddFrame(const std::vector<float>& power, int64_t end_sample = 0, int present = -1,
                double envelope_energy = -1);
  // Frames ending in (begin_sample, end_sample] sounded, unless present_range_db below the
  // loudest recent frame.
  void MarkPresent(int64_t begin_sample, int64_t end_sample);
  SoundClassEstimate Classify() const;
  SoundClassFeatures Features() const;
  // The rule of the header from given features.
  static SoundClassEstimate Decide(const SoundClassFeatures& f, const SourceClassOptions& options);
  int64_t frames_seen() const { return frames_seen_; }

 private:
  struct Frame {
    int64_t end_sample = 0;
    bool present = false;
    double energy = 0;     // envelope energy (0 if no bin belongs to the source)
    double flatness = -1;  // -1: too few bins
    double tonality = 0, flux = 0;
    int peak = -1;
  };
  SourceClassOptions options_;
  double frame_rate_hz_;
  int bin_lo_, bin_hi_;
  size_t history_frames_;
  std::deque<Frame> frames_;
  std::vector<double> last_shape_;  // the last frame's band powers (-1: masked out)
  double max_energy_ = 0;           // loudest frame so far (decays slowly)
  int64_t frames_seen_ = 0;
};

// Multichannel audio + directions from a localiser -> class per direction.
class DirectionalClassifier {
 public:
  DirectionalClassifier(ArrayGeometry geometry, DoaKind kind, SourceClassOptions options);
  const SourceClassOptions& options() const { return options_; }
  // Audio, as Localiser::Push / PushFloat take it (mics through the array's channel_map).
  void Push(const int16_t* data, int frames, int block_channels);
  void PushFloat(const std::vector<std::vector<float>>& mic_channels, size_t begin, size_t count);
  void SkipSamples(int64_t samples);
  void ResetStream();
  // The directions a localiser reported for the block (begin_sample, end_sample] (stream
  // samples, as LocaliserOutput counts them): each continues (or starts) a class track whose
  // frames of the block are marked as sounding; returns the class of each, in order.
  std::vector<SoundClassEstimate> Observe(int64_t begin_sample, int64_t end_sample,
                                          const std::vector<Direction>& directions);
  // The class of the class track nearest each direction (within gate_deg; kUnknown if none),
  // without marking or starting tracks: for a second stream of the same audio, whose reports
  // would mark other sources' frames as sounding.
  std::vector<SoundClassEstimate> Lookup(const std::vector<Direction>& directions) const;
  size_t num_tracks() const { return tracks_.size(); }

 private:
  struct ClassTrack {
    Direction direction;
    Eigen::Vector3d unit = Eigen::Vector3d::UnitX();
    Eigen::MatrixXcd conj_steering;  // (bins of the band) x mics: exp(+j w tau_m)
    int64_t last_sample = 0;
    std::unique_ptr<SoundClassifier> classifier;
  };
  void OnFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample);
  // One frame's bins shared out among the tracks; only the track `only` gets it when
  // only < tracks_.size().
  void AddFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample, size_t only);
  struct RecentFrame {
    Eigen::MatrixXcf spectra;
    int64_t end_sample = 0;
  };
  std::deque<RecentFrame> recent_;
  ArrayGeometry geometry_;
  DoaKind kind_;
  SourceClassOptions options_;
  MultichannelStft stft_;
  int bin_lo_, bin_hi_;
  std::vector<ClassTrack> tracks_;
  std::vector<float> power_;
  std::vector<double> coherence_;
  int64_t samples_seen_ = 0;
  int64_t stream_offset_ = 0;
};

}  // namespace sound
}  // namespace sarmap
