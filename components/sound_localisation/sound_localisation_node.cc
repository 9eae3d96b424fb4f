// sarmap-sound-localisation: AUDIO (audio_frame_t) -> DOA (doa_t: directions with covariance
// and track ids), for one microphone array.
#include <cmath>

#include "common/args.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"
#include "sound_localisation/async_alignment.h"
#include "sound_localisation/audio_intake.h"
#include "sound_localisation/doa_stream.h"

using namespace sarmap;

using sound::SoundLocalisationOptions;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-sound-localisation", [&]() {
    common::NodeArgs args;
    common::ArgParser p(
        "sarmap-sound-localisation",
        "Directions of arrival (SRP-PHAT, MUSIC, GEVD-MUSIC, GCC-PHAT, ESPRIT) with tracking.");
    p.AddNodeOptions(&args, "config/sound_localisation.yaml");
    p.SetEpilog("Channels: in AUDIO (audio_frame_t), out DOA (doa_t), NODE_STATUS.");
    if (!p.Parse(argc, argv)) return 0;
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options =
        common::LoadOptions<SoundLocalisationOptions>(args.config_path, args.overrides);
    if (args.print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    const auto array = common::LoadMicArray(options.array);
    const std::string array_dir = options.array.substr(0, options.array.find_last_of('/') + 1);
    std::unique_ptr<sound::DoaStream> stream;
    try {
      stream = std::make_unique<sound::DoaStream>(options, array, array_dir);
    } catch (const std::invalid_argument& e) {
      throw common::OptionsError(e.what());
    }
    const sound::ArrayGeometry& geometry = stream->geometry();
    int needed_channels = 0;
    for (int c : geometry.channel_map) needed_channels = std::max(needed_channels, c + 1);
    const bool asynchronous = !options.devices.empty();
    std::unique_ptr<sound::AsyncStreamAligner> aligner;
    std::vector<int> needed_per_device(options.devices.size(), 0);
    if (asynchronous) {
      if (static_cast<int>(options.mic_devices.size()) != geometry.num_mics())
        throw common::OptionsError("mic_devices has " + std::to_string(options.mic_devices.size()) +
                                   " entries, array '" + geometry.name + "' has " +
                                   std::to_string(geometry.num_mics()) + " microphones");
      try {
        aligner = std::make_unique<sound::AsyncStreamAligner>(
            geometry.sample_rate_hz, array.start_offsets_s, array.clock_drift, geometry.num_mics());
      } catch (const std::invalid_argument& e) {
        throw common::OptionsError(e.what());
      }
      for (int m = 0; m < geometry.num_mics(); ++m)
        needed_per_device[options.mic_devices[m]] =
            std::max(needed_per_device[options.mic_devices[m]], geometry.channel_map[m] + 1);
    }

    common::Node node("sarmap-sound-localisation", args);
    auto pub = node.Advertise<sarmap::doa_t>(options.doa_channel);
    std::vector<common::Node::Publisher<sarmap::doa_t>> map_pub;
    if (stream->has_map_stream())
      map_pub.push_back(node.Advertise<sarmap::doa_t>(options.map_doa_channel));
    sound::AudioIntake intake(options.device_id, geometry.sample_rate_hz,
                              options.max_bridged_gap_s);
    std::string device = options.device_id;
    int64_t last_overrun = 0, dropped = 0, published = 0;
    common::RateLimiter warn_limit(5.0);
    std::vector<sarmap::doa_t> doas, map_doas;

    auto warn = [&](const std::string& what) {
      ++dropped;
      long suppressed = 0;
      if (warn_limit.Allow(common::SteadySeconds(), &suppressed)) {
        SARMAP_LOG(WARN) << what
                         << (suppressed ? " (" + std::to_string(suppressed) + " similar suppressed)"
                                        : "");
      }
    };

    auto publish = [&] {
      for (auto& d : doas) pub.Publish(&d);
      for (auto& d : map_doas) map_pub[0].Publish(&d);
      published += static_cast<int64_t>(doas.size() + map_doas.size());
      doas.clear();
      map_doas.clear();
    };

    // Asynchronous array: each card's block goes to the aligner; aligned reference samples go to
    // the localiser. Reference time: the card of microphone 0 (tau = 0, drift = 0).
    std::vector<std::vector<float>> aligned;
    std::vector<float> channel;
    std::vector<int64_t> device_expected(options.devices.size(), -1);
    int64_t ref_utime = 0, ref_first = 0;
    auto on_async = [&](const sarmap::audio_frame_t& msg) {
      const auto it = std::find(options.devices.begin(), options.devices.end(), msg.device_id);
      if (it == options.devices.end())
        return warn("audio from device '" + msg.device_id +
                    "' ignored: not one of this array's devices");
      const int d = static_cast<int>(it - options.devices.begin());
      if (msg.sample_rate_hz != geometry.sample_rate_hz)
        return warn("sample-rate mismatch: device '" + msg.device_id + "' is " +
                    std::to_string(msg.sample_rate_hz) + " Hz, array '" + geometry.name +
                    "' expects " + std::to_string(geometry.sample_rate_hz) + " Hz; block dropped");
      if (msg.num_channels < needed_per_device[d])
        return warn("device '" + msg.device_id + "' has " + std::to_string(msg.num_channels) +
                    " channels, needs " + std::to_string(needed_per_device[d]) + "; block dropped");
      if (msg.sample_format != sarmap::audio_frame_t::SAMPLE_INT16 ||
          msg.num_values != static_cast<int32_t>(msg.num_channels) * msg.num_samples)
        return warn("malformed audio block (format or size); dropped");
      // Rate-limited: at datagram loss every lost block is a gap (the aligner counts them all).
      if (device_expected[d] >= 0 && msg.first_sample_index != device_expected[d] &&
          warn_limit.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << "device '" << common::EscapeForLog(msg.device_id)
                         << "': gap, expected sample " << device_expected[d] << ", got "
                         << msg.first_sample_index << " (filled with zeros)";
      }
      device_expected[d] = msg.first_sample_index + msg.num_samples;
      for (int m = 0; m < geometry.num_mics(); ++m) {
        if (options.mic_devices[m] != d) continue;
        channel.resize(msg.num_samples);
        for (int i = 0; i < msg.num_samples; ++i)
          channel[i] = msg.samples[i * msg.num_channels + geometry.channel_map[m]] / 32768.0f;
        aligner->Push(m, msg.first_sample_index, channel.data(), channel.size());
      }
      if (d == options.mic_devices[0]) {
        ref_utime = msg.header.utime;
        ref_first = msg.first_sample_index;
      }
      for (auto& a : aligned) a.clear();
      const int64_t first = aligner->next_reference_sample();
      const size_t n = aligner->Pull(&aligned);
      if (n == 0) return;
      const int64_t before = stream->samples_seen();
      // Stream sample `before` is reference sample `first`.
      stream->PushFloat(aligned, n, ref_utime, before + (ref_first - first), &doas, &map_doas);
      publish();
      node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " +
                            std::to_string(dropped) + ", samples lost " +
                            std::to_string(aligner->dropped_samples()));
    };
    if (asynchronous) {
      device.clear();
      for (const auto& d : options.devices) device += (device.empty() ? "" : "+") + d;
      stream->set_device(device);
      std::vector<std::string> channels = options.audio_channels;
      if (channels.empty()) channels.push_back(options.audio_channel);
      for (const auto& ch : channels)
        node.Subscribe<sarmap::audio_frame_t>(
            ch,
            [&](const sarmap::audio_frame_t& msg, const common::ReceiveInfo&) { on_async(msg); });
    } else
      node.Subscribe<sarmap::audio_frame_t>(
          options.audio_channel, [&](const sarmap::audio_frame_t& msg, const common::ReceiveInfo&) {
            if (!intake.FromDeviceLogged(msg.device_id)) {
              ++dropped;
              node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " +
                                    std::to_string(dropped) + "; audio " + intake.Summary());
              return;
            }
            device = intake.device();
            stream->set_device(device);
            if (msg.sample_rate_hz != geometry.sample_rate_hz)
              return warn("sample-rate mismatch: audio is " + std::to_string(msg.sample_rate_hz) +
                          " Hz, array '" + geometry.name + "' expects " +
                          std::to_string(geometry.sample_rate_hz) + " Hz; block dropped");
            if (msg.num_channels < needed_channels)
              return warn("audio has " + std::to_string(msg.num_channels) + " channels, array '" +
                          geometry.name + "' needs " + std::to_string(needed_channels) +
                          " (channel_map); block dropped");
            if (msg.sample_format != sarmap::audio_frame_t::SAMPLE_INT16 ||
                msg.num_values != static_cast<int32_t>(msg.num_channels) * msg.num_samples)
              return warn("malformed audio block (format or size); dropped");
            if (msg.overrun_samples != last_overrun) {
              if (warn_limit.Allow(common::SteadySeconds()))
                SARMAP_LOG(WARN) << "device '" << common::EscapeForLog(device) << "' lost "
                                 << (msg.overrun_samples - last_overrun) << " samples (overrun)";
              last_overrun = msg.overrun_samples;
            }
            const sound::AudioIntake::Decision decision =
                intake.Sequence(msg.first_sample_index, msg.num_samples);
            switch (decision.verdict) {
              case sound::AudioIntake::Verdict::kStale:
                return warn("audio block at sample " + std::to_string(msg.first_sample_index) +
                            " repeats or precedes what was analysed; dropped");
              case sound::AudioIntake::Verdict::kBridge:
                // A lost datagram or a few: go on, the time line advanced by the gap.
                stream->SkipSamples(decision.gap_samples);
                break;
              case sound::AudioIntake::Verdict::kRestart:
                if (warn_limit.Allow(common::SteadySeconds()))
                  SARMAP_LOG(WARN)
                      << "audio discontinuity of " << decision.gap_samples << " samples at sample "
                      << msg.first_sample_index << "; restarting the analysis";
                stream->ResetStream();
                break;
              default:
                break;
            }
            stream->Push(msg.samples.data(), msg.num_samples, msg.num_channels, msg.header.utime,
                         &doas, &map_doas);
            publish();
            node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " +
                                  std::to_string(dropped) + "; audio " + intake.Summary());
          });
    SARMAP_LOG(INFO) << "localising array '" << geometry.name << "' (" << geometry.num_mics()
                     << " mics, " << options.localiser.method << ") from " << options.audio_channel
                     << " -> " << options.doa_channel
                     << (stream->has_map_stream()
                             ? " and " + options.map_doa_channel + " (map_localiser)"
                             : "");
    return node.Run();
  });
}
