// ALSA capture device (interleaved S16_LE, any channel count and rate the device offers).
#include <alsa/asoundlib.h>

#include <cmath>

#include "audio_capture/audio_source.h"
#include "common/logging.h"
#include "common/time.h"

namespace sarmap {
namespace audio {
namespace {

std::string AlsaError(const std::string& device, const std::string& what, int err) {
  return "ALSA device '" + device + "': " + what + ": " + snd_strerror(err);
}

class AlsaSource : public AudioSource {
 public:
  explicit AlsaSource(const CaptureOptions& o) : options_(o) {
    int err = snd_pcm_open(&pcm_, o.device.c_str(), SND_PCM_STREAM_CAPTURE, 0);
    if (err < 0)
      throw AudioSourceError(AlsaError(o.device, "cannot open for capture", err) +
                             " (is the sound card connected? list capture devices with 'arecord -l' / 'arecord -L')");
    snd_pcm_hw_params_t* hw;
    snd_pcm_hw_params_alloca(&hw);
    snd_pcm_hw_params_any(pcm_, hw);
    Check(snd_pcm_hw_params_set_access(pcm_, hw, SND_PCM_ACCESS_RW_INTERLEAVED), "interleaved access");
    Check(snd_pcm_hw_params_set_format(pcm_, hw, SND_PCM_FORMAT_S16_LE), "16-bit format");
    unsigned min_ch = 0, max_ch = 0;
    snd_pcm_hw_params_get_channels_min(hw, &min_ch);
    snd_pcm_hw_params_get_channels_max(hw, &max_ch);
    err = snd_pcm_hw_params_set_channels(pcm_, hw, o.num_channels);
    if (err < 0)
      Fail("cannot capture " + std::to_string(o.num_channels) + " channels (the device offers " +
           std::to_string(min_ch) + ".." + std::to_string(max_ch) + "; fix num_channels or the array's channel_map)");
    unsigned rate = o.sample_rate_hz;
    Check(snd_pcm_hw_params_set_rate_near(pcm_, hw, &rate, nullptr), "sample rate");
    if (static_cast<int>(rate) != o.sample_rate_hz)
      Fail("gives " + std::to_string(rate) + " Hz, not the requested " + std::to_string(o.sample_rate_hz) +
           " Hz (use a plughw: device to resample, or change sample_rate_hz and the array description)");
    snd_pcm_uframes_t period = o.alsa_period_frames;
    Check(snd_pcm_hw_params_set_period_size_near(pcm_, hw, &period, nullptr), "period size");
    snd_pcm_uframes_t buffer = period * o.alsa_buffer_periods;
    Check(snd_pcm_hw_params_set_buffer_size_near(pcm_, hw, &buffer), "buffer size");
    Check(snd_pcm_hw_params(pcm_, hw), "hardware parameters");
    Check(snd_pcm_prepare(pcm_), "prepare");
    rate_ = static_cast<int>(rate);
    id_ = o.device_id.empty() ? o.device : o.device_id;
  }
  ~AlsaSource() override {
    if (pcm_) snd_pcm_close(pcm_);
  }
  int sample_rate_hz() const override { return rate_; }
  int num_channels() const override { return options_.num_channels; }
  std::string device_id() const override { return id_; }

  bool Read(int frames, AudioBlock* block) override {
    const int nc = options_.num_channels;
    block->samples.resize(static_cast<size_t>(frames) * nc);
    int done = 0;
    while (done < frames) {
      const snd_pcm_sframes_t n = snd_pcm_readi(pcm_, block->samples.data() + static_cast<size_t>(done) * nc, frames - done);
      if (n == -EPIPE || n == -ESTRPIPE) {
        // Overrun: the ring buffer filled before we read it; samples were lost. Estimate how
        // many from the wall clock and keep the counter honest.
        const double now = common::SteadySeconds();
        if (n == -ESTRPIPE)
          while (snd_pcm_resume(pcm_) == -EAGAIN) snd_pcm_wait(pcm_, 100);
        snd_pcm_prepare(pcm_);
        pending_overrun_ = true;
        overrun_detected_s_ = now;
        ++overrun_events_;
        continue;
      }
      if (n == -EAGAIN) continue;
      if (n < 0) throw AudioSourceError(AlsaError(options_.device, "read failed", static_cast<int>(n)));
      done += static_cast<int>(n);
    }
    const double now = common::SteadySeconds();
    if (pending_overrun_) {
      // Samples that should have arrived since the last good read, minus those we got.
      const double expected = (now - last_read_s_) * rate_;
      const int64_t lost = std::max<int64_t>(static_cast<int64_t>(std::llround(expected)) - frames, 1);
      overrun_total_ += lost;
      next_index_ += lost;
      SARMAP_LOG(WARN) << "ALSA overrun on '" << options_.device << "': about " << lost << " samples lost ("
                       << overrun_events_ << " overruns, " << overrun_total_ << " samples so far)";
      pending_overrun_ = false;
    }
    last_read_s_ = now;
    snd_pcm_sframes_t delay = 0;
    if (snd_pcm_delay(pcm_, &delay) < 0) delay = 0;
    block->num_channels = nc;
    block->num_frames = frames;
    block->first_sample_index = next_index_;
    block->overrun_samples = overrun_total_;
    block->utime = common::WallClockUtime() - common::SecondsToUtime(static_cast<double>(frames + delay) / rate_);
    next_index_ += frames;
    return true;
  }

 private:
  void Check(int err, const std::string& what) {
    if (err < 0) Fail(std::string("cannot set ") + what + ": " + snd_strerror(err));
  }
  [[noreturn]] void Fail(const std::string& what) {
    snd_pcm_close(pcm_);
    pcm_ = nullptr;
    throw AudioSourceError("ALSA device '" + options_.device + "': " + what);
  }
  CaptureOptions options_;
  snd_pcm_t* pcm_ = nullptr;
  int rate_ = 0;
  std::string id_;
  int64_t next_index_ = 0, overrun_total_ = 0, overrun_events_ = 0;
  bool pending_overrun_ = false;
  double overrun_detected_s_ = 0, last_read_s_ = common::SteadySeconds();
};

}  // namespace

std::unique_ptr<AudioSource> OpenAlsaSource(const CaptureOptions& options) {
  return std::make_unique<AlsaSource>(options);
}

}  // namespace audio
}  // namespace sarmap
