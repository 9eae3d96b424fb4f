#include "mic_calibrate/calibration_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace sarmap {
namespace mic_calibrate {
namespace {

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

// A CSV table: '#' comments, header, rows of numbers (empty / nan cells -> NaN).
struct Table {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::vector<int> line_of_row;
  int Col(const std::string& name) const {
    for (size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i);
    return -1;
  }
  int Need(const std::string& name) const {
    const int c = Col(name);
    if (c < 0) throw std::runtime_error(path + ": no column '" + name + "'");
    return c;
  }
};

Table ReadTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  Table t;
  t.path = path;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const std::string s = Trim(line);
    if (s.empty() || s[0] == '#') continue;
    const std::vector<std::string> cells = Split(s);
    if (t.header.empty()) {
      t.header = cells;
      continue;
    }
    if (cells.size() != t.header.size()) {
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": " +
                               std::to_string(cells.size()) + " cells, header has " +
                               std::to_string(t.header.size()));
    }
    std::vector<double> row;
    for (const auto& c : cells) {
      if (c.empty() || c == "nan" || c == "NaN" || c == "NA") {
        row.push_back(std::nan(""));
        continue;
      }
      char* end = nullptr;
      const double v = std::strtod(c.c_str(), &end);
      if (end == c.c_str() || *end != '\0') {
        throw std::runtime_error(path + ":" + std::to_string(lineno) + ": not a number: '" + c + "'");
      }
      row.push_back(v);
    }
    t.rows.push_back(row);
    t.line_of_row.push_back(lineno);
  }
  if (t.header.empty()) throw std::runtime_error(path + ": no header line");
  return t;
}

std::string Num(double v, int prec = 6) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(prec) << v;
  return s.str();
}

}  // namespace

TdoaCsv ReadTdoaCsv(const std::string& path, double step_s) {
  const Table t = ReadTable(path);
  std::vector<int> tdoa_cols;
  for (size_t i = 0; i < t.header.size(); ++i)
    if (t.header[i].rfind("tdoa", 0) == 0) tdoa_cols.push_back(static_cast<int>(i));
  if (tdoa_cols.empty()) throw std::runtime_error(path + ": no tdoa_* columns");
  const int ct = t.Col("t_s"), ck = t.Col("k");
  if (ct < 0 && ck < 0) throw std::runtime_error(path + ": needs a 'k' or 't_s' column");
  const int cx = t.Col("src_x"), cy = t.Col("src_y"), cz = t.Col("src_z");
  const int cinfo = t.Col("info"), csig = t.Col("sigma_s"), cutime = t.Col("utime");
  TdoaCsv out;
  out.data.num_mics = static_cast<int>(tdoa_cols.size()) + 1;
  const int K = static_cast<int>(t.rows.size());
  out.data.tdoa_s.resize(K, tdoa_cols.size());
  for (int k = 0; k < K; ++k) {
    const auto& row = t.rows[k];
    const double time = ct >= 0 ? row[ct] : row[ck] * step_s;
    if (!std::isfinite(time)) {
      throw std::runtime_error(path + ":" + std::to_string(t.line_of_row[k]) + ": time/step is missing");
    }
    out.data.times_s.push_back(time);
    if (cutime >= 0) {
      if (!std::isfinite(row[cutime])) {
        throw std::runtime_error(path + ":" + std::to_string(t.line_of_row[k]) + ": utime is missing");
      }
      out.data.utimes.push_back(std::llround(row[cutime]));
    }
    for (size_t j = 0; j < tdoa_cols.size(); ++j) out.data.tdoa_s(k, j) = row[tdoa_cols[j]];
    if (cinfo >= 0 || csig >= 0) {
      const double sigma = csig >= 0 ? row[csig] : 1.0 / std::sqrt(row[cinfo]);
      if (!(std::isfinite(sigma) && sigma > 0)) {
        throw std::runtime_error(path + ":" + std::to_string(t.line_of_row[k]) +
                                 ": TDOA information/sigma must be > 0");
      }
      out.data.sigma_s.push_back(sigma);
    }
    if (cx >= 0 && cy >= 0) {
      out.source_truth_m.emplace_back(row[cx], row[cy], cz >= 0 ? row[cz] : 0.0);
    }
  }
  return out;
}

void WriteTdoaCsv(const std::string& path, const TdoaData& d) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# TDOAs z_n of mic n against mic 1 (s), emission time t_s on mic 1's clock\n";
  out << "k,t_s";
  for (int n = 2; n <= d.num_mics; ++n) out << ",tdoa_m" << n << "_s";
  if (!d.sigma_s.empty()) out << ",sigma_s";
  const bool utimes = static_cast<int>(d.utimes.size()) == d.num_emissions();
  if (utimes) out << ",utime";
  out << "\n" << std::setprecision(10);
  for (int k = 0; k < d.num_emissions(); ++k) {
    out << k + 1 << "," << d.times_s[k];
    for (int n = 0; n < d.num_mics - 1; ++n) {
      out << ",";
      if (std::isfinite(d.tdoa_s(k, n))) out << d.tdoa_s(k, n); else out << "nan";
    }
    if (!d.sigma_s.empty()) out << "," << d.sigma_s[k];
    if (utimes) out << "," << d.utimes[k];
    out << "\n";
  }
}

TdoaData SelectMics(const TdoaData& d, const std::vector<int>& mics) {
  if (mics.size() < 2) throw std::invalid_argument("select at least 2 microphones");
  for (size_t i = 0; i < mics.size(); ++i) {
    if (mics[i] < 1 || mics[i] > d.num_mics) {
      throw std::invalid_argument("microphone " + std::to_string(mics[i]) + " not in 1.." +
                                  std::to_string(d.num_mics));
    }
    for (size_t j = 0; j < i; ++j)
      if (mics[j] == mics[i]) throw std::invalid_argument("microphone listed twice");
  }
  auto z = [&](int k, int mic) { return mic == 1 ? 0.0 : d.tdoa_s(k, mic - 2); };
  TdoaData out = d;
  out.num_mics = static_cast<int>(mics.size());
  out.tdoa_s.resize(d.num_emissions(), out.num_mics - 1);
  for (int k = 0; k < d.num_emissions(); ++k)
    for (int j = 1; j < out.num_mics; ++j) out.tdoa_s(k, j - 1) = z(k, mics[j]) - z(k, mics[0]);
  return out;
}

MicsCsv ReadMicsCsv(const std::string& path) {
  const Table t = ReadTable(path);
  MicsCsv m;
  const int gx = t.Need("gt_x"), gy = t.Need("gt_y"), gz = t.Col("gt_z");
  const int ix = t.Col("init_x"), iy = t.Col("init_y"), iz = t.Col("init_z");
  const int io = t.Col("init_offset"), id = t.Col("init_drift");
  for (const auto& row : t.rows) {
    m.truth_m.emplace_back(row[gx], row[gy], gz >= 0 ? row[gz] : 0.0);
    if (ix >= 0 && iy >= 0) m.init_m.emplace_back(row[ix], row[iy], iz >= 0 ? row[iz] : 0.0);
    if (io >= 0) m.init_offset_s.push_back(row[io]);
    if (id >= 0) m.init_drift.push_back(row[id]);
  }
  return m;
}

void ReadMotionCsv(const std::string& path, TdoaData* data) {
  const Table t = ReadTable(path);
  const int K = data->num_emissions();
  data->motion_m.assign(std::max(K - 1, 0), Eigen::Vector3d::Zero());
  data->motion_sigma_m.assign(std::max(K - 1, 0), Eigen::Vector3d::Constant(1.0));
  std::vector<bool> seen(std::max(K - 1, 0), false);
  const int cf = t.Need("k_from"), cto = t.Need("k_to");
  const char* d[3] = {"dx", "dy", "dz"};
  const char* info[3] = {"info_x", "info_y", "info_z"};
  for (size_t r = 0; r < t.rows.size(); ++r) {
    const auto& row = t.rows[r];
    const int a = static_cast<int>(row[cf]), b = static_cast<int>(row[cto]);
    if (b != a + 1 || a < 1 || b > K) {
      throw std::runtime_error(path + ":" + std::to_string(t.line_of_row[r]) +
                               ": only consecutive edges k, k+1 within 1.." + std::to_string(K) +
                               " are supported");
    }
    for (int i = 0; i < 3; ++i) {
      const int cd = t.Col(d[i]), ci = t.Col(info[i]);
      data->motion_m[a - 1][i] = cd >= 0 ? row[cd] : 0.0;
      const double inf = ci >= 0 ? row[ci] : 1.0;
      if (!(inf > 0)) throw std::runtime_error(path + ": information must be > 0");
      data->motion_sigma_m[a - 1][i] = 1.0 / std::sqrt(inf);
    }
    seen[a - 1] = true;
  }
  for (size_t e = 0; e < seen.size(); ++e) {
    if (!seen[e]) {
      throw std::runtime_error(path + ": no edge " + std::to_string(e + 1) + "-" + std::to_string(e + 2));
    }
  }
}

common::MicArrayOptions ToArrayOptions(const CalibrationResult& r, const SolverOptions& o,
                                       const std::string& name, int sample_rate_hz) {
  common::MicArrayOptions a;
  a.name = name;
  a.sample_rate_hz = sample_rate_hz;
  a.speed_of_sound_mps = o.speed_of_sound_mps;
  a.geometry = o.geometry;
  const int N = static_cast<int>(r.mic_positions_m.size());
  for (int n = 0; n < N; ++n) {
    a.channel_map.push_back(n);
    for (int i = 0; i < 3; ++i) a.mic_positions_m.push_back(r.mic_positions_m[n][i] + 0.0);  // no -0
    a.mic_position_std_m.push_back(
        r.has_covariance ? std::sqrt(std::max(0.0, r.mic_position_cov[n].trace())) : 0.0);
  }
  if (!o.synchronous) {
    a.start_offsets_s = r.start_offsets_s;
    a.clock_drift = r.clock_drift;
  }
  return a;
}

void WriteArrayYaml(const std::string& path, const common::MicArrayOptions& a,
                    const std::string& header_comment) {
  common::ValidateOptions(a);
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  std::istringstream lines(header_comment);
  std::string line;
  while (std::getline(lines, line)) out << "# " << line << "\n";
  out << common::OptionsToYaml(a, false);
  if (!out) throw std::runtime_error("error writing " + path);
}

TruthComparison CompareWithNominal(const CalibrationResult& r,
                                   const std::vector<Eigen::Vector3d>& nominal,
                                   const std::vector<Eigen::Vector3d>& source_truth) {
  TruthComparison c;
  const int N = static_cast<int>(r.mic_positions_m.size());
  if (static_cast<int>(nominal.size()) != N || N < 2) return c;
  const int dim = r.dim == 3 ? 3 : 2;
  GaugeTransform g;
  if (r.dim != 1) g = GaugeFrameOf(nominal, dim, r.gauge_x, r.gauge_plane, r.gauge_z);
  else g.origin = nominal[0];
  c.available = true;
  double s2 = 0;
  for (int n = 0; n < N; ++n) {
    c.nominal_in_gauge_m.push_back(g.Apply(nominal[n]));
    const double e = (r.mic_positions_m[n] - c.nominal_in_gauge_m[n]).norm();
    c.error_m.push_back(e);
    if (n > 0) s2 += e * e;
  }
  c.position_rms_m = std::sqrt(s2 / (N - 1));
  if (!source_truth.empty() && source_truth.size() == r.source_positions_m.size()) {
    double ss = 0;
    for (size_t k = 0; k < source_truth.size(); ++k) {
      Eigen::Vector3d e = r.source_positions_m[k] - g.Apply(source_truth[k]);
      if (dim == 2) e.z() = 0;
      ss += e.squaredNorm();
    }
    c.source_rms_m = std::sqrt(ss / source_truth.size());
  }
  return c;
}

std::string TextReport(const CalibrationResult& r, const TruthComparison& c,
                       const SolverOptions& o) {
  std::ostringstream s;
  s << std::fixed;
  s << "microphone-array calibration (" << o.geometry << (o.synchronous ? ", synchronous" : "")
    << (o.estimate_drift ? "" : ", drift not estimated") << ")\n";
  const bool posed = r.bearing_span_deg >= 0;  // known array poses, static source
  if (posed) {
    const Eigen::Vector3d& src = r.source_positions_m.at(0);
    s << "known array poses, static source at (" << std::setprecision(3) << src.x() << ", "
      << src.y() << ", " << src.z() << ") m in the pose frame, std "
      << std::sqrt(std::max(0.0, r.source_cov.at(0).trace())) << " m; its bearing in the array "
      << "frame spans " << std::setprecision(1) << r.bearing_span_deg
      << " deg; microphone positions known (array frame)\n";
  }
  if (!posed) s << "gauge: mic 1 at origin";
  if (!posed && r.dim != 1) {
    s << ", mic " << r.gauge_x << " on +x, mic " << r.gauge_plane << " y > 0";
    if (r.dim == 3) s << " (z = 0), mic " << r.gauge_z << " z > 0";
  }
  if (!posed) s << "\n";
  s << "emissions " << r.tdoa_residual_s.rows() << ", starts tried " << r.starts.size()
    << " (best " << r.best_start + 1 << "), iterations " << r.iterations << " (all starts "
    << r.total_iterations << "), solve " << std::setprecision(3) << r.solve_time_s
    << " s, covariance " << r.covariance_time_s << " s, final cost " << std::setprecision(4)
    << r.final_cost << "\n";
  if (!r.converged)
    s << "NOT CONVERGED: the estimate below is where the solver stopped, not a solution\n";
  if (r.variance_factor > 1) {
    s << "std scaled by the residuals: variance factor " << std::setprecision(2)
      << r.variance_factor << " (residuals larger than the stated TDOA sigma)\n";
  }
  s << "TDOA residuals: rms " << std::setprecision(4) << r.residual_rms_s * 1e3 << " ms, std "
    << r.residual_std_s * 1e3 << " ms, max |r| " << r.residual_max_abs_s * 1e3 << " ms\n";
  s << "mic        x [m]     y [m]     z [m]   std [m]   tau [ms] std [ms]  delta [us/s] std";
  if (c.available) s << "   nominal x     y     z   err [m]";
  s << "\n";
  for (size_t n = 0; n < r.mic_positions_m.size(); ++n) {
    const auto& p = r.mic_positions_m[n];
    s << std::setw(3) << n + 1 << std::setprecision(4) << std::setw(10) << p.x() << std::setw(10)
      << p.y() << std::setw(10) << p.z() << std::setw(10)
      << std::sqrt(std::max(0.0, r.mic_position_cov[n].trace())) << std::setw(11)
      << r.start_offsets_s[n] * 1e3 << std::setw(9)
      << std::sqrt(std::max(0.0, r.clock_cov[n](0, 0))) * 1e3 << std::setw(12)
      << r.clock_drift[n] * 1e6 << std::setw(9)
      << std::sqrt(std::max(0.0, r.clock_cov[n](1, 1))) * 1e6;
    if (c.available) {
      const auto& q = c.nominal_in_gauge_m[n];
      s << std::setw(12) << q.x() << std::setw(8) << q.y() << std::setw(8) << q.z()
        << std::setw(10) << c.error_m[n];
    }
    s << "\n";
  }
  if (r.has_covariance && !o.synchronous && r.recording_end_s > 0) {
    const double t = r.recording_end_s;
    s << "clock correction std (worst mic): " << std::setprecision(4) << ClockStdAt(r, t) * 1e3
      << " ms at the last emission (t = " << std::setprecision(1) << t << " s), "
      << std::setprecision(4) << ClockStdAt(r, 2 * t) * 1e3
      << " ms at twice the recording's length (the drift is extrapolated beyond it)\n";
  }
  if (c.available) {
    s << "mic-position RMS error vs nominal (mics 2..N): " << std::setprecision(4)
      << c.position_rms_m << " m\n";
    if (c.source_rms_m >= 0) s << "source-position RMS error vs truth: " << c.source_rms_m << " m\n";
  }
  for (const auto& w : r.warnings) s << "warning: " << w << "\n";
  return s.str();
}

std::string JsonReport(const CalibrationResult& r, const TruthComparison& c,
                       const SolverOptions& o) {
  std::ostringstream s;
  s << "{\n  \"geometry\": \"" << o.geometry << "\", \"synchronous\": "
    << (o.synchronous ? "true" : "false") << ", \"estimate_drift\": "
    << (o.estimate_drift ? "true" : "false") << ",\n";
  s << "  \"gauge\": {\"ref\": 1, \"x\": " << r.gauge_x << ", \"plane\": " << r.gauge_plane
    << ", \"z\": " << r.gauge_z << "},\n";
  if (r.bearing_span_deg >= 0) {
    s << "  \"known_array_poses\": {\"bearing_span_deg\": " << Num(r.bearing_span_deg)
      << ", \"source_m\": [" << Num(r.source_positions_m.at(0).x()) << ", "
      << Num(r.source_positions_m.at(0).y()) << ", " << Num(r.source_positions_m.at(0).z())
      << "]},\n";
  }
  s << "  \"converged\": " << (r.converged ? "true" : "false")
    << ", \"variance_factor\": " << Num(r.variance_factor) << ",\n";
  s << "  \"num_emissions\": " << r.tdoa_residual_s.rows() << ", \"starts_tried\": "
    << r.starts.size() << ", \"best_start\": " << r.best_start + 1 << ", \"iterations\": "
    << r.iterations << ", \"total_iterations\": " << r.total_iterations
    << ", \"solve_time_s\": " << Num(r.solve_time_s) << ", \"covariance_time_s\": "
    << Num(r.covariance_time_s) << ", \"final_cost\": " << Num(r.final_cost) << ",\n";
  s << "  \"residual_rms_s\": " << Num(r.residual_rms_s) << ", \"residual_std_s\": "
    << Num(r.residual_std_s) << ", \"residual_max_abs_s\": " << Num(r.residual_max_abs_s)
    << ",\n";
  if (c.available) {
    s << "  \"position_rms_error_m\": " << Num(c.position_rms_m) << ",\n";
    if (c.source_rms_m >= 0) s << "  \"source_rms_error_m\": " << Num(c.source_rms_m) << ",\n";
  }
  s << "  \"mics\": [\n";
  for (size_t n = 0; n < r.mic_positions_m.size(); ++n) {
    const auto& p = r.mic_positions_m[n];
    const auto& cp = r.mic_position_cov[n];
    s << "    {\"mic\": " << n + 1 << ", \"position_m\": [" << Num(p.x()) << ", " << Num(p.y())
      << ", " << Num(p.z()) << "], \"position_cov_m2\": [";
    for (int i = 0; i < 9; ++i) s << (i ? ", " : "") << Num(cp(i / 3, i % 3));
    s << "], \"start_offset_s\": " << Num(r.start_offsets_s[n], 9)
      << ", \"start_offset_std_s\": " << Num(std::sqrt(std::max(0.0, r.clock_cov[n](0, 0))))
      << ", \"clock_drift\": " << Num(r.clock_drift[n], 9)
      << ", \"clock_drift_std\": " << Num(std::sqrt(std::max(0.0, r.clock_cov[n](1, 1))));
    if (c.available) {
      const auto& q = c.nominal_in_gauge_m[n];
      s << ", \"nominal_m\": [" << Num(q.x()) << ", " << Num(q.y()) << ", " << Num(q.z())
        << "], \"error_m\": " << Num(c.error_m[n]);
    }
    s << "}" << (n + 1 < r.mic_positions_m.size() ? "," : "") << "\n";
  }
  s << "  ],\n  \"residuals_s\": [\n";
  for (int k = 0; k < r.tdoa_residual_s.rows(); ++k) {
    s << "    [";
    for (int n = 0; n < r.tdoa_residual_s.cols(); ++n)
      s << (n ? ", " : "") << Num(r.tdoa_residual_s(k, n), 4);
    s << "]" << (k + 1 < r.tdoa_residual_s.rows() ? "," : "") << "\n";
  }
  s << "  ],\n  \"warnings\": [";
  for (size_t i = 0; i < r.warnings.size(); ++i) {
    std::string w = r.warnings[i];
    std::replace(w.begin(), w.end(), '"', '\'');
    s << (i ? ", " : "") << "\"" << w << "\"";
  }
  s << "]\n}\n";
  return s.str();
}

void WritePlot(const std::string& png_path, const CalibrationResult& r,
               const TruthComparison& c) {
  std::vector<Eigen::Vector2d> pts;
  for (const auto& p : r.mic_positions_m) pts.push_back(p.head<2>());
  for (const auto& p : r.source_positions_m) pts.push_back(p.head<2>());
  for (const auto& p : c.nominal_in_gauge_m) pts.push_back(p.head<2>());
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 0.2}) * 1.15;
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  const int size = 800, margin = 40;
  const double scale = (size - 2 * margin) / span;
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(size / 2 + (p.x() - mid.x()) * scale),
                     static_cast<int>(size / 2 - (p.y() - mid.y()) * scale));
  };
  cv::Mat img(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  // 0.1 m grid.
  for (double g = std::floor((mid.x() - span) * 10) / 10; g < mid.x() + span; g += 0.1) {
    cv::line(img, px({g, mid.y() - span}), px({g, mid.y() + span}), cv::Scalar(235, 235, 235), 1);
  }
  for (double g = std::floor((mid.y() - span) * 10) / 10; g < mid.y() + span; g += 0.1) {
    cv::line(img, px({mid.x() - span, g}), px({mid.x() + span, g}), cv::Scalar(235, 235, 235), 1);
  }
  for (size_t k = 1; k < r.source_positions_m.size(); ++k) {
    cv::line(img, px(r.source_positions_m[k - 1].head<2>()), px(r.source_positions_m[k].head<2>()),
             cv::Scalar(200, 160, 120), 1, cv::LINE_AA);
  }
  for (size_t n = 0; n < c.nominal_in_gauge_m.size(); ++n) {
    const cv::Point q = px(c.nominal_in_gauge_m[n].head<2>());
    cv::drawMarker(img, q, cv::Scalar(0, 150, 0), cv::MARKER_SQUARE, 14, 2);
  }
  for (size_t n = 0; n < r.mic_positions_m.size(); ++n) {
    const cv::Point p = px(r.mic_positions_m[n].head<2>());
    if (r.has_covariance) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(r.mic_position_cov[n].topLeftCorner<2, 2>());
      const Eigen::Vector2d ev = es.eigenvalues().cwiseMax(0.0);
      const Eigen::Vector2d v = es.eigenvectors().col(1);
      const double angle = std::atan2(-v.y(), v.x()) * 180 / M_PI;
      cv::ellipse(img, p,
                  cv::Size(std::max(1, static_cast<int>(2 * std::sqrt(ev[1]) * scale)),
                           std::max(1, static_cast<int>(2 * std::sqrt(ev[0]) * scale))),
                  angle, 0, 360, cv::Scalar(0, 0, 220), 1, cv::LINE_AA);
    }
    cv::drawMarker(img, p, cv::Scalar(0, 0, 220), cv::MARKER_CROSS, 14, 2);
    cv::putText(img, std::to_string(n + 1), p + cv::Point(8, -8), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  std::ostringstream title;
  title << std::fixed << std::setprecision(4) << "x-y: estimated (red, 2-sigma), nominal (green)";
  if (c.available) title << ", RMS " << c.position_rms_m << " m";
  title << ", residual std " << std::setprecision(3) << r.residual_std_s * 1e3 << " ms";
  cv::putText(img, title.str(), cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  if (!cv::imwrite(png_path, img)) throw std::runtime_error("cannot write " + png_path);
}

}  // namespace mic_calibrate
}  // namespace sarmap
