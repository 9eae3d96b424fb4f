// sarmap-procman: the sheriff. Sends the desired state of a .pmd config to the deputies and
// shows what they report.
//
//   sarmap-procman CONFIG.pmd status
//   sarmap-procman CONFIG.pmd start|stop|restart NAME     (command, group, or "everything")
//   sarmap-procman CONFIG.pmd run SCRIPT
//   sarmap-procman CONFIG.pmd                             (live status table + output tail)
//   sarmap-procman CONFIG.pmd --observer                  (live view, sends nothing)
//   sarmap-procman CONFIG.pmd --lone-ranger [COMMAND]     (deputies in-process: one computer)
#include "common/args.h"
#include "procman/procman_cli.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-procman",
                                 [&] { return sarmap::procman::RunSheriff(argc, argv); });
}
