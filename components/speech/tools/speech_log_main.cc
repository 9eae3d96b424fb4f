// sarmap-log-speech: runs sarmap-speech's adapter (SpeechNode) over a recorded log's AUDIO and
// DOA, on the log's clock (logtools::NodeReplay), and writes a copy of the log whose SPEECH and
// PEOPLE_AUDIO are the new ones: speech settings tried on a mission without running it again
// (then e.g. `sarmap-log sound-map OUT --heard-check`).
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/node.h"
#include "common/node_main.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/node_replay.h"
#include "speech/speech_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunMain("sarmap-log-speech", [&]() {
    common::ArgParser parser(
        "sarmap-log-speech",
        "Runs sarmap-speech over a log's AUDIO and DOA (the same adapter, on the log's clock) and "
        "writes a copy of\nthe log with the new SPEECH and PEOPLE_AUDIO (the old ones are left "
        "out). Options as sarmap-speech's (--config, --set).");
    std::string in_path, out_path;
    parser.AddPositional("log", &in_path, "LCM log file to read");
    parser.AddPositional("out", &out_path, "LCM log file to write");
    common::NodeArgs node_args;
    const auto parsed = common::ParseNodeOptions<speech::SpeechNodeOptions>(
        &parser, &node_args, argc, argv, "config/speech.yaml");
    if (!parsed) return 0;
    const speech::SpeechNodeOptions& options = *parsed;

    common::Node node("sarmap-log-speech", logtools::ReplayNodeArgs(node_args));
    speech::SpeechNode speech_node(options, &node);
    logtools::NodeReplay replay(&node);
    logtools::LcmLogWriter out(out_path);
    replay.Capture(options.speech_channel + "|" + options.people_channel,
                   [&](const std::string& channel, const std::vector<uint8_t>& data) {
                     out.WriteBytes(channel, data, replay.now_us());
                   });
    const auto stats = replay.Run(in_path, [&](logtools::LogEvent* e) {
      if (e->channel == options.speech_channel || e->channel == options.people_channel) {
        return false;  // replaced by the new ones
      }
      out.WriteBytes(e->channel, e->data, e->timestamp_us);
      return e->channel == options.audio_channel || e->channel == options.doa_channel;
    });
    speech_node.Finish();  // utterances still open, stamped at the last input's time
    replay.Drain();

    const speech::SpeechProcessor& processor = speech_node.stream().processor();
    for (const auto& problem : stats.problems) {
      std::fprintf(stderr, "%s: damaged at byte %lld (%s); read on from the next event\n",
                   in_path.c_str(), static_cast<long long>(problem.file_offset),
                   problem.what.c_str());
    }
    std::printf(
        "%.1f s of audio (%lld inputs dropped): %lld SPEECH, %lld PEOPLE_AUDIO; %lld keyword "
        "hits re-attributed to another track, %lld dropped as another beam's leak -> %s\n",
        static_cast<double>(processor.samples_seen()) /
            speech_node.stream().geometry().sample_rate_hz,
        static_cast<long long>(speech_node.dropped()), static_cast<long long>(speech_node.events()),
        static_cast<long long>(speech_node.people()),
        static_cast<long long>(processor.hits_reattributed()),
        static_cast<long long>(processor.leaked_hits_dropped()), out_path.c_str());
    return 0;
  });
}
