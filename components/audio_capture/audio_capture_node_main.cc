// sarmap-audio-capture: audio capture (AudioCaptureNode, audio_capture_node.h).
#include "audio_capture/audio_capture_node.h"
#include "common/node_runner.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<audio::AudioCaptureNode, audio::CaptureOptions>(
      {"sarmap-audio-capture",
       "Captures multichannel audio from an ALSA device or a file and publishes audio_frame_t.",
       "Channels out: AUDIO (or AUDIO_<DEVICE> with channel: AUDIO_*), NODE_STATUS.\n"
       "Example: sarmap-audio-capture --device hw:CARD=ArrayUAC10 --set num_channels=6 --set "
       "channel=AUDIO_*",
       "config/audio_capture.yaml",
       {{"--file", "play this file (sets source=file)", {"source=file", "file={}"}},
        {"--device", "capture this ALSA device (sets source=alsa)", {"source=alsa", "device={}"}},
        {"--speed", "file pacing (1 real time, 0 as fast as possible)", {"speed={}"}}}},
      argc, argv);
}
