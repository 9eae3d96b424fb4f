#pragma once
// Files of the calibration tool: TDOA / microphone / motion CSVs (the format of
// shared/data/audio/calibration/fig8a_*), the array YAML (common::MicArrayOptions, read by
// LoadMicArray), and the report (text, JSON, PNG plot).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/robot_config.h"
#include "mic_calibrate/calibration.h"

namespace sarmap {
namespace mic_calibrate {

// TDOA CSV: '#' comment lines, then a header. Columns: `k` (1-based step) and/or `t_s`
// (emission time), optional `src_x,src_y,src_z` (source truth), one `tdoa_*` column per mic
// 2..N (seconds against mic 1; empty/nan = missing), optional `info` (1/sigma^2, s^-2) or
// `sigma_s`. Without `t_s`, t_k = k * step_s.
struct TdoaCsv {
  TdoaData data;
  std::vector<Eigen::Vector3d> source_truth_m;  // empty when the file has none
};
TdoaCsv ReadTdoaCsv(const std::string& path, double step_s);
void WriteTdoaCsv(const std::string& path, const TdoaData& data);

// Keeps the microphones `mics` (1-based, in that order; the first becomes the reference):
// z'_j = z_{mics[j]} - z_{mics[0]} with z_1 = 0. Throws on a bad list.
TdoaData SelectMics(const TdoaData& data, const std::vector<int>& mics);

// Mic CSV: columns mic, gt_x, gt_y, gt_z [, init_x, init_y, init_z, init_offset, init_drift].
struct MicsCsv {
  std::vector<Eigen::Vector3d> truth_m;
  std::vector<Eigen::Vector3d> init_m;  // empty when absent
  std::vector<double> init_offset_s, init_drift;
};
MicsCsv ReadMicsCsv(const std::string& path);

// Motion CSV (source prior edges): k_from, k_to, dx, dy, dz, info_x, info_y, info_z.
// Fills data->motion_m / motion_sigma_m for consecutive edges.
void ReadMotionCsv(const std::string& path, TdoaData* data);

// The calibrated array in the MicArrayOptions schema.
common::MicArrayOptions ToArrayOptions(const CalibrationResult& result,
                                       const SolverOptions& options, const std::string& name,
                                       int sample_rate_hz);
void WriteArrayYaml(const std::string& path, const common::MicArrayOptions& array,
                    const std::string& header_comment);

// Comparison with measured / nominal positions, in the calibration gauge frame.
struct TruthComparison {
  bool available = false;
  std::vector<Eigen::Vector3d> nominal_in_gauge_m;
  std::vector<double> error_m;  // per mic
  double position_rms_m = 0;    // over the non-reference mics
  double source_rms_m = -1;     // when source truth is given
};
TruthComparison CompareWithNominal(const CalibrationResult& result,
                                   const std::vector<Eigen::Vector3d>& nominal,
                                   const std::vector<Eigen::Vector3d>& source_truth);

std::string TextReport(const CalibrationResult& r, const TruthComparison& cmp,
                       const SolverOptions& o);
std::string JsonReport(const CalibrationResult& r, const TruthComparison& cmp,
                       const SolverOptions& o);
// Top view (x-y) of estimated mics (with 2-sigma ellipses), nominal mics and the source path.
void WritePlot(const std::string& png_path, const CalibrationResult& r,
               const TruthComparison& cmp);

}  // namespace mic_calibrate
}  // namespace sarmap
