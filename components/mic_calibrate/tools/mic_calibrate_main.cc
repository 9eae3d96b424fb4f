// sarmap-mic-calibrate: calibrates a microphone array (positions, start offsets, clock drift)
// from a recording of a sound source moving around it (Su 2017 ch. 3) and writes the array
// YAML that LoadMicArray() / sarmap-sound-localisation read, plus a report.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "mic_calibrate/calibration.h"
#include "mic_calibrate/calibration_io.h"
#include "mic_calibrate/lcm_audio_log.h"
#include "mic_calibrate/mic_calibrate_options.h"
#include "mic_calibrate/tdoa_extraction.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

std::string Ext(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string e = path.substr(dot + 1);
  for (char& c : e) c = static_cast<char>(tolower(c));
  return e;
}

std::vector<Eigen::Vector3d> PositionsOf(const common::MicArrayOptions& a) {
  std::vector<Eigen::Vector3d> p;
  for (int n = 0; n < a.num_mics(); ++n) p.push_back(a.mic_position(n));
  return p;
}

// The text report on stderr, then the array YAML (`output`, checked to load back) and the report
// files (`report`.txt/.json/.png), when asked for.
template <class Progress>
void WriteOutputs(const CalibrationResult& result, const TruthComparison& cmp,
                  const SolverOptions& so, const std::string& array_name, int sample_rate_hz,
                  const std::string& output, const std::string& report, bool quiet,
                  const std::string& written_from, const std::string& positions_note,
                  const Progress& progress) {
  const std::string text = TextReport(result, cmp, so);
  if (!quiet) fprintf(stderr, "%s", text.c_str());
  if (!output.empty()) {
    const common::MicArrayOptions array = ToArrayOptions(result, so, array_name, sample_rate_hz);
    WriteArrayYaml(
        output, array,
        (result.converged ? "" : "NOT CONVERGED: not to be trusted (see the report's warnings)\n") +
            written_from + "\nTDOA residual std " + std::to_string(result.residual_std_s * 1e3) +
            " ms; " + positions_note);
    common::LoadMicArray(output);  // what we wrote must load
    progress("array written to " + output);
  }
  if (!report.empty()) {
    std::ofstream(report + ".txt") << text;
    std::ofstream(report + ".json") << JsonReport(result, cmp, so);
    WritePlot(report + ".png", result, cmp);
    progress("report written to " + report + ".{txt,json,png}");
  }
}

// Exit code of a solve that produced outputs: 0, or kNotConverged when the solve did not converge
// (the outputs are written, marked untrusted).
constexpr int kNotConverged = 4;
template <class Progress>
int ExitCode(const CalibrationResult& result, const Progress& progress) {
  if (result.converged) return 0;
  progress("the solve did not converge: outputs written but not to be trusted (exit code " +
           std::to_string(kNotConverged) + ")");
  return kNotConverged;
}

// Known array motion, static source: the pose of every emission from the log, then
// CalibrateWithArrayPoses. Returns the exit code.
template <class Progress>
int RunWithArrayPoses(const MicCalibrateOptions& opt, const std::string& input,
                      const std::string& input_type, std::string poses_log, TdoaData data,
                      const std::vector<Eigen::Vector3d>& nominal, const std::string& output,
                      const std::string& report, int sample_rate_hz, bool quiet,
                      const Progress& progress) {
  const ArrayPosesOptions& po = opt.array_poses;
  if (nominal.empty()) {
    throw common::ArgError(
        "array_poses needs the microphone positions in the array frame (--nominal)");
  }
  if (poses_log.empty()) {
    if (input_type != "lcm") {
      throw common::ArgError("array_poses: give --poses LOG (the input is not an LCM log)");
    }
    poses_log = input;
  }
  if (static_cast<int>(data.utimes.size()) != data.num_emissions()) {
    throw common::ArgError(
        "array_poses: the TDOAs carry no absolute times (utime); use an LCM "
        "log, or a TDOA CSV written by --write-tdoa from one");
  }
  LcmAudioLogStats st;
  const std::vector<common::StampedPose> poses = ReadLcmPoses(poses_log, po.channel, &st);
  for (const auto& w : st.warnings) progress("warning: " + w);
  const int64_t gap_us = static_cast<int64_t>(po.max_gap_s * 1e6);
  common::PoseHistory history(std::numeric_limits<int64_t>::max() / 4, gap_us);
  for (const auto& p : poses) history.Add(p);
  const common::RobotOptions robot = common::LoadRobot(po.robot_config);
  const common::Rigid3d base_from_array = robot.base_from_mic_array.ToRigid3d();
  // Keep the emissions that have a pose.
  TdoaData kept = data;
  kept.times_s.clear();
  kept.utimes.clear();
  kept.sigma_s.clear();
  std::vector<int> rows;
  std::vector<Eigen::Isometry3d> world_from_array;
  for (int k = 0; k < data.num_emissions(); ++k) {
    const auto p = history.At(data.utimes[k]);
    if (!p) continue;
    const common::Rigid3d w = p->pose * base_from_array;
    Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
    iso.linear() = w.rotation().toRotationMatrix();
    iso.translation() = w.translation();
    world_from_array.push_back(iso);
    rows.push_back(k);
  }
  kept.tdoa_s.resize(static_cast<long>(rows.size()), data.num_mics - 1);
  for (size_t i = 0; i < rows.size(); ++i) {
    const int k = rows[i];
    kept.tdoa_s.row(static_cast<long>(i)) = data.tdoa_s.row(k);
    kept.times_s.push_back(data.times_s[k]);
    kept.utimes.push_back(data.utimes[k]);
    if (!data.sigma_s.empty()) kept.sigma_s.push_back(data.sigma_s[k]);
  }
  progress(std::to_string(poses.size()) + " poses on " + po.channel + " from " + poses_log + "; " +
           std::to_string(rows.size()) + " of " + std::to_string(data.num_emissions()) +
           " emissions have one; solving (static source, known array poses)");
  SolverOptions so = opt.solver;
  so.verbose = so.verbose || !quiet;
  CalibrationResult result;
  try {
    result = CalibrateWithArrayPoses(kept, world_from_array, nominal, so);
  } catch (const UnobservableError& e) {
    fprintf(stderr, "sarmap-mic-calibrate: refused: %s\n", e.what());
    return 3;
  }
  if (rows.size() < data.utimes.size()) {
    result.warnings.push_back(std::to_string(data.utimes.size() - rows.size()) +
                              " emissions had no pose within " + std::to_string(po.max_gap_s) +
                              " s on " + po.channel + " and were left out");
  }
  const TruthComparison cmp = CompareWithNominal(result, {}, {});
  WriteOutputs(result, cmp, so, opt.array_name, sample_rate_hz, output, report, quiet,
               "Written by sarmap-mic-calibrate from " + input + " with the array poses of " +
                   po.channel + " (static source)",
               "microphone positions as given (array frame).", progress);
  return ExitCode(result, progress);
}

int Run(int argc, char** argv) {
  std::string input, input_type = "auto", output, report, nominal_path, mics_csv, motion_csv,
                     write_tdoa, config_path, poses_log;
  std::vector<std::string> overrides;
  std::string mic_list;
  bool print_config = false, init_from_nominal = false, quiet = false;
  common::ArgParser args("sarmap-mic-calibrate",
                         "Calibrate a microphone array (positions, start offsets, clock drift) "
                         "from a recording of a sound source moving around it (Su 2017 ch. 3).");
  args.AddPositional("input", &input,
                     "multichannel WAV (channel 1 = reference mic), LCM log with one AUDIO_* "
                     "channel per sound card, or TDOA CSV");
  args.AddFlag("--input-type", &input_type,
               "auto, wav, lcm or csv (auto: by extension; "
               ".csv = TDOAs, .wav/.flac = audio, else LCM log)");
  args.AddFlag("--output", &output, "array YAML to write (MicArrayOptions schema)");
  args.AddFlag("--report", &report, "report prefix: writes PREFIX.txt, PREFIX.json, PREFIX.png");
  args.AddFlag("--nominal", &nominal_path,
               "nominal/measured positions to compare with: array YAML or mic CSV (gt_x,...)");
  args.AddSwitch("--init-from-nominal", &init_from_nominal,
                 "first start from the nominal positions (mic CSV: its init_* columns)");
  args.AddFlag("--mics", &mic_list,
               "use only these microphones, e.g. 1,2,3,4 (the first is the reference)");
  args.AddFlag("--motion-csv", &motion_csv,
               "source motion prior edges (k_from,k_to,dx,..,info_x,..)");
  args.AddFlag("--write-tdoa", &write_tdoa, "also write the extracted TDOAs as CSV");
  args.AddFlag("--poses", &poses_log,
               "LCM log with the array's poses (array_poses.channel; default: the input log)");
  args.AddFlag("--config", &config_path, "options YAML (config/mic_calibrate.yaml)");
  args.AddRepeated("--set", &overrides, "override an option: key=value (e.g. solver.geometry=3d)");
  args.AddSwitch("--print-config", &print_config, "print the effective options and exit");
  args.AddSwitch("--quiet", &quiet, "no progress output");
  args.SetEpilog(
      "Examples:\n"
      "  sarmap-mic-calibrate ../shared/data/audio/calibration/fig8a_tdoa.csv --config "
      "mic_calibrate.yaml \\\n"
      "      --mics 1,2,3,4 --nominal ../shared/data/audio/calibration/fig8a_mics.csv \\\n"
      "      --output /tmp/fig8a.yaml --report /tmp/fig8a\n"
      "  sarmap-mic-calibrate recording.lcmlog --output config/arrays/cards.yaml --report "
      "/tmp/cards\n"
      "Exit codes: 0 calibrated, 2 bad arguments/options/input, 3 refused (unobservable: the "
      "message says what the data cannot determine), 4 the solve did not converge (outputs "
      "written but marked untrusted: \"converged\": false and a warning in the report, a "
      "NOT CONVERGED line in the array YAML; raise solver.max_iterations or give a better "
      "start).\n");
  if (!args.Parse(argc, argv)) return 0;
  const MicCalibrateOptions opt = common::LoadOptions<MicCalibrateOptions>(
      config_path.empty() ? config_path : common::ResolveConfigPath(config_path), overrides);
  if (print_config) {
    printf("%s", common::OptionsToYaml(opt, true).c_str());
    return 0;
  }
  if (output.empty() && report.empty()) throw common::ArgError("give --output and/or --report");
  auto progress = [&](const std::string& s) {
    if (!quiet) fprintf(stderr, "[mic-calibrate] %s\n", s.c_str());
  };
  if (input_type == "auto") {
    const std::string e = Ext(input);
    input_type = e == "csv" ? "csv" : (e == "wav" || e == "flac" || e == "ogg") ? "wav" : "lcm";
  }
  if (input_type != "csv" && input_type != "wav" && input_type != "lcm") {
    throw common::ArgError("--input-type must be auto, wav, lcm or csv");
  }
  {
    std::ifstream probe(input);
    if (!probe) throw common::ArgError("cannot open input " + input);
  }

  TdoaData data;
  std::vector<Eigen::Vector3d> source_truth;
  int sample_rate_hz = 44100;
  if (input_type == "csv") {
    progress("reading TDOAs from " + input);
    TdoaCsv csv = ReadTdoaCsv(input, opt.step_s);
    data = std::move(csv.data);
    source_truth = std::move(csv.source_truth_m);
  } else {
    Recording rec;
    if (input_type == "wav") {
      progress("reading audio " + input);
      rec = ReadWav(input);
    } else {
      progress("reading LCM log " + input + " (channels " + opt.lcm_channel_prefix + "*)");
      LcmAudioLogStats st;
      rec = ReadLcmAudioLog(input, opt.lcm_channel_prefix, &st);
      progress(std::to_string(st.devices) + " devices, " + std::to_string(st.frames) + " frames, " +
               std::to_string(st.bad_frames) + " bad");
      for (const auto& w : st.warnings) progress("warning: " + w);
    }
    sample_rate_hz = static_cast<int>(rec.sample_rate_hz);
    progress(std::to_string(rec.channels.size()) + " channels at " +
             std::to_string(sample_rate_hz) + " Hz; extracting TDOAs (" + opt.extraction.method +
             ")");
    ExtractionStats es;
    data = ExtractTdoas(rec, opt.extraction, &es);
    progress(std::to_string(es.events) + " emissions found, " + std::to_string(es.missing) +
             " TDOAs missing");
    for (const auto& w : es.warnings) progress("warning: " + w);
  }
  if (!write_tdoa.empty()) {
    WriteTdoaCsv(write_tdoa, data);
    progress("TDOAs written to " + write_tdoa);
  }
  if (!motion_csv.empty()) ReadMotionCsv(motion_csv, &data);
  std::vector<int> selected;
  if (!mic_list.empty()) {
    std::stringstream ss(mic_list);
    std::string item;
    while (std::getline(ss, item, ',')) {
      try {
        selected.push_back(std::stoi(item));
      } catch (const std::exception&) {
        throw common::ArgError("--mics: not a number: '" + item + "'");
      }
    }
    try {
      data = SelectMics(data, selected);
    } catch (const std::invalid_argument& e) {
      throw common::ArgError(std::string("--mics: ") + e.what());
    }
    progress("using microphones " + mic_list + " (mic " + std::to_string(selected[0]) +
             " is the reference)");
  }

  // Nominal positions (comparison, gauge choice, optional initial guess).
  std::vector<Eigen::Vector3d> nominal;
  InitialGuess guess;
  if (!nominal_path.empty()) {
    if (Ext(nominal_path) == "csv") {
      const MicsCsv m = ReadMicsCsv(nominal_path);
      nominal = m.truth_m;
      guess.mic_positions_m = m.init_m.empty() ? m.truth_m : m.init_m;
      guess.start_offsets_s = m.init_offset_s;
      guess.clock_drift = m.init_drift;
    } else {
      nominal = PositionsOf(common::LoadMicArray(nominal_path));
      guess.mic_positions_m = nominal;
    }
    if (!selected.empty() &&
        static_cast<int>(nominal.size()) >= *std::max_element(selected.begin(), selected.end())) {
      std::vector<Eigen::Vector3d> n2, g2;
      for (int m : selected) {
        n2.push_back(nominal[m - 1]);
        if (static_cast<int>(guess.mic_positions_m.size()) >= m)
          g2.push_back(guess.mic_positions_m[m - 1]);
      }
      nominal = n2;
      guess.mic_positions_m = g2;
      guess.start_offsets_s.clear();  // re-referenced: the file's offsets no longer apply
      guess.clock_drift.clear();
    }
    if (static_cast<int>(nominal.size()) != data.num_mics) {
      throw common::ArgError("--nominal has " + std::to_string(nominal.size()) +
                             " microphones, the input " + std::to_string(data.num_mics));
    }
  }
  SolverOptions so = opt.solver;
  if (!opt.array_poses.channel.empty()) {
    return RunWithArrayPoses(opt, input, input_type, poses_log, data, nominal, output, report,
                             sample_rate_hz, quiet, progress);
  }
  if (so.known_positions && so.geometry != "linear") {
    if (nominal.empty()) {
      throw common::ArgError("solver.known_positions needs --nominal (the known positions)");
    }
    guess = InitialGuess();
    guess.mic_positions_m = nominal;  // mic 1 is moved to the origin by the solver
    init_from_nominal = true;
  } else if (!nominal.empty() && so.geometry != "linear") {
    ChooseGauge(data.num_mics, so.dim(), nominal, &so.gauge_x_mic, &so.gauge_plane_mic,
                &so.gauge_z_mic);
    if (so.dim() == 3 && so.height_prior_sigma_m > 0 && so.mic_heights_m.empty()) {
      // Known heights: the nominal z in the gauge frame (meaningful when the gauge mics span
      // the horizontal plane, e.g. --set solver.gauge_x_mic=2 --set solver.gauge_plane_mic=3).
      for (const auto& p :
           ToGaugeFrame(nominal, 3, so.gauge_x_mic, so.gauge_plane_mic, so.gauge_z_mic)) {
        so.mic_heights_m.push_back(p.z());
      }
    }
    if (init_from_nominal) {
      // The guess must be in the gauge frame (offsets/drifts, if given, are frame-free).
      guess.mic_positions_m = ToGaugeFrame(guess.mic_positions_m, so.dim(), so.gauge_x_mic,
                                           so.gauge_plane_mic, so.gauge_z_mic);
    }
  }
  so.verbose = so.verbose || !quiet;
  progress(std::to_string(data.num_emissions()) + " emissions x " + std::to_string(data.num_mics) +
           " mics; solving (" + so.geometry + (so.synchronous ? ", synchronous" : "") + ", up to " +
           std::to_string(so.num_starts) + " starts)");
  CalibrationResult result;
  try {
    result = Calibrate(data, so, init_from_nominal ? &guess : nullptr);
  } catch (const UnobservableError& e) {
    fprintf(stderr, "sarmap-mic-calibrate: refused: %s\n", e.what());
    return 3;
  }
  for (const auto& w : result.warnings) progress("warning: " + w);
  // Known positions are the nominal ones (translated to mic 1): nothing to compare.
  const TruthComparison cmp = CompareWithNominal(
      result, so.known_positions ? std::vector<Eigen::Vector3d>() : nominal, source_truth);
  WriteOutputs(result, cmp, so, opt.array_name, sample_rate_hz, output, report, quiet,
               "Written by sarmap-mic-calibrate from " + input,
               "positions in the calibration gauge frame (mic 1 at the origin).", progress);
  return ExitCode(result, progress);
}

}  // namespace
}  // namespace mic_calibrate
}  // namespace sarmap

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-mic-calibrate",
                                 [&] { return sarmap::mic_calibrate::Run(argc, argv); });
}
