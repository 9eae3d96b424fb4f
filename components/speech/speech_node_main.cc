// sarmap-speech: the speech node (SpeechNode, speech_node.h).
#include "common/node_runner.h"
#include "speech/speech_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<speech::SpeechNode, speech::SpeechNodeOptions>(
      {"sarmap-speech", "Enhances tracked talkers and spots keywords (help, rescue, assist, here).",
       "Channels: in AUDIO, DOA; out SPEECH, PEOPLE_AUDIO, NODE_STATUS.\n"
       "Full decoding on request: --set speech.keywords.full_decoding=true",
       "config/speech.yaml"},
      argc, argv);
}
