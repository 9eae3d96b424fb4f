// sarmap-speech: AUDIO + DOA -> SPEECH (speech_event_t) and PEOPLE_AUDIO (people_detections_t):
// per tracked source an MVDR beam with post-filter, voice activity, PocketSphinx keywords.
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
#include "sound_localisation/localiser.h"
#include "speech/speech_processor.h"

using namespace sarmap;

struct SpeechNodeOptions {
  std::string audio_channel = "AUDIO";
  std::string doa_channel = "DOA";
  std::string speech_channel = "SPEECH";
  std::string people_channel = "PEOPLE_AUDIO";
  std::string array = "config/arrays/respeaker4.yaml";
  std::string device_id = "";
  std::string search = "auto";  // must match the localiser's (1d for linear arrays)
  speech::SpeechOptions speech;
  template <class V>
  void Visit(V& v) {
    v("audio_channel", audio_channel, "input audio_frame_t");
    v("doa_channel", doa_channel, "input doa_t (tracked directions)");
    v("speech_channel", speech_channel, "output speech_event_t");
    v("people_channel", people_channel, "output people_detections_t (CUE_HEARD)");
    v("array", array, "array description (config/arrays/<name>.yaml)");
    v("device_id", device_id, "only this device ('' = the first heard)");
    v("search", search, "direction kind of the DOA input: auto, 1d, azimuth, azimuth_elevation");
    v("speech", speech, "enhancement, VAD and keyword spotting");
  }
  void Validate(common::Validator&) const {}
};

int main(int argc, char** argv) {
  return common::RunMain("sarmap-speech", [&]() {
    common::NodeArgs args;
    common::ArgParser p("sarmap-speech", "Enhances tracked talkers and spots keywords (help, rescue, assist, here).");
    p.AddNodeOptions(&args, "config/speech.yaml");
    p.SetEpilog("Channels: in AUDIO, DOA; out SPEECH, PEOPLE_AUDIO, NODE_STATUS.\n"
                "Full decoding on request: --set speech.keywords.full_decoding=true");
    if (!p.Parse(argc, argv)) return 0;
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options = common::LoadOptions<SpeechNodeOptions>(args.config_path, args.overrides);
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
    std::string device = options.device_id;
    // Anchor between stream samples and utime (from the latest audio block).
    int64_t anchor_sample = -1, anchor_utime = 0, expected_index = -1, dropped = 0, events = 0, people = 0;
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
      const int64_t sample = anchor_sample + static_cast<int64_t>(std::llround((msg.header.utime - anchor_utime) * 1e-6 * rate));
      for (const auto& s : msg.sources) {
        if (s.track_id < 0) continue;
        if (s.kind != static_cast<int8_t>(kind)) {
          warn("DOA kind " + std::to_string(s.kind) + " does not match this node's search (" + options.search + ")");
          continue;
        }
        Eigen::Matrix2d cov;
        cov << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
        processor->UpdateTrack(s.track_id, {s.azimuth_rad, s.elevation_rad}, cov, sample);
      }
    });

    node.Subscribe<sarmap::audio_frame_t>(options.audio_channel, [&](const sarmap::audio_frame_t& msg,
                                                                      const common::ReceiveInfo&) {
      if (device.empty()) device = msg.device_id;
      if (msg.device_id != device) return warn("audio from '" + msg.device_id + "' ignored (this node: '" + device + "')");
      if (msg.sample_rate_hz != geometry.sample_rate_hz)
        return warn("sample-rate mismatch: audio " + std::to_string(msg.sample_rate_hz) + " Hz, array " +
                    std::to_string(geometry.sample_rate_hz) + " Hz; dropped");
      if (msg.num_channels < needed)
        return warn("audio has " + std::to_string(msg.num_channels) + " channels, array needs " + std::to_string(needed));
      if (msg.num_values != static_cast<int32_t>(msg.num_channels) * msg.num_samples)
        return warn("malformed audio block; dropped");
      if (expected_index >= 0 && msg.first_sample_index != expected_index) {
        SARMAP_LOG(WARN) << "audio gap of " << (msg.first_sample_index - expected_index) << " samples";
      }
      expected_index = msg.first_sample_index + msg.num_samples;
      anchor_sample = processor->samples_seen();
      anchor_utime = msg.header.utime;
      results.clear();
      processor->Push(msg.samples.data(), msg.num_samples, msg.num_channels, &results);
      for (const auto& r : results) {
        sarmap::speech_event_t e;
        e.header.utime = to_utime(r.start_sample);
        e.header.frame = "mic_array";
        e.track_id = r.track_id;
        e.text = r.text;
        e.keyword = r.keyword;
        e.confidence = static_cast<float>(r.confidence);
        e.azimuth_rad = r.has_direction ? r.direction.azimuth_rad : NAN;
        e.elevation_rad = r.has_direction ? r.direction.elevation_rad : NAN;
        e.start_utime = to_utime(r.start_sample);
        e.end_utime = to_utime(r.end_sample);
        e.is_final = true;
        speech_pub.Publish(&e);
        ++events;
        SARMAP_LOG(INFO) << "heard" << (r.keyword.empty() ? "" : " keyword '" + r.keyword + "'")
                         << (r.text.empty() ? "" : " \"" + r.text + "\"") << " track " << r.track_id << " conf "
                         << r.confidence;
        if (r.keyword.empty() || !r.has_direction) continue;
        sarmap::people_detections_t d;
        d.header.utime = e.end_utime;
        d.header.frame = "mic_array";
        d.sensor_id = device;
        sarmap::person_detection_t person{};
        person.track_id = r.track_id;
        person.cue = sarmap::person_detection_t::CUE_HEARD;
        person.has_range = false;
        for (double& v : person.position_m) v = 0;
        for (double& v : person.position_covariance) v = 0;
        person.azimuth_rad = r.direction.azimuth_rad;
        person.elevation_rad = r.direction.elevation_rad;
        for (int i = 0; i < 4; ++i) person.direction_covariance[i] = r.covariance(i / 2, i % 2);
        person.height_m = 0;
        person.confidence = static_cast<float>(r.confidence);
        person.keyword = r.keyword;
        d.detections.push_back(person);
        d.num_detections = 1;
        people_pub.Publish(&d);
        ++people;
      }
      node.SetStatusMessage("utterances " + std::to_string(processor->utterances()) + ", events " +
                            std::to_string(events) + ", people " + std::to_string(people) + ", dropped " +
                            std::to_string(dropped) + ", leaked hits " +
                            std::to_string(processor->leaked_hits_dropped()));
    });
    SARMAP_LOG(INFO) << "listening to array '" << geometry.name << "' on " << options.audio_channel << " + "
                     << options.doa_channel;
    return node.Run();
  });
}
