// sarmap-monitor: the bus monitor (MonitorNode, monitor_node.h).
#include "common/node_runner.h"
#include "monitor/monitor_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<monitor::MonitorNode, monitor::MonitorOptions>(
      {"sarmap-monitor",
       "Watches every sarmap channel: decodes and checks each message with its type, and\n"
       "prints rates, sequence gaps and malformed-message counts. NODE_STATUS carries the\n"
       "same counts for other tools.",
       "", ""},
      argc, argv);
}
