// sarmap-sound-map: the robot's sound map node (SoundMapNode, sound_map_node.h).
#include "common/node_runner.h"
#include "sound_map/sound_map_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<sound_map::SoundMapNode, sound_map::SoundMapNodeOptions>(
      {"sarmap-sound-map",
       "Maps stationary sound sources from DOA observations: an inverse-depth EKF sound map\n"
       "kept conditionally independent of SLAM (Su 2017 §4.3), updated from SLAM_ANCHORS by\n"
       "back-propagation after every SLAM optimisation.",
       "Channels in: DOA, PEOPLE_AUDIO, POSE, SLAM_ANCHORS, MAP. Out: SLAM_ANCHOR_REQUEST, "
       "SOUND_MAP.",
       "config/sound_map.yaml"},
      argc, argv);
}
