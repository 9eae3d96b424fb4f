// bench_audio_chain: CPU cost of capture -> DOA -> tracking -> enhancement -> keyword spotting
// for a 4-channel 16 kHz array on one core (real ReSpeaker recordings), and latency from a sound
// onset to its first DOA. Prints figures; asserts nothing.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "audio_capture/audio_source.h"
#include "common/robot_config.h"
#include "sound_localisation/localiser.h"
#include "sound_localisation/testing/room_simulation.h"
#include "speech/speech_processor.h"

using namespace sarmap;

static double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

int main() {
  namespace fs = std::filesystem;
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/audio/respeaker4/a180e20";
  const auto array = common::LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/respeaker4.yaml");
  const auto geometry = sound::ArrayGeometry::FromOptions(array);
  std::vector<std::string> files;
  if (fs::exists(dir))
    for (const auto& e : fs::recursive_directory_iterator(dir))
      if (e.path().extension() == ".wav") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::printf("shared data missing: %s\n", dir.c_str());
    return 0;
  }
  struct Config {
    std::string method;
    bool verify;
    bool call_shape;  // the default call-shape rule (max_utterance_s); off = every utterance decoded
    bool verifier = false;  // config/speech.yaml's keyword verifier, switched on
  };
  for (const Config& cfg : {Config{"srp_phat", false, true}, Config{"srp_phat", false, false},
                            Config{"srp_phat", true, false}, Config{"srp_phat", true, true},
                            Config{"music", false, true}, Config{"srp_phat", false, true, true}}) {
    const std::string method = cfg.method;
    sound::LocaliserOptions lo;
    lo.method = method;
    sound::Localiser localiser(geometry, lo, sound::SensorModel::FromArray(array, ""));
    speech::SpeechOptions so;  // defaults (= config/speech.yaml): MVDR + post-filter, VAD, kws + call shape
    so.keywords.verify_with_lm = cfg.verify;
    if (!cfg.call_shape) so.keywords.max_utterance_s = 0;
    if (cfg.verifier) {
      so.keywords.verifier = common::LoadOptions<speech::SpeechOptions>(
                                 std::string(SARMAP_SOURCE_DIR) + "/config/speech.yaml", {}, "speech")
                                 .keywords.verifier;
      so.keywords.verifier.enabled = true;
    }
    speech::SpeechProcessor processor(geometry, localiser.kind(), so);
    double t_capture = 0, t_doa = 0, t_speech = 0, audio_s = 0;
    int doa_outputs = 0, results = 0;
    double max_doa_ms = 0;
    for (const auto& f : files) {
      audio::CaptureOptions co;
      co.file = f;
      co.speed = 0;
      auto source = audio::OpenAudioSource(co);
      audio::SignalChecker checker(co, source->sample_rate_hz(), source->num_channels());
      audio::AudioBlock block;
      std::vector<sound::LocaliserOutput> outs;
      std::vector<speech::SpeechResult> res;
      while (true) {
        double t0 = CpuSeconds();
        if (!source->Read(512, &block)) break;
        checker.Check(block);
        double t1 = CpuSeconds();
        outs.clear();
        localiser.Push(block.samples.data(), block.num_frames, block.num_channels, &outs);
        double t2 = CpuSeconds();
        for (const auto& o : outs) {
          ++doa_outputs;
          for (const auto& t : o.tracks)
            if (t.updated) processor.UpdateTrack(t.id, t.direction, t.covariance, o.end_sample);
        }
        if (!outs.empty()) max_doa_ms = std::max(max_doa_ms, 1e3 * (t2 - t1));
        res.clear();
        processor.Push(block.samples.data(), block.num_frames, block.num_channels, &res);
        double t3 = CpuSeconds();
        results += static_cast<int>(res.size());
        t_capture += t1 - t0;
        t_doa += t2 - t1;
        t_speech += t3 - t2;
        audio_s += block.num_frames / 16000.0;
      }
    }
    const double total = t_capture + t_doa + t_speech;
    std::printf("[%s, LM verification %s, keyword verifier %s, call-shape rule %s] %.1f s of 4-ch 16 kHz audio (%zu real ReSpeaker "
                "files), one thread:\n", method.c_str(), cfg.verify ? "on" : "off", cfg.verifier ? "on" : "off",
                cfg.call_shape ? "on (default)" : "off (every utterance decoded)", audio_s, files.size());
    std::printf("  capture (libsndfile + checks) %.4f s  = %.2f%% of a core\n", t_capture, 100 * t_capture / audio_s);
    std::printf("  DOA + tracking                %.3f s  = %.2f%% of a core (%d outputs, worst %.1f ms each)\n", t_doa,
                100 * t_doa / audio_s, doa_outputs, max_doa_ms);
    std::printf("  enhancement + VAD + keywords  %.3f s  = %.2f%% of a core (%lld utterances, %d results)\n", t_speech,
                100 * t_speech / audio_s, static_cast<long long>(processor.utterances()), results);
    std::printf("  whole chain                   %.3f s  = %.2f%% of a core (goal <= 25%%)\n", total,
                100 * total / audio_s);
  }
  // Latency: a talker starts at t = 1.0 s after noise; time from the onset to the first DOA
  // output (audio-time latency: the block must complete) plus its compute time.
  {
    auto speech = std::vector<float>();
    const std::string wav = std::string(SARMAP_DATA_DIR) + "/audio/cmu_arctic/cmu_arctic_us_aew_a0001.wav";
    if (fs::exists(wav)) speech = audio::ReadAudioFile(wav).channels[0];
    const size_t n = 16000 + speech.size();
    std::vector<float> sig(n, 0.0f);
    for (size_t i = 0; i < speech.size(); ++i) sig[16000 + i] = speech[i] * 4;
    sound::Room room;
    const Eigen::Vector3d centre(3, 2.5, 1);
    const auto mics = sound::SimulateRoom(room, geometry.positions_m.colwise() + centre,
                                          {{centre + Eigen::Vector3d(-1.5, 0.2, 0.5), sig}}, n, 0.001, 3);
    const auto pcm = audio::ToInterleavedInt16(mics, 0, n);
    sound::Localiser localiser(geometry, sound::LocaliserOptions{}, nullptr);
    std::vector<sound::LocaliserOutput> outs;
    for (size_t i = 0; i < n; i += 512) {
      const auto t0 = std::chrono::steady_clock::now();
      outs.clear();
      localiser.Push(pcm.data() + i * 4, static_cast<int>(std::min<size_t>(512, n - i)), 4, &outs);
      const double compute = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      bool found = false;
      for (const auto& o : outs)
        if (!o.directions.empty()) {
          const double onset_to_block_end = o.end_sample / 16000.0 - 1.0;
          const double block_end_to_delivery = (i + 512.0 - o.end_sample) / 16000.0;
          std::printf("latency sound onset -> first DOA: %.0f ms of audio (block %.0f ms, window %d blocks) + %.0f ms "
                      "until the capture block is delivered + %.1f ms compute = %.0f ms (capture block 32 ms adds up to "
                      "32 ms more on a device)\n",
                      1e3 * onset_to_block_end, 1e3 * sound::LocaliserOptions{}.block_s,
                      sound::LocaliserOptions{}.window_blocks, 1e3 * block_end_to_delivery, 1e3 * compute,
                      1e3 * (onset_to_block_end + block_end_to_delivery + compute));
          found = true;
          break;
        }
      if (found) break;
    }
  }
  return 0;
}
