// sarmap-audio-capture: an ALSA device or a multichannel audio file -> audio_frame_t on AUDIO
// (or AUDIO_<DEVICE>). One process per sound card: each has its own clock and sample counter.
#include <cmath>

#include "audio_capture/audio_source.h"
#include "common/args.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "sarmap/audio_frame_t.hpp"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-audio-capture", [&]() {
    common::NodeArgs args;
    std::string file, device;
    double speed = -1;
    common::ArgParser p("sarmap-audio-capture",
                        "Captures multichannel audio from an ALSA device or a file and publishes audio_frame_t.");
    p.AddNodeOptions(&args, "config/audio_capture.yaml");
    p.AddFlag("--file", &file, "play this file (sets source=file)");
    p.AddFlag("--device", &device, "capture this ALSA device (sets source=alsa)");
    p.AddFlag("--speed", &speed, "file pacing (1 real time, 0 as fast as possible)");
    p.SetEpilog("Channels out: AUDIO (or AUDIO_<DEVICE> with channel: AUDIO_*), NODE_STATUS.\n"
                "Example: sarmap-audio-capture --device hw:CARD=ArrayUAC10 --set num_channels=6 --set channel=AUDIO_*");
    if (!p.Parse(argc, argv)) return 0;
    std::vector<std::string> overrides = args.overrides;
    if (!file.empty()) {
      overrides.push_back("source=file");
      overrides.push_back("file=" + file);
    }
    if (!device.empty()) {
      overrides.push_back("source=alsa");
      overrides.push_back("device=" + device);
    }
    if (speed >= 0) overrides.push_back("speed=" + std::to_string(speed));
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options = common::LoadOptions<audio::CaptureOptions>(args.config_path, overrides);
    if (args.print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    std::unique_ptr<audio::AudioSource> source;
    try {
      source = audio::OpenAudioSource(options);
    } catch (const audio::AudioSourceError& e) {
      throw common::OptionsError(e.what());  // one clear line, exit code 2
    }
    const std::string channel = audio::OutputChannel(options.channel, source->device_id());
    common::Node node("sarmap-audio-capture", args);
    auto pub = node.Advertise<sarmap::audio_frame_t>(channel);
    audio::SignalChecker checker(options, source->sample_rate_hz(), source->num_channels());
    const int frames = std::max(1, static_cast<int>(std::lround(options.block_s * source->sample_rate_hz())));
    SARMAP_LOG(INFO) << "capturing '" << source->device_id() << "' (" << source->num_channels() << " ch, "
                     << source->sample_rate_hz() << " Hz) -> " << channel;
    audio::AudioBlock block;
    int64_t published = 0, last_overrun = 0;
    while (node.SpinOnce(0)) {
      if (!source->Read(frames, &block)) break;
      for (const auto& w : checker.Check(block)) SARMAP_LOG(WARN) << source->device_id() << ": " << w;
      if (block.overrun_samples != last_overrun) {
        SARMAP_LOG(WARN) << source->device_id() << ": " << (block.overrun_samples - last_overrun)
                         << " samples lost before sample " << block.first_sample_index;
        last_overrun = block.overrun_samples;
      }
      sarmap::audio_frame_t msg;
      msg.header.utime = block.utime;
      msg.header.frame = "mic_array";
      msg.device_id = source->device_id();
      msg.sample_rate_hz = source->sample_rate_hz();
      msg.num_channels = static_cast<int16_t>(block.num_channels);
      msg.num_samples = block.num_frames;
      msg.first_sample_index = block.first_sample_index;
      msg.overrun_samples = block.overrun_samples;
      msg.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
      msg.num_values = static_cast<int32_t>(block.samples.size());
      msg.samples = block.samples;
      pub.Publish(&msg);
      ++published;
      node.SetStatusMessage("blocks " + std::to_string(published) + ", lost samples " +
                            std::to_string(block.overrun_samples) + ", clipped samples " +
                            std::to_string(checker.clipped_samples()));
    }
    SARMAP_LOG(INFO) << "end of stream after " << published << " blocks";
    return 0;
  });
}
