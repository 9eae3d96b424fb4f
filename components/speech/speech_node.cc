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

using namespace sarmap;


int main(int argc, char** argv) {
  return common::RunMain("sarmap-speech", [&]() {
    common::NodeArgs args;
    common::ArgParser p("sarmap-speech", "Enhances tracked talkers and spots keywords (help, rescue, assist, here).");
    p.AddNodeOptions(&args, "config/speech.yaml");
    p.SetEpilog("Channels: in AUDIO, DOA; out SPEECH, PEOPLE_AUDIO, NODE_STATUS.\n"
                "Full decoding on request: --set speech.keywords.full_decoding=true");
    if (!p.Parse(argc, argv)) return 0;
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options = common::LoadOptions<speech::SpeechNodeOptions>(args.config_path, args.overrides);
    if (args.print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    const auto array = common::LoadMicArray(options.array);
    sound::ArrayGeometry geometry;
    sound::DoaKind kind;
    std::unique_ptr<speech::SpeechProcessor> processor;
    try {
      geometry = sound::ArrayGeometry::FromOptions(array);
      kind = sound::ResolveKind(geometry, options.search);
      processor = std::make_unique<speech::SpeechProcessor>(geometry, kind, options.speech);
    } catch (const std::invalid_argument& e) {
      throw common::OptionsError(e.what());
    } catch (const std::runtime_error& e) {
      throw common::OptionsError(e.what());
    }
    int needed = 0;
    for (int c : geometry.channel_map) needed = std::max(needed, c + 1);
    const double rate = geometry.sample_rate_hz;

    common::Node node("sarmap-speech", args.lcm_url);
    auto speech_pub = node.Advertise<sarmap::speech_event_t>(options.speech_channel);
    auto people_pub = node.Advertise<sarmap::people_detections_t>(options.people_channel);
    sound::AudioIntake intake(options.device_id, geometry.sample_rate_hz,
                              options.max_bridged_gap_s);
    std::string device = options.device_id;
    // Anchor between stream samples and utime (from the latest audio block).
    int64_t anchor_sample = -1, anchor_utime = 0, dropped = 0, events = 0, people = 0;
    common::RateLimiter warn_limit(5.0);
    auto warn = [&](const std::string& what) {
      ++dropped;
      if (warn_limit.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << what;
      }
    };
    auto to_utime = [&](int64_t sample) {
      return anchor_utime + common::SecondsToUtime((sample - anchor_sample) / rate);
    };
    std::vector<speech::SpeechResult> results;

    node.Subscribe<sarmap::doa_t>(options.doa_channel, [&](const sarmap::doa_t& msg, const common::ReceiveInfo&) {
      if (anchor_sample < 0 || (!device.empty() && msg.device_id != device)) return;
      // In double and clamped: a stamp near the int64 limits must not overflow (the processor
      // drops DOAs far ahead of the audio, and a track far behind times out).
      const double offset_samples = std::clamp(
          (static_cast<double>(msg.header.utime) - static_cast<double>(anchor_utime)) * 1e-6 * rate,
          -1e12, 1e12);
      const int64_t sample = anchor_sample + static_cast<int64_t>(std::llround(offset_samples));
      for (const auto& s : msg.sources) {
        if (s.track_id < 0) continue;
        if (s.kind != static_cast<int8_t>(kind)) {
          warn("DOA kind " + std::to_string(s.kind) + " does not match this node's search (" + options.search + ")");
          continue;
        }
        Eigen::Matrix2d cov;
        cov << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
        if (!processor->UpdateTrack(s.track_id, {s.azimuth_rad, s.elevation_rad}, cov, sample))
          warn("DOA stamped more than " + std::to_string(options.speech.max_doa_ahead_s) +
               " s ahead of the audio; dropped");
      }
    });

    node.Subscribe<sarmap::audio_frame_t>(options.audio_channel, [&](const sarmap::audio_frame_t&
                                                                         msg,
                                                                     const common::ReceiveInfo&) {
      std::string report;
      const bool ours = intake.FromDevice(msg.device_id, &report);
      if (!report.empty()) {
        if (ours)
          SARMAP_LOG(INFO) << common::EscapeForLog(report, 512);  // names devices heard
        else
          SARMAP_LOG(ERROR) << common::EscapeForLog(report, 512);
      }
      if (!ours) {
        ++dropped;
        node.SetStatusMessage("dropped " + std::to_string(dropped) + "; audio " + intake.Summary());
        return;
      }
      device = intake.device();
      if (msg.sample_rate_hz != geometry.sample_rate_hz)
        return warn("sample-rate mismatch: audio " + std::to_string(msg.sample_rate_hz) + " Hz, array " +
                    std::to_string(geometry.sample_rate_hz) + " Hz; dropped");
      if (msg.num_channels < needed)
        return warn("audio has " + std::to_string(msg.num_channels) + " channels, array needs " + std::to_string(needed));
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
      anchor_sample = processor->samples_seen();
      anchor_utime = msg.header.utime;
      results.clear();
      processor->Push(msg.samples.data(), msg.num_samples, msg.num_channels, &results);
      for (const auto& r : results) {
        sarmap::speech_event_t e = speech::ToSpeechEvent(r, to_utime(r.start_sample), to_utime(r.end_sample));
        speech_pub.Publish(&e);
        ++events;
        SARMAP_LOG(INFO) << "heard" << (r.keyword.empty() ? "" : " keyword '" + r.keyword + "'")
                         << (r.text.empty() ? "" : " \"" + r.text + "\"") << " track " << r.track_id << " conf "
                         << r.confidence;
        if (r.keyword.empty() || !r.has_direction) continue;
        sarmap::people_detections_t d = speech::ToPeopleAudio(r, device, e.end_utime);
        people_pub.Publish(&d);
        ++people;
      }
      node.SetStatusMessage("utterances " + std::to_string(processor->utterances()) + ", events " +
                            std::to_string(events) + ", people " + std::to_string(people) +
                            ", dropped " + std::to_string(dropped) + ", leaked hits " +
                            std::to_string(processor->leaked_hits_dropped()) + ", re-attributed " +
                            std::to_string(processor->hits_reattributed()) + ", tracks " +
                            std::to_string(processor->num_tracks()) + " (evicted " +
                            std::to_string(processor->tracks_evicted()) + "); audio " +
                            intake.Summary());
    });
    SARMAP_LOG(INFO) << "listening to array '" << geometry.name << "' on " << options.audio_channel << " + "
                     << options.doa_channel;
    return node.Run();
  });
}
