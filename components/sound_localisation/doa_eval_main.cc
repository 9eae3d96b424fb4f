// sarmap-log-doa-eval: DOA accuracy of each method on labelled multichannel recordings.
//   sarmap-log doa-eval --array config/arrays/respeaker4.yaml --azimuth-deg 180 --elevation-deg 20
//     --methods srp_phat,music,gevd_music,gcc_phat FILE.wav...
#include <cstdio>
#include <iostream>
#include <sstream>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sound_localisation/doa_evaluation.h"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-doa-eval", [&]() {
    std::string array_path = "config/arrays/respeaker4.yaml", config_path, methods = "srp_phat,music,gevd_music,gcc_phat";
    double az = 0, el = 0;
    std::vector<std::string> files, overrides;
    common::ArgParser p("sarmap-log-doa-eval", "Per-file DOA accuracy of each method against a known direction.");
    p.AddFlag("--array", &array_path, "array description (config/arrays/<name>.yaml)");
    p.AddFlag("--config", &config_path, "sound_localisation.yaml (its 'localiser' section); defaults if empty");
    p.AddRepeated("--set", &overrides, "override a localiser option key=value");
    p.AddFlag("--methods", &methods, "comma-separated methods");
    p.AddFlag("--azimuth-deg", &az, "true azimuth (linear arrays: angle to the axis)");
    p.AddFlag("--elevation-deg", &el, "true elevation");
    p.AddRest("FILE", &files, "multichannel WAV files");
    if (!p.Parse(argc, argv)) return 0;
    if (files.empty()) throw common::ArgError("give at least one file");
    const auto array = common::LoadMicArray(array_path);
    const auto geometry = sound::ArrayGeometry::FromOptions(array);
    sound::LocaliserOptions base = config_path.empty()
                                       ? common::LoadOptions<sound::LocaliserOptions>("", overrides)
                                       : common::LoadOptions<sound::LocaliserOptions>(config_path, overrides, "localiser");
    std::vector<double> all_az, all_el;
    std::printf("| file | method | blocks | median az err (deg) | median el err (deg) | whole-file az/el (deg) |\n");
    std::printf("|---|---|---|---|---|---|\n");
    std::stringstream ms(methods);
    std::string method;
    std::vector<std::string> method_list;
    while (std::getline(ms, method, ',')) method_list.push_back(method);
    for (const auto& m : method_list) {
      std::vector<double> maz, mel;
      for (const auto& f : files) {
        auto opt = base;
        opt.method = m;
        const auto r = sound::EvaluateDoaFile(f, geometry, opt, {sound::DegToRad(az), sound::DegToRad(el)});
        std::printf("| %s | %s | %d | %.2f | %.2f | %.1f / %.1f |\n", f.c_str(), m.c_str(), r.blocks,
                    r.median_azimuth_error_deg, r.median_elevation_error_deg, r.whole_azimuth_deg, r.whole_elevation_deg);
        maz.push_back(r.median_azimuth_error_deg);
        mel.push_back(r.median_elevation_error_deg);
      }
      std::printf("| ALL (median of files) | %s | | %.2f | %.2f | |\n", m.c_str(), sound::Median(maz), sound::Median(mel));
    }
    return 0;
  });
}
