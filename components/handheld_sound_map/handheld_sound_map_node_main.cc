// sarmap-handheld-sound-map: the hand-held rig's sound map (HandheldSoundMapNode,
// handheld_sound_map_node.h).
#include "common/node_runner.h"
#include "handheld_sound_map/handheld_sound_map_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<sound_map::HandheldSoundMapNode, sound_map::HandheldSoundMapOptions>(
      {"sarmap-handheld-sound-map",
       "Maps stationary sound sources heard by a linear microphone array (a Kinect's) on a\n"
       "hand-held RGB-D rig (Su 2017 ch. 5): each new source starts as N_h hypotheses on the\n"
       "cone of its first DOA, pruned by chi-square and converged by linearity index; converged\n"
       "sources are refined jointly with the last keyframe poses of the rig's odometry.",
       "Channels in: RIG_POSE (sarmap-rgbd-odometry), DOA_MAP (sarmap-sound-localisation with a\n"
       "linear array), PEOPLE_AUDIO. Out: SOUND_MAP, positions in the odometry's frame (the rig "
       "at\n"
       "its first frame) as corrected by the joint optimisation.",
       "config/handheld_sound_map.yaml"},
      argc, argv);
}
