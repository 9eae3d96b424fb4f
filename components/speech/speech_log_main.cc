// sarmap-log-speech: re-runs sarmap-speech over a recorded log (its AUDIO and DOA, in log order)
// and writes a copy of the log whose SPEECH and PEOPLE_AUDIO are the new ones, to try speech
// settings on a mission without running it again (then e.g. `sarmap-log sound-map OUT
// --heard-check`).
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <stdexcept>

#include "common/args.h"
#include "common/decode.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"
#include "sound_localisation/localiser.h"
#include "speech/speech_messages.h"

namespace {

template <class T>
bool Decode(const lcm::LogEvent& e, T* msg) {
  return e.datalen >= 0 &&
         sarmap::common::DecodeMessage(e.data, static_cast<size_t>(e.datalen), msg);
}

template <class T>
void Write(lcm::LogFile* out, int64_t timestamp, const std::string& channel, T& msg) {
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  lcm::LogEvent e;
  e.eventnum = 0;
  e.timestamp = timestamp;
  e.channel = channel;
  e.datalen = static_cast<int32_t>(buffer.size());
  e.data = buffer.data();
  if (out->writeEvent(&e) != 0) throw std::runtime_error("error writing the output log");
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-speech", [&]() {
    sarmap::common::ArgParser parser(
        "sarmap-log-speech",
        "Re-runs sarmap-speech over a log's AUDIO and DOA and writes a copy of the log with the "
        "new SPEECH and\n"
        "PEOPLE_AUDIO (the old ones are left out). Options as sarmap-speech's (--config, --set).");
    std::string in_path, out_path;
    parser.AddPositional("log", &in_path, "LCM log file to read");
    parser.AddPositional("out", &out_path, "LCM log file to write");
    sarmap::common::NodeArgs node_args;
    const auto parsed = sarmap::common::ParseNodeOptions<sarmap::speech::SpeechNodeOptions>(
        &parser, &node_args, argc, argv, "config/speech.yaml");
    if (!parsed) return 0;
    const auto& options = *parsed;
    const auto array = sarmap::common::LoadMicArray(options.array);
    sarmap::sound::ArrayGeometry geometry;
    sarmap::sound::DoaKind kind;
    std::unique_ptr<sarmap::speech::SpeechProcessor> processor;
    try {
      geometry = sarmap::sound::ArrayGeometry::FromOptions(array);
      kind = sarmap::sound::ResolveKind(geometry, options.search);
      processor = std::make_unique<sarmap::speech::SpeechProcessor>(geometry, kind, options.speech);
    } catch (const std::exception& e) {
      throw sarmap::common::OptionsError(e.what());
    }
    int needed = 0;
    for (int c : geometry.channel_map) needed = std::max(needed, c + 1);
    const double rate = geometry.sample_rate_hz;

    lcm::LogFile in(in_path, "r");
    if (!in.good()) throw std::runtime_error("cannot read log " + in_path);
    lcm::LogFile out(out_path, "w");
    if (!out.good()) throw std::runtime_error("cannot write log " + out_path);
    std::string device = options.device_id;
    int64_t anchor_sample = -1, anchor_utime = 0, blocks = 0, events = 0, people = 0, skipped = 0;
    auto to_utime = [&](int64_t sample) {
      return anchor_utime +
             static_cast<int64_t>(std::llround((sample - anchor_sample) / rate * 1e6));
    };
    std::vector<sarmap::speech::SpeechResult> results;
    for (const lcm::LogEvent* e = in.readNextEvent(); e; e = in.readNextEvent()) {
      if (e->channel == options.speech_channel || e->channel == options.people_channel) continue;
      if (out.writeEvent(const_cast<lcm::LogEvent*>(e)) != 0)
        throw std::runtime_error("error writing " + out_path);
      if (e->channel == options.doa_channel) {
        sarmap::doa_t msg;
        if (!Decode(*e, &msg) || anchor_sample < 0 || (!device.empty() && msg.device_id != device))
          continue;
        const int64_t sample =
            anchor_sample + std::llround((msg.header.utime - anchor_utime) * 1e-6 * rate);
        for (const auto& s : msg.sources) {
          if (s.track_id < 0 || s.kind != static_cast<int8_t>(kind)) continue;
          Eigen::Matrix2d cov;
          cov << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
          processor->UpdateTrack(s.track_id, {s.azimuth_rad, s.elevation_rad}, cov, sample);
        }
      } else if (e->channel == options.audio_channel) {
        sarmap::audio_frame_t msg;
        if (!Decode(*e, &msg)) continue;
        if (device.empty()) device = msg.device_id;
        if (msg.device_id != device || msg.sample_rate_hz != geometry.sample_rate_hz ||
            msg.num_channels < needed ||
            msg.num_values != static_cast<int32_t>(msg.num_channels) * msg.num_samples) {
          ++skipped;
          continue;
        }
        anchor_sample = processor->samples_seen();
        anchor_utime = msg.header.utime;
        results.clear();
        processor->Push(msg.samples.data(), msg.num_samples, msg.num_channels, &results);
        for (const auto& r : results) {
          auto event =
              sarmap::speech::ToSpeechEvent(r, to_utime(r.start_sample), to_utime(r.end_sample));
          Write(&out, e->timestamp, options.speech_channel, event);
          ++events;
          if (r.keyword.empty() || !r.has_direction) continue;
          auto heard = sarmap::speech::ToPeopleAudio(r, device, event.end_utime);
          Write(&out, e->timestamp, options.people_channel, heard);
          ++people;
        }
        if (++blocks % 2000 == 0)
          std::fprintf(stderr, "  %.0f s of audio ...\n", processor->samples_seen() / rate);
      }
    }
    results.clear();
    processor->Flush(&results);
    for (const auto& r :
         results) {  // utterances still open at the end: stamped after the last block
      auto event =
          sarmap::speech::ToSpeechEvent(r, to_utime(r.start_sample), to_utime(r.end_sample));
      Write(&out, anchor_utime, options.speech_channel, event);
      ++events;
    }
    std::printf(
        "%.1f s of audio from '%s' (%ld blocks skipped): %ld SPEECH, %ld PEOPLE_AUDIO; %ld keyword "
        "hits "
        "re-attributed to another track, %ld dropped as another beam's leak -> %s\n",
        processor->samples_seen() / rate, device.c_str(), static_cast<long>(skipped),
        static_cast<long>(events), static_cast<long>(people),
        static_cast<long>(processor->hits_reattributed()),
        static_cast<long>(processor->leaked_hits_dropped()), out_path.c_str());
    return 0;
  });
}
