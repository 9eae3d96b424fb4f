// sarmap-sound-localisation: the sound localisation node (SoundLocalisationNode,
// sound_localisation_node.h).
#include "common/node_runner.h"
#include "sound_localisation/sound_localisation_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<sound::SoundLocalisationNode, sound::SoundLocalisationOptions>(
      {"sarmap-sound-localisation",
       "Directions of arrival (SRP-PHAT, MUSIC, GEVD-MUSIC, GCC-PHAT, ESPRIT) with tracking.",
       "Channels: in AUDIO (audio_frame_t), out DOA (doa_t), NODE_STATUS.",
       "config/sound_localisation.yaml"},
      argc, argv);
}
