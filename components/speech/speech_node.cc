// sarmap-speech: AUDIO + DOA -> SPEECH (speech_event_t) and PEOPLE_AUDIO (people_detections_t):
// per tracked source an MVDR beam with post-filter, voice activity, PocketSphinx keywords.
#include <algorithm>
#include <cmath>

#include "common/args.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/speech_event_t.hpp"
#include "sound_localisation/audio_intake.h"
#include "sound_localisation/localiser.h"
#include "speech/speech_messages.h"
#include "speech/speech_stream.h"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-speech", [&]() {
    common::NodeArgs args;
    common::ArgParser p(
        "sarmap-speech",
        "Enhances tracked talkers and spots keywords (help, rescue, assist, here).");
    p.AddNodeOptions(&args, "config/speech.yaml");
    p.SetEpilog(
        "Channels: in AUDIO, DOA; out SPEECH, PEOPLE_AUDIO, NODE_STATUS.\n"
        "Full decoding on request: --set speech.keywords.full_decoding=true");
    if (!p.Parse(argc, argv)) return 0;
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options =
        common::LoadOptions<speech::SpeechNodeOptions>(args.config_path, args.overrides);
    if (args.print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    const auto array = common::LoadMicArray(options.array);
    std::unique_ptr<speech::SpeechStream> stream;
    try {
      stream = std::make_unique<speech::SpeechStream>(options, array);
    } catch (const std::invalid_argument& e) {
      throw common::OptionsError(e.what());
    } catch (const std::runtime_error& e) {
      throw common::OptionsError(e.what());
    }
    const sound::ArrayGeometry& geometry = stream->geometry();
    speech::SpeechProcessor* processor = &stream->processor();
    int needed = 0;
    for (int c : geometry.channel_map) needed = std::max(needed, c + 1);

    common::Node node("sarmap-speech", args);
    auto speech_pub = node.Advertise<sarmap::speech_event_t>(options.speech_channel);
    auto people_pub = node.Advertise<sarmap::people_detections_t>(options.people_channel);
    sound::AudioIntake intake(options.device_id, geometry.sample_rate_hz,
                              options.max_bridged_gap_s);
    std::string device = options.device_id;
    int64_t dropped = 0, events = 0, people = 0;
    common::RateLimiter warn_limit(5.0);
    auto warn = [&](const std::string& what) {
      ++dropped;
      if (warn_limit.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << what;
      }
    };
    std::vector<std::string> warnings;
    std::vector<sarmap::speech_event_t> event_msgs;
    std::vector<sarmap::people_detections_t> people_msgs;

    node.Subscribe<sarmap::doa_t>(options.doa_channel,
                                  [&](const sarmap::doa_t& msg, const common::ReceiveInfo&) {
                                    warnings.clear();
                                    stream->OnDoa(msg, device, &warnings);
                                    for (const auto& w : warnings) warn(w);
                                  });

    node.Subscribe<sarmap::audio_frame_t>(
        options.audio_channel, [&](const sarmap::audio_frame_t& msg, const common::ReceiveInfo&) {
          if (!intake.FromDeviceLogged(msg.device_id)) {
            ++dropped;
            node.SetStatusMessage("dropped " + std::to_string(dropped) + "; audio " +
                                  intake.Summary());
            return;
          }
          device = intake.device();
          if (msg.sample_rate_hz != geometry.sample_rate_hz)
            return warn("sample-rate mismatch: audio " + std::to_string(msg.sample_rate_hz) +
                        " Hz, array " + std::to_string(geometry.sample_rate_hz) + " Hz; dropped");
          if (msg.num_channels < needed)
            return warn("audio has " + std::to_string(msg.num_channels) +
                        " channels, array needs " + std::to_string(needed));
          if (msg.num_values != static_cast<int32_t>(msg.num_channels) * msg.num_samples)
            return warn("malformed audio block; dropped");
          // The beams and keyword spotting go on across gaps (each block's stamp anchors its
          // samples); a repeated or late block is dropped.
          const sound::AudioIntake::Decision decision =
              intake.Sequence(msg.first_sample_index, msg.num_samples);
          if (decision.verdict == sound::AudioIntake::Verdict::kStale)
            return warn("audio block at sample " + std::to_string(msg.first_sample_index) +
                        " repeats or precedes what was processed; dropped");
          if (decision.verdict == sound::AudioIntake::Verdict::kRestart &&
              warn_limit.Allow(common::SteadySeconds()))
            SARMAP_LOG(WARN) << "audio discontinuity of " << decision.gap_samples << " samples";
          event_msgs.clear();
          people_msgs.clear();
          stream->OnAudio(msg.samples.data(), msg.num_samples, msg.num_channels, msg.header.utime,
                          device, &event_msgs, &people_msgs);
          for (const auto& r : stream->last_results()) {
            SARMAP_LOG(INFO) << "heard" << (r.keyword.empty() ? "" : " keyword '" + r.keyword + "'")
                             << (r.text.empty() ? "" : " \"" + r.text + "\"") << " track "
                             << r.track_id << " conf " << r.confidence;
          }
          for (auto& e : event_msgs) speech_pub.Publish(&e);
          for (auto& d : people_msgs) people_pub.Publish(&d);
          events += static_cast<int64_t>(event_msgs.size());
          people += static_cast<int64_t>(people_msgs.size());
          node.SetStatusMessage(
              "utterances " + std::to_string(processor->utterances()) + ", events " +
              std::to_string(events) + ", people " + std::to_string(people) + ", dropped " +
              std::to_string(dropped) + ", leaked hits " +
              std::to_string(processor->leaked_hits_dropped()) + ", re-attributed " +
              std::to_string(processor->hits_reattributed()) + ", tracks " +
              std::to_string(processor->num_tracks()) + " (evicted " +
              std::to_string(processor->tracks_evicted()) + "); audio " + intake.Summary());
        });
    SARMAP_LOG(INFO) << "listening to array '" << geometry.name << "' on " << options.audio_channel
                     << " + " << options.doa_channel;
    return node.Run();
  });
}
