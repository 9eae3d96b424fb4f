// sarmap-log-doa-eval: DOA accuracy of each method on labelled multichannel recordings.
//   sarmap-log doa-eval --array config/arrays/respeaker4.yaml --azimuth-deg 180 --elevation-deg 20
//     --methods srp_phat,music,gevd_music,gcc_phat FILE.wav...
// With --score: the multi-talker scorer (doa_evaluation.h) over the files (one talker at the
// given direction) and, with --simulate 2,3, simulated scenes of 2 and 3 talkers (speech from
// --speech-dir), one table row per scene and a summary per group.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sound_localisation/testing/doa_evaluation.h"

using namespace sarmap;

namespace {

double Percent(int a, int b) { return b > 0 ? 100.0 * a / b : NAN; }

int RunScore(const sound::ArrayGeometry& geometry, const sound::LocaliserOptions& options,
             const sound::ScoreOptions& score_options, const std::vector<std::string>& files,
             const sound::Direction& truth, const std::string& simulate,
             const std::string& speech_dir) {
  std::vector<std::pair<std::string, std::vector<sound::Scene>>> groups;
  if (!files.empty()) {
    std::vector<sound::Scene> recorded;
    for (const auto& f : files) recorded.push_back(sound::LoadRecordedScene(f, geometry, truth));
    groups.emplace_back("recorded", std::move(recorded));
  }
  std::stringstream ss(simulate);
  std::string count;
  while (std::getline(ss, count, ',')) {
    if (speech_dir.empty())
      throw common::ArgError("--simulate needs --speech-dir (shared/data/audio/cmu_arctic)");
    auto scenes = sound::SimulatedBenchmarkScenes(geometry, speech_dir, std::stoi(count));
    if (scenes.empty()) throw std::runtime_error("speech files missing in " + speech_dir);
    groups.emplace_back("sim " + count + " talkers", std::move(scenes));
  }
  std::printf(
      "| scene | talkers | speech blocks | found <=5 deg | covered <=5 deg | tracked <=5 deg | "
      "tracks | spurious | onset (s) | el err (deg) | CPU-s/audio-s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [group, scenes] : groups) {
    int pairs = 0, found = 0, covered = 0, tracked = 0, spurious = 0;
    double cpu = 0, audio = 0;
    std::vector<double> onsets, el_errors;
    for (const auto& scene : scenes) {
      const auto r = sound::ScoreScene(scene, geometry, options, score_options);
      std::string onset;
      for (double l : r.onset_latency_s) {
        char b[32];
        std::snprintf(b, sizeof b, "%s%.2f", onset.empty() ? "" : " ", l);
        onset += b;
        onsets.push_back(std::isnan(l) ? 1e9 : l);
      }
      std::string ghosts;
      for (const auto& d : r.spurious_directions) {
        char b[48];
        std::snprintf(b, sizeof b, " (%.0f/%.0f)", sound::RadToDeg(d.azimuth_rad),
                      sound::RadToDeg(d.elevation_rad));
        ghosts += b;
      }
      std::printf("| %s | %d | %d | %.0f %% | %.0f %% | %.0f %% | %d | %d%s | %s | %.1f | %.4f |\n",
                  std::filesystem::path(r.name).filename().c_str(), r.talkers, r.speech_pairs,
                  Percent(r.found, r.speech_pairs), Percent(r.covered, r.speech_pairs),
                  Percent(r.tracked, r.speech_pairs), r.confirmed_tracks, r.spurious_tracks,
                  ghosts.c_str(), onset.c_str(), r.median_elevation_error_deg, r.cpu_s / r.audio_s);
      el_errors.push_back(r.median_elevation_error_deg);
      pairs += r.speech_pairs;
      found += r.found;
      covered += r.covered;
      tracked += r.tracked;
      spurious += r.spurious_tracks;
      cpu += r.cpu_s;
      audio += r.audio_s;
    }
    std::printf(
        "| **%s** (%zu) | | %d | %.0f %% | %.0f %% | %.0f %% | | %.2f per scene | median %.2f | "
        "%.1f | %.4f |\n",
        group.c_str(), scenes.size(), pairs, Percent(found, pairs), Percent(covered, pairs),
        Percent(tracked, pairs), static_cast<double>(spurious) / scenes.size(),
        sound::Median(onsets), sound::Median(el_errors), cpu / audio);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-doa-eval", [&]() {
    std::string array_path = "config/arrays/respeaker4.yaml", config_path,
                methods = "srp_phat,music,gevd_music,gcc_phat";
    double az = 0, el = 0;
    std::vector<std::string> files, overrides;
    common::ArgParser p("sarmap-log-doa-eval",
                        "Per-file DOA accuracy of each method against a known direction.");
    p.AddFlag("--array", &array_path, "array description (config/arrays/<name>.yaml)");
    p.AddFlag("--config", &config_path,
              "sound_localisation.yaml (its 'localiser' section); defaults if empty");
    std::string section = "localiser";
    p.AddFlag("--section", &section, "the config's section to use (localiser or map_localiser)");
    p.AddRepeated("--set", &overrides, "override a localiser option key=value");
    p.AddFlag("--methods", &methods, "comma-separated methods");
    p.AddFlag("--azimuth-deg", &az, "true azimuth (linear arrays: angle to the axis)");
    p.AddFlag("--elevation-deg", &el, "true elevation");
    bool score = false;
    sound::ScoreOptions score_options;
    std::string simulate, speech_dir;
    p.AddSwitch("--score", &score, "multi-talker scorer instead of the per-method accuracy table");
    p.AddFlag("--simulate", &simulate,
              "with --score: also simulated scenes of these talker counts (e.g. 2,3)");
    p.AddFlag("--found-deg", &score_options.found_deg,
              "with --score: a talker is found / covered within this azimuth error");
    p.AddFlag("--speech-dir", &speech_dir, "CMU ARCTIC speech for the simulated scenes");
    p.AddRest("FILE", &files, "multichannel WAV files");
    if (!p.Parse(argc, argv)) return 0;
    if (files.empty() && simulate.empty()) throw common::ArgError("give at least one file");
    const auto array = common::LoadMicArray(array_path);
    const auto geometry = sound::ArrayGeometry::FromOptions(array);
    sound::LocaliserOptions base =
        config_path.empty()
            ? common::LoadOptions<sound::LocaliserOptions>("", overrides)
            : common::LoadOptions<sound::LocaliserOptions>(config_path, overrides, section);
    if (score)
      return RunScore(geometry, base, score_options, files,
                      {sound::DegToRad(az), sound::DegToRad(el)}, simulate, speech_dir);
    std::vector<double> all_az, all_el;
    std::printf(
        "| file | method | blocks | median az err (deg) | median el err (deg) | whole-file az/el "
        "(deg) |\n");
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
        const auto r =
            sound::EvaluateDoaFile(f, geometry, opt, {sound::DegToRad(az), sound::DegToRad(el)});
        std::printf("| %s | %s | %d | %.2f | %.2f | %.1f / %.1f |\n", f.c_str(), m.c_str(),
                    r.blocks, r.median_azimuth_error_deg, r.median_elevation_error_deg,
                    r.whole_azimuth_deg, r.whole_elevation_deg);
        maz.push_back(r.median_azimuth_error_deg);
        mel.push_back(r.median_elevation_error_deg);
      }
      std::printf("| ALL (median of files) | %s | | %.2f | %.2f | |\n", m.c_str(),
                  sound::Median(maz), sound::Median(mel));
    }
    return 0;
  });
}
