// sarmap-people-map: the people map node (PeopleMapNode, people_map_node.h).
#include "common/node_runner.h"
#include "people_map/people_map_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<people_map::PeopleMapNode, people_map::PeopleMapNodeOptions>(
      {"sarmap-people-map",
       "The people map: moves each person seen or heard into the map frame with the robot pose\n"
       "at the detection's capture time, merges detections within 45 cm, fuses a heard person\n"
       "with a seen one, places heard-only people at their sound-map position, and keeps a\n"
       "confidence that grows with evidence and decays without it. A seen person moves with\n"
       "the SLAM node they were first seen from when a loop closure corrects it.\n"
       "In: PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP, POSE, SLAM_ANCHORS.\n"
       "Out: PEOPLE_MAP, SLAM_ANCHOR_REQUEST.",
       "", "config/people_map.yaml"},
      argc, argv);
}
