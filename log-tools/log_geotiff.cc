// sarmap-log geotiff LOG -o FILE.tif: the mission's map, path, people and sound sources as a
// RoboCup-Rescue-style GeoTIFF (log-tools/geotiff.h).
#include <cstdio>

#include "common/args.h"
#include "log-tools/geotiff.h"
#include "log-tools/mission_report.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log geotiff", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log geotiff",
        "Writes the last MAP of a log as a RoboCup-Rescue-style GeoTIFF: one pixel per map cell\n"
        "(free white, obstacles dark blue, unknown a grey 1 m checkerboard), a 1 m grid, the "
        "robot's\n"
        "path (orange), the start pose (green arrow), the people found coloured by how (seen red,\n"
        "heard magenta, both yellow; 3-sigma ellipses) and the sound sources (blue). "
        "Georeferenced\n"
        "in the map frame (metres; pixel size = map resolution). People and sources that are\n"
        "unconverged or far outside the map are left out, as in the report.");
    std::string log, output;
    parser.AddPositional("LOG", &log, "LCM log of the mission");
    parser.AddFlag("-o", &output, "GeoTIFF to write (default: LOG without extension + .tif)");
    if (!parser.Parse(argc, argv)) return 0;
    if (output.empty()) {
      const size_t dot = log.rfind('.'), slash = log.rfind('/');
      output = (dot == std::string::npos || (slash != std::string::npos && dot < slash)
                    ? log
                    : log.substr(0, dot)) +
               ".tif";
    }
    std::vector<std::string> problems;
    fprintf(stderr, "geotiff: reading %s\n", log.c_str());
    const auto data = sarmap::logtools::LoadMission(log, &problems);
    for (const auto& p : problems) fprintf(stderr, "warning: %s\n", p.c_str());
    const auto summary = sarmap::logtools::Summarise(data, 0.5);
    sarmap::logtools::WriteGeoTiff(data, summary, output);
    const auto& m = *data.map;
    printf(
        "%s: %d x %d pixels of %.3f m, %d people, %d sound sources, %zu left out (unconverged or "
        "outside the map)\n",
        output.c_str(), m.width, m.height, m.resolution_m, summary.people_found,
        summary.sources_mapped, summary.outside_map.size());
    return 0;
  });
}
