// sarmap-log report LOG: the mission report (HTML, PNG map, JSON) and a summary on stdout.
#include <cstdio>

#include "common/args.h"
#include "log-tools/mission_report.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log report", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log report",
        "Writes the mission report of a log: report.html, map.png (map, robot path, people seen "
        "and\n"
        "heard with their uncertainty, sound sources with 3-sigma ellipses) and report.json. With\n"
        "SIM_TRUTH in the log it also says who was found against the simulator's truth, how, when\n"
        "and with what position error, and gives the mission metrics: coverage of the reachable\n"
        "floor (SIM_FLOOR; coverage.png, unmapped floor shaded on map.png), distance, collisions,\n"
        "stuck time and coming home (EXPLORE_STATUS). Prints a summary.");
    std::string log, output, bus_key_file;
    double match_radius_m = 0.5;
    parser.AddPositional("LOG", &log, "LCM log of the mission");
    parser.AddFlag("-o", &output, "output directory (default: LOG without extension + -report)");
    parser.AddFlag("--match-radius", &match_radius_m, "a reported person within this of a true one found them (m)");
    parser.AddFlag("--bus-key-file", &bus_key_file,
                   "the bus key of a signed bus (common/bus_auth.h): only messages signed with it "
                   "count (default: every well-formed message)");
    if (!parser.Parse(argc, argv)) return 0;
    const sarmap::common::AuthKey bus_key =
        bus_key_file.empty() ? sarmap::common::AuthKey{}
                             : sarmap::common::LoadAuthKeyFile(bus_key_file);
    if (output.empty()) output = log.substr(0, log.rfind('.')) + "-report";
    std::vector<std::string> problems;
    sarmap::logtools::MissionMetricsOptions metrics_options;
    metrics_options.match_radius_m = match_radius_m;
    const auto data = sarmap::logtools::LoadMission(log, &problems, metrics_options, bus_key);
    for (const auto& p : problems) fprintf(stderr, "warning: %s\n", p.c_str());
    const auto summary = sarmap::logtools::Summarise(data, match_radius_m);
    sarmap::logtools::WriteReport(data, summary, output);
    fputs(sarmap::logtools::SummaryText(data, summary).c_str(), stdout);
    printf("report: %s/report.html\n", output.c_str());
    return 0;
  });
}
