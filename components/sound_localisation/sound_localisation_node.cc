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
#include "sound_localisation/localiser.h"
#include "sound_localisation/source_class.h"

using namespace sarmap;

struct SoundLocalisationOptions {
  std::string audio_channel = "AUDIO";
  std::string doa_channel = "DOA";
  std::string array = "config/arrays/respeaker4.yaml";
  std::string device_id = "";      // accept only this device ("" = the first one heard)
  // Longest run of lost samples (dropped datagrams) bridged without restarting the analysis.
  double max_bridged_gap_s = 0.25;
  bool publish_untracked = true;   // also publish directions not (yet) in a confirmed track
  // Asynchronous array (several cards, each its own process on AUDIO_<DEVICE>): the device of
  // each microphone; channel_map then gives the channel within that device. The streams are
  // aligned by sample counter, start_offsets_s and clock_drift of the array file before DOA.
  std::vector<std::string> devices;       // device ids, e.g. [card0, card1]
  std::vector<int> mic_devices;           // per microphone: index into devices
  std::vector<std::string> audio_channels;  // extra input channels (AUDIO_<DEVICE>)
  sound::LocaliserOptions localiser;
  // A second DOA stream for the sound map, from its own localiser over the same audio (e.g.
  // precedence-effect onset bins, which place a talker near a wall better but give sparser
  // tracks than sarmap-speech's beams want). Empty: none.
  std::string map_doa_channel = "";
  sound::LocaliserOptions map_localiser;
  // What each direction's source is (doa_source_t sound_class), from its own time-frequency bins.
  bool classify = true;
  sound::SourceClassOptions classes;
  template <class V>
  void Visit(V& v) {
    v("audio_channel", audio_channel, "input audio_frame_t channel");
    v("doa_channel", doa_channel, "output doa_t channel");
    v("array", array, "array description (config/arrays/<name>.yaml)");
    v("device_id", device_id,
      "only use this device ('' = the first one heard); others are dropped and reported");
    v("max_bridged_gap_s", max_bridged_gap_s,
      "a gap in the audio up to this long is bridged (analysis goes on); longer ones restart it");
    v("publish_untracked", publish_untracked, "publish directions outside confirmed tracks with track_id -1");
    v("devices", devices, "asynchronous array: device ids of its cards ([] = one device)");
    v("mic_devices", mic_devices, "asynchronous array: index into devices of each microphone");
    v("audio_channels", audio_channels, "further input channels (one per card, AUDIO_<DEVICE>)");
    v("localiser", localiser, "DOA estimation and tracking");
    v("map_doa_channel", map_doa_channel, "second doa_t stream for the sound map, from map_localiser ('' = none)");
    v("map_localiser", map_localiser, "DOA estimation and tracking of the map_doa_channel stream");
    v("classify", classify, "tell each direction's source class (voice, alarm, machinery, music)");
    v("classes", classes, "source classification");
  }
  void Validate(common::Validator& check) const {
    check.NonNegative("max_bridged_gap_s", max_bridged_gap_s);
    for (int d : mic_devices)
      check.That(d >= 0 && d < static_cast<int>(devices.size()), "mic_devices", "indices must point into devices");
    check.That(devices.empty() || !mic_devices.empty(), "mic_devices", "needed with devices");
  }
};

int8_t MethodCode(const std::string& m) {
  if (m == "gcc_phat") return doa_source_t::METHOD_GCC_PHAT;
  if (m == "music") return doa_source_t::METHOD_MUSIC;
  if (m == "gevd_music") return doa_source_t::METHOD_GEVD_MUSIC;
  if (m == "esprit") return doa_source_t::METHOD_ESPRIT;
  return doa_source_t::METHOD_SRP_PHAT;
}

int main(int argc, char** argv) {
  return common::RunMain("sarmap-sound-localisation", [&]() {
    common::NodeArgs args;
    common::ArgParser p("sarmap-sound-localisation",
                        "Directions of arrival (SRP-PHAT, MUSIC, GEVD-MUSIC, GCC-PHAT, ESPRIT) with tracking.");
    p.AddNodeOptions(&args, "config/sound_localisation.yaml");
    p.SetEpilog("Channels: in AUDIO (audio_frame_t), out DOA (doa_t), NODE_STATUS.");
    if (!p.Parse(argc, argv)) return 0;
    common::SetLogLevel(common::ParseLogLevel(args.log_level));
    const auto options = common::LoadOptions<SoundLocalisationOptions>(args.config_path, args.overrides);
    if (args.print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    const auto array = common::LoadMicArray(options.array);
    const std::string array_dir = options.array.substr(0, options.array.find_last_of('/') + 1);
    sound::ArrayGeometry geometry;
    std::unique_ptr<sound::Localiser> localiser, map_localiser;
    std::unique_ptr<sound::DirectionalClassifier> classifier;
    try {
      geometry = sound::ArrayGeometry::FromOptions(array);
      localiser = std::make_unique<sound::Localiser>(geometry, options.localiser,
                                                     sound::SensorModel::FromArray(array, array_dir));
      if (!options.map_doa_channel.empty())
        map_localiser = std::make_unique<sound::Localiser>(geometry, options.map_localiser,
                                                           sound::SensorModel::FromArray(array, array_dir));
      if (options.classify)
        classifier = std::make_unique<sound::DirectionalClassifier>(geometry, localiser->kind(),
                                                                    options.classes);
    } catch (const std::invalid_argument& e) {
      throw common::OptionsError(e.what());
    }
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
        aligner = std::make_unique<sound::AsyncStreamAligner>(geometry.sample_rate_hz, array.start_offsets_s,
                                                              array.clock_drift, geometry.num_mics());
      } catch (const std::invalid_argument& e) {
        throw common::OptionsError(e.what());
      }
      for (int m = 0; m < geometry.num_mics(); ++m)
        needed_per_device[options.mic_devices[m]] =
            std::max(needed_per_device[options.mic_devices[m]], geometry.channel_map[m] + 1);
    }

    common::Node node("sarmap-sound-localisation", args.lcm_url);
    auto pub = node.Advertise<sarmap::doa_t>(options.doa_channel);
    std::vector<common::Node::Publisher<sarmap::doa_t>> map_pub;
    if (map_localiser) map_pub.push_back(node.Advertise<sarmap::doa_t>(options.map_doa_channel));
    sound::AudioIntake intake(options.device_id, geometry.sample_rate_hz,
                              options.max_bridged_gap_s);
    std::string device = options.device_id;
    int64_t last_overrun = 0, dropped = 0, published = 0;
    common::RateLimiter warn_limit(5.0);
    const int8_t kind = static_cast<int8_t>(localiser->kind());
    std::vector<sound::LocaliserOutput> outs, map_outs;

    auto warn = [&](const std::string& what) {
      ++dropped;
      long suppressed = 0;
      if (warn_limit.Allow(common::SteadySeconds(), &suppressed)) {
        SARMAP_LOG(WARN) << what << (suppressed ? " (" + std::to_string(suppressed) + " similar suppressed)" : "");
      }
    };

    // Publishes the outputs; utime of stream sample s = base_utime + (s - base_sample) / rate.
    auto publish_stream = [&](const std::vector<sound::LocaliserOutput>& stream, const sound::LocaliserOptions& lo,
                              common::Node::Publisher<sarmap::doa_t>* to, int64_t base_utime, int64_t base_sample) {
      const int8_t method = MethodCode(lo.method);
      for (const auto& o : stream) {
        sarmap::doa_t doa;
        doa.header.utime = base_utime + common::SecondsToUtime(static_cast<double>(o.centre_sample - base_sample) /
                                                               geometry.sample_rate_hz);
        doa.header.frame = "mic_array";
        doa.device_id = device;
        struct Entry {
          int64_t id;
          const sound::Direction* direction;
          const Eigen::Matrix2d* covariance;
          double power, confidence;
        };
        std::vector<Entry> entries;
        for (const auto& t : o.tracks)
          if (t.updated)
            entries.push_back({t.id, &t.direction, &t.covariance, t.power, t.confidence});
        if (options.publish_untracked)
          for (const auto& d : o.directions) {
            bool in_track = false;
            for (const auto& t : o.tracks)
              in_track |= t.updated && sound::AngularDistanceRad(geometry, localiser->kind(), t.direction, d.direction) <
                                           sound::DegToRad(lo.tracker.gate_deg);
            if (!in_track)
              entries.push_back({-1, &d.direction, &d.covariance, d.power, d.confidence});
          }
        std::vector<sound::SoundClassEstimate> classes(entries.size());
        if (classifier && !entries.empty()) {
          std::vector<sound::Direction> directions;
          for (const auto& e : entries) directions.push_back(*e.direction);
          const int64_t block =
              static_cast<int64_t>(std::llround(lo.block_s * geometry.sample_rate_hz));
          // The stream the sound map reads marks the class tracks; the other one (the speech
          // beams' DOA) only reads them: its reports of one source near another's direction
          // marked the other's frames as sounding (lab tour: the smoke alarm mapped as a voice).
          const bool marks = map_localiser ? &lo == &options.map_localiser : true;
          classes = marks ? classifier->Observe(o.end_sample - block, o.end_sample, directions)
                          : classifier->Lookup(directions);
        }
        for (size_t i = 0; i < entries.size(); ++i) {
          const Entry& e = entries[i];
          sarmap::doa_source_t s{};
          s.track_id = e.id;
          s.kind = kind;
          s.azimuth_rad = e.direction->azimuth_rad;
          s.elevation_rad = e.direction->elevation_rad;
          for (int j = 0; j < 4; ++j) s.covariance[j] = (*e.covariance)(j / 2, j % 2);
          s.power = static_cast<float>(e.power);
          s.confidence = static_cast<float>(e.confidence);
          s.method = method;
          s.sound_class = static_cast<int8_t>(classes[i].sound_class);
          s.class_confidence = static_cast<float>(classes[i].confidence);
          doa.sources.push_back(s);
        }
        doa.num_sources = static_cast<int32_t>(doa.sources.size());
        to->Publish(&doa);
        ++published;
      }
    };
    auto publish = [&](int64_t base_utime, int64_t base_sample) {
      publish_stream(outs, options.localiser, &pub, base_utime, base_sample);
      if (map_localiser) publish_stream(map_outs, options.map_localiser, &map_pub[0], base_utime, base_sample);
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
        return warn("audio from device '" + msg.device_id + "' ignored: not one of this array's devices");
      const int d = static_cast<int>(it - options.devices.begin());
      if (msg.sample_rate_hz != geometry.sample_rate_hz)
        return warn("sample-rate mismatch: device '" + msg.device_id + "' is " + std::to_string(msg.sample_rate_hz) +
                    " Hz, array '" + geometry.name + "' expects " + std::to_string(geometry.sample_rate_hz) +
                    " Hz; block dropped");
      if (msg.num_channels < needed_per_device[d])
        return warn("device '" + msg.device_id + "' has " + std::to_string(msg.num_channels) + " channels, needs " +
                    std::to_string(needed_per_device[d]) + "; block dropped");
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
      const int64_t before = localiser->samples_seen();
      outs.clear();
      localiser->PushFloat(aligned, 0, n, &outs);
      if (map_localiser) {
        map_outs.clear();
        map_localiser->PushFloat(aligned, 0, n, &map_outs);
      }
      if (classifier) classifier->PushFloat(aligned, 0, n);
      // Stream sample `before` is reference sample `first`.
      publish(ref_utime, before + (ref_first - first));
      node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " + std::to_string(dropped) +
                            ", samples lost " + std::to_string(aligner->dropped_samples()));
    };
    if (asynchronous) {
      device.clear();
      for (const auto& d : options.devices) device += (device.empty() ? "" : "+") + d;
      std::vector<std::string> channels = options.audio_channels;
      if (channels.empty()) channels.push_back(options.audio_channel);
      for (const auto& ch : channels)
        node.Subscribe<sarmap::audio_frame_t>(ch, [&](const sarmap::audio_frame_t& msg, const common::ReceiveInfo&) {
          on_async(msg);
        });
    } else
      node.Subscribe<sarmap::audio_frame_t>(
          options.audio_channel, [&](const sarmap::audio_frame_t& msg, const common::ReceiveInfo&) {
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
              node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " +
                                    std::to_string(dropped) + "; audio " + intake.Summary());
              return;
            }
            device = intake.device();
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
                localiser->SkipSamples(decision.gap_samples);
                if (map_localiser) map_localiser->SkipSamples(decision.gap_samples);
                if (classifier) classifier->SkipSamples(decision.gap_samples);
                break;
              case sound::AudioIntake::Verdict::kRestart:
                if (warn_limit.Allow(common::SteadySeconds()))
                  SARMAP_LOG(WARN)
                      << "audio discontinuity of " << decision.gap_samples << " samples at sample "
                      << msg.first_sample_index << "; restarting the analysis";
                localiser->ResetStream();
                if (map_localiser) map_localiser->ResetStream();
                if (classifier) classifier->ResetStream();
                break;
              default:
                break;
            }
            const int64_t before = localiser->samples_seen();
            outs.clear();
            localiser->Push(msg.samples.data(), msg.num_samples, msg.num_channels, &outs);
            if (map_localiser) {
              map_outs.clear();
              map_localiser->Push(msg.samples.data(), msg.num_samples, msg.num_channels, &map_outs);
            }
            if (classifier) classifier->Push(msg.samples.data(), msg.num_samples, msg.num_channels);
            publish(msg.header.utime, before);
            node.SetStatusMessage("doa " + std::to_string(published) + ", dropped audio blocks " +
                                  std::to_string(dropped) + "; audio " + intake.Summary());
          });
    SARMAP_LOG(INFO) << "localising array '" << geometry.name << "' (" << geometry.num_mics() << " mics, "
                     << options.localiser.method << ") from " << options.audio_channel << " -> " << options.doa_channel
                     << (map_localiser ? " and " + options.map_doa_channel + " (map_localiser)" : "");
    return node.Run();
  });
}
