// sarmap-teleop: the operator's TELEOP from a terminal. An emergency stop, its release, or a
// drive for some seconds, signed with the command key so that an explorer with
// command_key_file obeys it; then EXPLORE_STATUS says whether it was obeyed.
#include "common/node_main.h"
#include "teleop/teleop_sender.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-teleop",
                                 [&] { return sarmap::teleop::RunTeleop(argc, argv); });
}
