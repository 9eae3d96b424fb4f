// sarmap-vision-people: the people detector node (VisionPeopleNode, vision_people_node.h).
#include "common/node_runner.h"
#include "vision_people/vision_people_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<vision_people::VisionPeopleNode, vision_people::VisionPeopleOptions>(
      {"sarmap-vision-people",
       "Detects people in RGB-D frames (DEPTH + RGB image_t, paired by utime) and publishes\n"
       "them on PEOPLE_VISUAL (people_detections_t, camera optical frame). Ground-based\n"
       "clustering with HOG on the colour patch; a depth-only shape classifier takes over in\n"
       "darkness and glare. People are reported after k of n frames.",
       "", "config/vision_people.yaml"},
      argc, argv);
}
