// sarmap-procman-deputy: runs the commands a verified sheriff orders on this computer.
#include "common/args.h"
#include "procman/procman_cli.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-procman-deputy",
                                 [&] { return sarmap::procman::RunDeputy(argc, argv); });
}
