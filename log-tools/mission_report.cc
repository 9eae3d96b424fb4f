#include "log-tools/mission_report.h"

#include <sys/stat.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "common/decode.h"
#include "common/image_messages.h"
#include "log-tools/geotiff.h"
#include "log-tools/lcm_log_reader.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {

namespace {

std::string Fixed(double v, int digits);

template <class T>
bool Decode(const std::vector<uint8_t>& data, T* out) {
  return common::DecodeMessage(data.data(), data.size(), out);
}

}  // namespace

MissionData LoadMission(const std::string& log_path, std::vector<std::string>* problems,
                        const MissionMetricsOptions& metrics_options,
                        const common::AuthKey& bus_key) {
  MissionData data;
  data.metrics = MissionMetrics(metrics_options);
  data.log_path = log_path;
  LcmLogReader reader(log_path);
  LogEvent event;
  int64_t first_us = -1, last_us = 0;
  std::map<int64_t, Eigen::Vector2d> estimated_by_utime, truth_by_utime;
  // A hostile publisher's datagrams are in the log too: another type's message on a channel
  // and far-off stamps are skipped, as the nodes skip them live.
  LogMessageFilter filter;
  if (!bus_key.empty()) filter.SetBusKey(bus_key);
  while (reader.Next(&event)) {
    ++data.messages;
    if (first_us < 0) first_us = event.timestamp_us;
    last_us = std::max(last_us, event.timestamp_us);
    if (!filter.Accept(event)) continue;
    const std::string type = SarmapTypeName(event.data);
    if (type == "occupancy_grid_t" && event.channel == "SIM_FLOOR") {
      sarmap::occupancy_grid_t m;
      if (Decode(event.data, &m)) data.metrics.OnFloor(event.timestamp_us, m);
    } else if (type == "occupancy_grid_t") {
      sarmap::occupancy_grid_t m;
      if (Decode(event.data, &m)) {
        data.metrics.OnMap(event.timestamp_us, m);
        data.map = std::move(m);
      }
    } else if (type == "explore_status_t") {
      sarmap::explore_status_t m;
      if (Decode(event.data, &m)) data.metrics.OnExploreStatus(event.timestamp_us, m);
    } else if (type == "pose_t" && event.channel == "POSE") {
      sarmap::pose_t m;
      if (Decode(event.data, &m)) {
        estimated_by_utime[m.header.utime] = Eigen::Vector2d(m.position_m[0], m.position_m[1]);
        if (!data.has_start) {
          data.has_start = true;
          data.start_x_m = m.position_m[0];
          data.start_y_m = m.position_m[1];
          data.start_yaw_rad = 2 * std::atan2(m.orientation[3], m.orientation[0]);
        }
      }
      if (Decode(event.data, &m) &&
          (data.trail.empty() || std::hypot(data.trail.back().first - m.position_m[0],
                                            data.trail.back().second - m.position_m[1]) > 0.05)) {
        data.trail.emplace_back(m.position_m[0], m.position_m[1]);
      }
    } else if (type == "people_map_t") {
      sarmap::people_map_t m;
      if (Decode(event.data, &m)) {
        data.metrics.OnPeopleMap(event.timestamp_us, m);
        data.people = std::move(m);
      }
    } else if (type == "sound_map_t") {
      sarmap::sound_map_t m;
      if (Decode(event.data, &m)) data.sources = std::move(m);
    } else if (type == "sim_truth_t") {
      sarmap::sim_truth_t m;
      if (Decode(event.data, &m)) {
        data.metrics.OnTruth(event.timestamp_us, m);
        truth_by_utime[m.header.utime] =
            Eigen::Vector2d(m.robot_position_m[0], m.robot_position_m[1]);
        if (data.truth_trail.empty() ||
            std::hypot(data.truth_trail.back().first - m.robot_position_m[0],
                       data.truth_trail.back().second - m.robot_position_m[1]) > 0.05) {
          data.truth_trail.emplace_back(m.robot_position_m[0], m.robot_position_m[1]);
        }
        data.truth = std::move(m);
      }
    }
  }
  data.duration_s = first_us < 0 ? 0.0 : (last_us - first_us) * 1e-6;
  // Pair each truth sample with the estimate nearest in time (within 50 ms).
  for (const auto& [utime, truth] : truth_by_utime) {
    auto it = estimated_by_utime.lower_bound(utime);
    const Eigen::Vector2d* best = nullptr;
    int64_t best_dt = 50'000;
    for (auto c : {it, it == estimated_by_utime.begin() ? it : std::prev(it)}) {
      if (c == estimated_by_utime.end()) continue;
      if (std::llabs(c->first - utime) <= best_dt) {
        best_dt = std::llabs(c->first - utime);
        best = &c->second;
      }
    }
    if (best) data.matched_positions.emplace_back(*best, truth);
  }
  if (problems) {
    for (const auto& p : reader.problems()) {
      problems->push_back("log damaged at byte " + std::to_string(p.file_offset) + ": " + p.what);
    }
    if (!filter.Summary().empty()) problems->push_back(filter.Summary());
  }
  return data;
}

Eigen::Vector2d Alignment::Apply(const Eigen::Vector2d& truth) const {
  return Eigen::Rotation2Dd(yaw_rad) * truth + translation;
}

namespace {

// RMS of |map_from_truth(truth) - estimate| over the time-matched robot positions.
void TrailResidual(const MissionData& data, Alignment* a) {
  a->pairs = static_cast<int>(data.matched_positions.size());
  a->rms_m = TrailResidualRms(common::Rigid2d(a->translation, a->yaw_rad), data.matched_positions);
}

}  // namespace

Alignment AlignByStartPose(const MissionData& data) {
  Alignment a;
  if (!data.truth) return a;
  const common::Rigid2d map_from_truth =
      common::Rigid2d(data.truth->start_pose[0], data.truth->start_pose[1],
                      data.truth->start_pose[2])
          .inverse();
  a.method = "start pose";
  a.yaw_rad = map_from_truth.yaw_rad();
  a.translation = map_from_truth.translation();
  TrailResidual(data, &a);
  return a;
}

Alignment AlignTruth(const MissionData& data) {
  Alignment a;
  const auto& pairs = data.matched_positions;
  if (pairs.size() < 3) return a;
  a.method = "trail fit";
  // Kabsch in 2D: centre both sets, the rotation is atan2 of the cross/dot sums.
  Eigen::Vector2d mean_est = Eigen::Vector2d::Zero(), mean_truth = Eigen::Vector2d::Zero();
  for (const auto& [e, t] : pairs) {
    mean_est += e;
    mean_truth += t;
  }
  mean_est /= pairs.size();
  mean_truth /= pairs.size();
  // The rotation is undetermined when the robot hardly moved: its error grows as the position
  // noise over the trail's spread, so below kMinSpreadM the fit is not attempted.
  constexpr double kMinSpreadM = 0.5;
  double spread2 = 0;
  for (const auto& pair : pairs) spread2 += (pair.second - mean_truth).squaredNorm();
  if (std::sqrt(spread2 / pairs.size()) < kMinSpreadM) {
    a.method = "none (trail too short)";
    a.pairs = static_cast<int>(pairs.size());
    return a;
  }
  double dot = 0, cross = 0;
  for (const auto& [e, t] : pairs) {
    const Eigen::Vector2d de = e - mean_est, dt = t - mean_truth;
    dot += dt.dot(de);
    cross += dt.x() * de.y() - dt.y() * de.x();
  }
  a.yaw_rad = std::atan2(cross, dot);
  a.translation = mean_est - Eigen::Rotation2Dd(a.yaw_rad) * mean_truth;
  TrailResidual(data, &a);
  return a;
}

std::string HowFound(int cues) {
  const bool rgbd = cues & sarmap::mapped_person_t::CUE_SEEN_RGBD;
  const bool depth = cues & sarmap::mapped_person_t::CUE_SEEN_DEPTH;
  const bool heard = cues & sarmap::mapped_person_t::CUE_HEARD;
  std::string seen = rgbd ? "seen" : depth ? "seen (depth only)" : "";
  if (!seen.empty() && heard) return seen + " + heard";
  return heard ? "heard" : seen;
}

MapExtent ExtentOf(const MissionData& data) {
  MapExtent e;
  const auto grow = [&](double x, double y) {
    if (e.empty) {
      e = {false, x, y, x, y};
      return;
    }
    e.x0 = std::min(e.x0, x);
    e.y0 = std::min(e.y0, y);
    e.x1 = std::max(e.x1, x);
    e.y1 = std::max(e.y1, y);
  };
  if (data.map && data.map->width > 0 && data.map->height > 0) {
    const auto& m = *data.map;
    const double c = std::cos(m.origin_yaw_rad), sn = std::sin(m.origin_yaw_rad);
    for (const double u : {0.0, m.width * m.resolution_m}) {
      for (const double v : {0.0, m.height * m.resolution_m}) {
        grow(m.origin_x_m + c * u - sn * v, m.origin_y_m + sn * u + c * v);
      }
    }
  }
  for (const auto& p : data.trail) grow(p.first, p.second);
  if (!e.empty) {
    e.x0 -= kOutsideMapMarginM;
    e.y0 -= kOutsideMapMarginM;
    e.x1 += kOutsideMapMarginM;
    e.y1 += kOutsideMapMarginM;
  }
  return e;
}

std::string OutsideReason(const MapExtent& extent, const double* p, const double* cov,
                          double* std_m) {
  Eigen::Matrix2d P;
  P << cov[0], cov[1], cov[3], cov[4];
  const double largest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(0.5 * (P + P.transpose())).eigenvalues()(1);
  *std_m = std::sqrt(std::max(0.0, largest));
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !extent.Contains(p[0], p[1]))
    return "outside the map";
  if (!std::isfinite(*std_m) || *std_m > kUnlocalisedStdM)
    return "unconverged (std " + Fixed(*std_m, 1) + " m)";
  return "";
}

std::string SoundClassName(int sound_class) {
  static const char* kNames[] = {"unknown", "voice", "alarm", "machinery", "music"};
  return sound_class >= 0 && sound_class <= 4 ? kNames[sound_class] : "unknown";
}

std::vector<sarmap::mapped_person_t> PeopleOnMap(const MissionData& data,
                                                 const MissionSummary& summary) {
  std::vector<sarmap::mapped_person_t> out;
  if (!data.people) return out;
  for (const auto& p : data.people->people) {
    bool outside = false;
    for (const auto& o : summary.outside_map)
      outside = outside || (o.kind == "person" && o.id == p.id);
    if (!outside) out.push_back(p);
  }
  return out;
}

std::vector<sarmap::sound_source_t> SourcesOnMap(const MissionData& data,
                                                 const MissionSummary& summary) {
  std::vector<sarmap::sound_source_t> out;
  if (!data.sources) return out;
  for (const auto& src : data.sources->sources) {
    bool outside = false;
    for (const auto& o : summary.outside_map)
      outside = outside || (o.kind == "sound source" && o.id == src.id);
    if (!outside) out.push_back(src);
  }
  return out;
}

MissionSummary Summarise(const MissionData& data, double match_radius_m) {
  MissionSummary s;
  s.match_radius_m = match_radius_m;
  const MapExtent extent = ExtentOf(data);
  const auto check = [&](const std::string& kind, int64_t id, const double* p, const double* cov) {
    OutsideMap o;
    o.why = OutsideReason(extent, p, cov, &o.std_m);
    if (o.why.empty()) return;
    o.kind = kind;
    o.id = id;
    o.x_m = p[0];
    o.y_m = p[1];
    s.outside_map.push_back(o);
  };
  if (data.people) {
    for (const auto& p : data.people->people) check("person", p.id, p.position_m, p.covariance);
  }
  if (data.sources) {
    for (const auto& src : data.sources->sources) {
      if (!src.has_position) {
        // A bearing: position_m is where it was heard from, not the source.
        OutsideMap o;
        o.kind = "sound source";
        o.id = src.id;
        o.x_m = src.position_m[0];
        o.y_m = src.position_m[1];
        o.std_m = INFINITY;
        char why[160];
        snprintf(why, sizeof(why),
                 "%s heard at bearing %.0f deg from here, range not yet observable",
                 SoundClassName(src.sound_class).c_str(), src.bearing_rad * 180 / M_PI);
        o.why = why;
        s.outside_map.push_back(o);
        continue;
      }
      check("sound source", src.id, src.position_m, src.covariance);
    }
  }
  s.people_found = static_cast<int>(PeopleOnMap(data, s).size());
  s.sources_mapped = static_cast<int>(SourcesOnMap(data, s).size());
  s.metrics = data.metrics.Result();
  if (!data.truth) return s;
  s.alignment = AlignByStartPose(data);
  s.trail_fit = AlignTruth(data);
  const auto& truth = data.truth->people;
  std::vector<Eigen::Vector2d> truth_xy;
  for (const auto& t : truth)
    truth_xy.push_back(s.alignment.Apply(Eigen::Vector2d(t.position_m[0], t.position_m[1])));
  const std::vector<sarmap::mapped_person_t> found = PeopleOnMap(data, s);
  std::vector<double> error;
  const std::vector<int> truth_to = MatchPeople(truth_xy, found, match_radius_m, &error);
  std::vector<int> found_used(found.size(), 0);
  for (int f : truth_to) {
    if (f >= 0) found_used[f] = 1;
  }
  for (size_t t = 0; t < truth.size(); ++t) {
    TruthMatch m;
    m.truth_id = truth[t].id;
    m.name = truth[t].name;
    m.x_m = truth_xy[t].x();  // in the estimated map frame
    m.y_m = truth_xy[t].y();
    if (truth_to[t] >= 0) {
      const auto& p = found[truth_to[t]];
      m.found = true;
      m.person_id = p.id;
      m.how = HowFound(p.cues);
      m.error_m = error[t];
    }
    for (const auto& o : s.metrics.people) {
      if (o.truth_id != m.truth_id) continue;
      if (m.found) m.found_after_s = o.found_after_s;
      m.dropped = !m.found && (o.found || o.dropped);
    }
    s.truth.push_back(m);
  }
  for (size_t f = 0; f < found.size(); ++f) s.false_positives += found_used[f] ? 0 : 1;
  // Sound sources: every simulated emitter against the placed sources, nearest pairs first.
  const std::vector<sarmap::sound_source_t> placed = SourcesOnMap(data, s);
  const auto& emitters = data.truth->sources;
  struct Pair {
    double d;
    size_t t, m;
  };
  std::vector<Pair> pairs;
  std::vector<Eigen::Vector2d> emitter_xy;
  for (const auto& e : emitters)
    emitter_xy.push_back(s.alignment.Apply(Eigen::Vector2d(e.position_m[0], e.position_m[1])));
  for (size_t t = 0; t < emitters.size(); ++t)
    for (size_t m = 0; m < placed.size(); ++m) {
      const double d =
          (emitter_xy[t] - Eigen::Vector2d(placed[m].position_m[0], placed[m].position_m[1]))
              .norm();
      if (d <= match_radius_m) pairs.push_back({d, t, m});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<int> emitter_to(emitters.size(), -1), placed_used(placed.size(), 0);
  std::vector<double> emitter_error(emitters.size(), 0);
  for (const Pair& p : pairs) {
    if (emitter_to[p.t] >= 0 || placed_used[p.m]) continue;
    emitter_to[p.t] = static_cast<int>(p.m);
    emitter_error[p.t] = p.d;
    placed_used[p.m] = 1;
  }
  for (size_t t = 0; t < emitters.size(); ++t) {
    SourceTruthMatch m;
    m.name = emitters[t].name;
    const int8_t k = emitters[t].kind;
    m.kind = k == sarmap::sim_sound_source_t::KIND_VOICE   ? "voice"
             : k == sarmap::sim_sound_source_t::KIND_MUSIC ? "music"
             : k == sarmap::sim_sound_source_t::KIND_ALARM ? "alarm"
                                                           : "noise";
    m.x_m = emitter_xy[t].x();
    m.y_m = emitter_xy[t].y();
    if (emitter_to[t] >= 0) {
      const auto& src = placed[emitter_to[t]];
      m.found = true;
      m.source_id = src.id;
      m.error_m = emitter_error[t];
      m.mapped_class = SoundClassName(src.sound_class);
      m.is_person = src.is_person;
      m.class_right = m.mapped_class == (m.kind == "noise" ? "machinery" : m.kind);
      if (m.is_person && m.kind != "voice") ++s.non_voice_people;
    }
    s.source_truth.push_back(m);
  }
  return s;
}

namespace {

// Map frame -> image pixels (the grid drawn at `scale` pixels per cell, y up).
struct Canvas {
  cv::Mat image;
  double x0 = 0, y0 = 0, pixels_per_m = 40;
  cv::Point P(double x, double y) const {
    // Clamped far outside the image (drawing clips there) before the conversion to int.
    const auto pixel = [](double v) {
      return static_cast<int>(std::lround(std::isfinite(v) ? std::clamp(v, -1e6, 1e6) : -1e6));
    };
    return cv::Point(pixel((x - x0) * pixels_per_m),
                     pixel(image.rows - 1 - (y - y0) * pixels_per_m));
  }
};

void DrawEllipse(Canvas* c, double x, double y, const double (&cov)[9], const cv::Scalar& colour) {
  Eigen::Matrix2d P;
  P << cov[0], cov[1], cov[3], cov[4];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (P + P.transpose()));
  const Eigen::Vector2d v = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  const double angle_deg = -std::atan2(axis.y(), axis.x()) * 180 / M_PI;
  // Axes beyond a few image sizes look the same and would overflow the rasteriser.
  const double max_axis_px = 4.0 * std::max(c->image.cols, c->image.rows);
  const auto axis_px = [&](double variance) {
    return std::max(
        2, static_cast<int>(std::min(max_axis_px, 3 * std::sqrt(variance) * c->pixels_per_m)));
  };
  const cv::Size axes(axis_px(v(1)), axis_px(v(0)));
  cv::ellipse(c->image, c->P(x, y), axes, angle_deg, 0, 360, colour, 2, cv::LINE_AA);
}

Canvas RenderMap(const MissionData& data, const MissionSummary& summary) {
  Canvas c;
  // Sources and people far outside the map or unconverged (summary.outside_map) are listed
  // apart and never drawn: an estimate hundreds of metres away would shrink the map to a speck.
  const std::vector<sarmap::mapped_person_t> people = PeopleOnMap(data, summary);
  const std::vector<sarmap::sound_source_t> sources = SourcesOnMap(data, summary);
  // Extent: the grid, else everything drawn, with a margin.
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  const auto grow = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x0 = std::min(x0, x - 1);
    y0 = std::min(y0, y - 1);
    x1 = std::max(x1, x + 1);
    y1 = std::max(y1, y + 1);
  };
  std::vector<uint8_t> cells;
  if (data.map) {
    const auto& m = *data.map;
    grow(m.origin_x_m + 1, m.origin_y_m + 1);
    grow(m.origin_x_m + m.width * m.resolution_m - 1, m.origin_y_m + m.height * m.resolution_m - 1);
    std::string error;
    std::vector<int8_t> decoded;
    if (common::DecodeOccupancyGrid(m, &decoded, &error))
      cells.assign(decoded.begin(), decoded.end());
  }
  const std::vector<Eigen::Vector2d> unmapped = data.metrics.UnmappedFloorInMap();
  for (const auto& p : unmapped) grow(p.x(), p.y());
  const auto& explore = data.metrics.last_explore_status();
  if (explore) {
    for (int i = 0; i < explore->num_path; ++i) grow(explore->path_x_m[i], explore->path_y_m[i]);
    if (explore->has_goal) grow(explore->goal_m[0], explore->goal_m[1]);
  }
  for (const auto& p : data.trail) grow(p.first, p.second);
  for (const auto& p : people) grow(p.position_m[0], p.position_m[1]);
  for (const auto& t : summary.truth) grow(t.x_m, t.y_m);
  if (x0 > x1) {
    x0 = y0 = -5;
    x1 = y1 = 5;
  }
  for (const auto& s : sources) grow(s.position_m[0], s.position_m[1]);
  c.x0 = x0;
  c.y0 = y0;
  // At most kMaxPixels a side, whatever the extent (a damaged message's coordinates may be
  // anywhere a double reaches).
  constexpr double kMaxPixels = 4000;
  const double extent_m = std::max(x1 - x0, y1 - y0);
  c.pixels_per_m = std::clamp(1400.0 / extent_m, 5.0, 100.0);
  if (extent_m * c.pixels_per_m > kMaxPixels) c.pixels_per_m = kMaxPixels / extent_m;
  const auto side = [&](double metres) {
    const double pixels = metres * c.pixels_per_m;
    return std::isfinite(pixels) ? static_cast<int>(std::clamp(pixels, 0.0, kMaxPixels)) + 1 : 1;
  };
  c.image = cv::Mat(side(y1 - y0), side(x1 - x0), CV_8UC3, cv::Scalar(60, 60, 60));
  if (data.map && !cells.empty()) {
    const auto& m = *data.map;
    for (int gy = 0; gy < m.height; ++gy) {
      for (int gx = 0; gx < m.width; ++gx) {
        const int8_t v = static_cast<int8_t>(cells[static_cast<size_t>(gy) * m.width + gx]);
        const uint8_t g = v < 0 ? 205 : static_cast<uint8_t>(255 - v * 255 / 100);
        const double x = m.origin_x_m + gx * m.resolution_m, y = m.origin_y_m + gy * m.resolution_m;
        cv::rectangle(c.image, c.P(x, y + m.resolution_m), c.P(x + m.resolution_m, y),
                      cv::Scalar(g, g, g), cv::FILLED);
      }
    }
  }
  const cv::Scalar orange(34, 126, 230), cyan(200, 200, 0);
  if (!unmapped.empty()) {
    // The reachable floor SLAM never observed, half-transparent over the map: each floor cell
    // drawn as its square, turned by the floor's yaw in the map frame.
    cv::Mat overlay = c.image.clone();
    const double h = 0.5 * data.metrics.floor_resolution_m();
    const Eigen::Rotation2Dd r(data.metrics.floor_yaw_in_map_rad());
    const Eigen::Vector2d corners[4] = {r * Eigen::Vector2d(-h, -h), r * Eigen::Vector2d(h, -h),
                                        r * Eigen::Vector2d(h, h), r * Eigen::Vector2d(-h, h)};
    for (const auto& p : unmapped) {
      cv::Point poly[4];
      for (int k = 0; k < 4; ++k) poly[k] = c.P(p.x() + corners[k].x(), p.y() + corners[k].y());
      cv::fillConvexPoly(overlay, poly, 4, orange);
    }
    cv::addWeighted(overlay, 0.55, c.image, 0.45, 0.0, c.image);
  }
  for (size_t i = 1; i < data.truth_trail.size(); ++i) {
    const Eigen::Vector2d a =
        summary.alignment.Apply({data.truth_trail[i - 1].first, data.truth_trail[i - 1].second});
    const Eigen::Vector2d b =
        summary.alignment.Apply({data.truth_trail[i].first, data.truth_trail[i].second});
    cv::line(c.image, c.P(a.x(), a.y()), c.P(b.x(), b.y()), cv::Scalar(160, 160, 160), 1,
             cv::LINE_AA);
  }
  for (size_t i = 1; i < data.trail.size(); ++i) {
    cv::line(c.image, c.P(data.trail[i - 1].first, data.trail[i - 1].second),
             c.P(data.trail[i].first, data.trail[i].second), cv::Scalar(182, 89, 155), 2,
             cv::LINE_AA);
  }
  if (explore) {  // the explorer's last plan: path and goal
    for (int i = 1; i < explore->num_path; ++i) {
      cv::line(c.image, c.P(explore->path_x_m[i - 1], explore->path_y_m[i - 1]),
               c.P(explore->path_x_m[i], explore->path_y_m[i]), cyan, 2, cv::LINE_AA);
    }
    if (explore->has_goal) {
      cv::drawMarker(c.image, c.P(explore->goal_m[0], explore->goal_m[1]), cyan, cv::MARKER_STAR,
                     18, 2);
    }
  }
  const cv::Scalar blue(219, 152, 52), red(60, 76, 231), green(113, 204, 46), yellow(15, 196, 241);
  for (const auto& s : sources) {
    DrawEllipse(&c, s.position_m[0], s.position_m[1], s.covariance, blue);
    cv::drawMarker(c.image, c.P(s.position_m[0], s.position_m[1]), blue, cv::MARKER_SQUARE, 10, 2);
  }
  for (const auto& t : summary.truth) {  // true people: hollow diamonds
    cv::drawMarker(c.image, c.P(t.x_m, t.y_m), cv::Scalar(0, 0, 0), cv::MARKER_DIAMOND, 22, 2);
  }
  {
    for (const auto& p : people) {
      const bool heard = p.cues & sarmap::mapped_person_t::CUE_HEARD;
      const bool seen = p.cues & (sarmap::mapped_person_t::CUE_SEEN_RGBD |
                                  sarmap::mapped_person_t::CUE_SEEN_DEPTH);
      const cv::Scalar colour = seen && heard ? yellow : heard ? red : green;
      if (heard) DrawEllipse(&c, p.position_m[0], p.position_m[1], p.covariance, colour);
      cv::circle(c.image, c.P(p.position_m[0], p.position_m[1]), 8, colour, cv::FILLED,
                 cv::LINE_AA);
      cv::circle(c.image, c.P(p.position_m[0], p.position_m[1]), 8, cv::Scalar(0, 0, 0), 1,
                 cv::LINE_AA);
      const std::string label =
          "#" + std::to_string(p.id) + (p.keyword.empty() ? "" : " \"" + p.keyword + "\"");
      const cv::Point at = c.P(p.position_m[0], p.position_m[1]) + cv::Point(11, -9);
      cv::putText(c.image, label, at, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 3,
                  cv::LINE_AA);
      cv::putText(c.image, label, at, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(255, 255, 255), 1,
                  cv::LINE_AA);
    }
  }
  // Legend (on a dark panel) and scale bar.
  std::vector<std::pair<std::string, cv::Scalar>> legend = {
      {"seen", green},
      {"heard (3-sigma)", red},
      {"seen + heard", yellow},
      {"sound source (3-sigma)", blue},
      {"true person (simulator)", cv::Scalar(0, 0, 0)},
      {"robot path", cv::Scalar(182, 89, 155)}};
  if (!unmapped.empty()) legend.emplace_back("reachable, not mapped", orange);
  if (explore && (explore->num_path > 0 || explore->has_goal))
    legend.emplace_back("last explore path, goal", cyan);
  cv::rectangle(c.image, cv::Point(4, 4), cv::Point(240, 16 + 20 * static_cast<int>(legend.size())),
                cv::Scalar(45, 45, 45), cv::FILLED);
  int y = 24;
  for (const auto& [text, colour] : legend) {
    cv::rectangle(c.image, cv::Point(10, y - 12), cv::Point(24, y + 2), colour, cv::FILLED);
    cv::putText(c.image, text, cv::Point(30, y), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0),
                3, cv::LINE_AA);
    cv::putText(c.image, text, cv::Point(30, y), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    y += 20;
  }
  const int bar = static_cast<int>(c.pixels_per_m);
  cv::rectangle(c.image, cv::Point(4, c.image.rows - 28), cv::Point(bar + 50, c.image.rows - 4),
                cv::Scalar(45, 45, 45), cv::FILLED);
  cv::line(c.image, cv::Point(10, c.image.rows - 15), cv::Point(10 + bar, c.image.rows - 15),
           cv::Scalar(255, 255, 255), 3);
  cv::putText(c.image, "1 m", cv::Point(14 + bar, c.image.rows - 10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  if (!summary.outside_map.empty()) {
    const std::string note = std::to_string(summary.outside_map.size()) +
                             " unconverged or far outside the map: listed in the report, not drawn";
    cv::putText(c.image, note, cv::Point(bar + 70, c.image.rows - 10), cv::FONT_HERSHEY_SIMPLEX,
                0.5, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return c;
}

std::string Html(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch == '<')
      out += "&lt;";
    else if (ch == '>')
      out += "&gt;";
    else if (ch == '&')
      out += "&amp;";
    else
      out += ch;
  }
  return out;
}

nlohmann::json Json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::string Fixed(double v, int digits) {
  char text[64];
  snprintf(text, sizeof(text), "%.*f", digits, v);
  return text;
}

// Explored area against time: mapped reachable floor (m^2) per coverage point, the reachable
// area as a dashed ceiling. Axes from 0 to the last time and to the reachable area.
cv::Mat CoveragePlot(const MissionMetricsResult& m) {
  const int width = 900, height = 380, left = 70, right = 20, top = 45, bottom = 50;
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  double t_max = std::max(1.0, m.mission_s), a_max = m.reachable_m2.value_or(0);
  for (const auto& p : m.coverage) {
    t_max = std::max(t_max, p.time_s);
    a_max = std::max(a_max, p.mapped_m2);
  }
  if (a_max <= 0) a_max = 1;
  const double a_top = 1.05 * a_max;
  const auto P = [&](double t, double a) {
    return cv::Point(
        left + static_cast<int>(std::lround(t / t_max * (width - left - right))),
        height - bottom - static_cast<int>(std::lround(a / a_top * (height - top - bottom))));
  };
  const cv::Scalar grey(200, 200, 200), black(0, 0, 0), line(182, 89, 155), orange(34, 126, 230);
  const auto text = [&](const std::string& s, cv::Point at, const cv::Scalar& colour) {
    cv::putText(image, s, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, colour, 1, cv::LINE_AA);
  };
  for (int k = 0; k <= 5; ++k) {
    const double t = t_max * k / 5, a = a_max * k / 5;
    cv::line(image, P(t, 0), P(t, a_top), grey, 1);
    cv::line(image, P(0, a), P(t_max, a), grey, 1);
    text(Fixed(t, t_max >= 10 ? 0 : 1), P(t, 0) + cv::Point(-10, 20), black);
    text(Fixed(a, a_max >= 10 ? 0 : 1), P(0, a) + cv::Point(-55, 5), black);
  }
  text("time since the first truth (s)", cv::Point(width / 2 - 110, height - 10), black);
  text("mapped reachable floor (m2)", cv::Point(left, 20), black);
  if (m.reachable_m2) {  // dashed
    for (int k = 0; k < 60; ++k) {
      cv::line(image, P(t_max * k / 60, *m.reachable_m2),
               P(t_max * (k + 0.5) / 60, *m.reachable_m2), orange, 2);
    }
    text("reachable " + Fixed(*m.reachable_m2, 1) + " m2",
         P(t_max, *m.reachable_m2) + cv::Point(-150, 18), orange);
  }
  std::vector<cv::Point> points;
  for (const auto& p : m.coverage) points.push_back(P(p.time_s, p.mapped_m2));
  if (points.size() >= 2) cv::polylines(image, points, false, line, 2, cv::LINE_AA);
  for (const auto& p : points) cv::circle(image, p, 3, line, cv::FILLED, cv::LINE_AA);
  cv::rectangle(image, P(0, 0), P(t_max, a_top), black, 1);
  return image;
}

std::string Seconds(const std::optional<double>& v) { return v ? Fixed(*v, 1) + " s" : "—"; }

}  // namespace

std::string SummaryText(const MissionData& data, const MissionSummary& summary) {
  std::ostringstream out;
  char line[256];
  snprintf(line, sizeof(line),
           "mission: %.1f s, %lld messages; %d people on the map, %d sound sources\n",
           data.duration_s, static_cast<long long>(data.messages), summary.people_found,
           summary.sources_mapped);
  out << line;
  {
    for (const auto& p : PeopleOnMap(data, summary)) {
      snprintf(line, sizeof(line), "  person #%lld at (%.2f, %.2f) m, %s, confidence %.0f%%%s\n",
               static_cast<long long>(p.id), p.position_m[0], p.position_m[1],
               HowFound(p.cues).c_str(), 100.0 * p.confidence,
               p.keyword.empty() ? "" : (", said \"" + p.keyword + "\"").c_str());
      out << line;
    }
  }
  for (const auto& src : SourcesOnMap(data, summary)) {
    snprintf(line, sizeof(line), "  sound source #%lld at (%.2f, %.2f) m: %s%s\n",
             static_cast<long long>(src.id), src.position_m[0], src.position_m[1],
             SoundClassName(src.sound_class).c_str(),
             src.is_person
                 ? (src.priority == sarmap::sound_source_t::PRIORITY_CALL ? ", person, calling"
                                                                          : ", person")
                 : "");
    out << line;
  }
  if (!summary.source_truth.empty()) {
    int placed = 0, right = 0;
    for (const auto& m : summary.source_truth) {
      placed += m.found;
      right += m.found && m.class_right;
      snprintf(line, sizeof(line), "  emitter %s (%s): %s\n", m.name.c_str(), m.kind.c_str(),
               m.found ? ("placed " + Fixed(m.error_m, 2) + " m off as " + m.mapped_class +
                          (m.class_right ? "" : " (wrong class)") + (m.is_person ? ", person" : ""))
                             .c_str()
                       : "not placed");
      out << line;
    }
    snprintf(
        line, sizeof(line),
        "sound sources: %d of %zu emitters placed within %.2f m, %d of them with the right class, "
        "%d non-voice marked a person\n",
        placed, summary.source_truth.size(), summary.match_radius_m, right,
        summary.non_voice_people);
    out << line;
  }
  if (!summary.outside_map.empty()) {
    out << "unconverged or far outside the map (not counted as found):\n";
    for (const auto& o : summary.outside_map) {
      snprintf(line, sizeof(line), "  %s #%lld at (%.1f, %.1f) m, std %.3g m: %s\n", o.kind.c_str(),
               static_cast<long long>(o.id), o.x_m, o.y_m, o.std_m, o.why.c_str());
      out << line;
    }
  }
  if (!summary.truth.empty()) {
    int found = 0;
    for (const auto& t : summary.truth) found += t.found;
    snprintf(line, sizeof(line),
             "against the simulator's truth: %d of %zu people found within %.2f m, %d false\n",
             found, summary.truth.size(), summary.match_radius_m, summary.false_positives);
    out << line;
    snprintf(line, sizeof(line),
             "  (truth aligned to the map by the start pose; robot trail residual %.3f m RMS over "
             "%d positions%s)\n",
             summary.alignment.rms_m, summary.alignment.pairs,
             summary.trail_fit.method != "trail fit"
                 ? ""
                 : (", " + Fixed(summary.trail_fit.rms_m, 3) + " m with a trail fit").c_str());
    out << line;
    for (const auto& t : summary.truth) {
      if (t.found) {
        snprintf(line, sizeof(line), "  %-12s FOUND  %-22s error %.2f m%s\n", t.name.c_str(),
                 t.how.c_str(), t.error_m,
                 t.found_after_s ? (", after " + Fixed(*t.found_after_s, 1) + " s").c_str() : "");
      } else {
        snprintf(line, sizeof(line), "  %-12s MISSED at (%.2f, %.2f)%s\n", t.name.c_str(), t.x_m,
                 t.y_m, t.dropped ? " (found earlier, no longer on the map)" : "");
      }
      out << line;
    }
  }
  const MissionMetricsResult& m = summary.metrics;
  if (m.have_truth) {
    snprintf(line, sizeof(line),
             "mission metrics: %.1f s since the first truth, %.2f m driven, %d collisions\n",
             m.mission_s, m.distance_m, m.collisions);
    out << line;
    if (m.mapped_m2) {
      snprintf(line, sizeof(line),
               "  coverage: %.1f of %.1f m2 of reachable floor mapped (%.0f%%)\n", *m.mapped_m2,
               *m.reachable_m2, 100.0 * *m.mapped_fraction);
    } else {
      snprintf(line, sizeof(line),
               "  coverage: not measured (needs SIM_FLOOR, SIM_TRUTH and MAP)\n");
    }
    out << line;
    if (m.stuck_s) {
      snprintf(line, sizeof(line),
               "  stuck: %.1f s in total, longest %.1f s; longest going nowhere: %.1f s\n",
               *m.stuck_s, *m.longest_stuck_s, *m.longest_confined_s);
    } else {
      snprintf(line, sizeof(line), "  stuck: not judged (no EXPLORE_STATUS)\n");
    }
    out << line;
    if (m.came_home) {
      snprintf(line, sizeof(line), "  came home after %.1f s\n", *m.home_after_s);
    } else {
      std::string why;
      if (!m.last_explore_state.empty()) why = "last state: " + m.last_explore_state;
      if (m.home_error_m) {
        char error[64];
        snprintf(error, sizeof(error), "%sended %.2f m from the start", why.empty() ? "" : ", ",
                 *m.home_error_m);
        why += error;
      }
      snprintf(line, sizeof(line), "  did not come home%s\n",
               why.empty() ? "" : (" (" + why + ")").c_str());
    }
    out << line;
  }
  return out.str();
}

void WriteReport(const MissionData& data, const MissionSummary& summary,
                 const std::string& directory) {
  mkdir(directory.c_str(), 0755);
  const Canvas canvas = RenderMap(data, summary);
  if (!cv::imwrite(directory + "/map.png", canvas.image)) {
    throw std::runtime_error(directory + "/map.png: cannot write");
  }
  // The GeoTIFF needs a map whose cells decode (a damaged one is still drawn, blank, in the PNG).
  std::vector<int8_t> map_cells;
  std::string map_error;
  const bool geotiff = data.map && data.map->width > 0 && data.map->height > 0 &&
                       data.map->resolution_m > 0 &&
                       common::DecodeOccupancyGrid(*data.map, &map_cells, &map_error);
  if (geotiff) WriteGeoTiff(data, summary, directory + "/map.tif");
  const bool wrote_plot = !summary.metrics.coverage.empty();
  if (wrote_plot && !cv::imwrite(directory + "/coverage.png", CoveragePlot(summary.metrics))) {
    throw std::runtime_error(directory + "/coverage.png: cannot write");
  }
  nlohmann::json j;
  j["log"] = data.log_path;
  j["duration_s"] = data.duration_s;
  j["messages"] = data.messages;
  j["people"] = nlohmann::json::array();
  {
    for (const auto& p : PeopleOnMap(data, summary)) {
      j["people"].push_back({{"id", p.id},
                             {"x_m", p.position_m[0]},
                             {"y_m", p.position_m[1]},
                             {"z_m", p.position_m[2]},
                             {"covariance", std::vector<double>(p.covariance, p.covariance + 9)},
                             {"confidence", p.confidence},
                             {"how", HowFound(p.cues)},
                             {"keyword", p.keyword},
                             {"count", p.people_count},
                             {"detections", p.num_detections},
                             {"sound_source_id", p.sound_source_id}});
    }
  }
  j["sound_sources"] = nlohmann::json::array();
  {
    for (const auto& s : SourcesOnMap(data, summary)) {
      j["sound_sources"].push_back(
          {{"id", s.id},
           {"x_m", s.position_m[0]},
           {"y_m", s.position_m[1]},
           {"z_m", s.position_m[2]},
           {"covariance", std::vector<double>(s.covariance, s.covariance + 9)},
           {"converged", s.state == sarmap::sound_source_t::STATE_CONVERGED},
           {"is_person", s.is_person},
           {"sound_class", SoundClassName(s.sound_class)},
           {"class_confidence", s.class_confidence},
           {"calling", s.priority == sarmap::sound_source_t::PRIORITY_CALL}});
    }
  }
  j["path_m"] = nlohmann::json::array();  // the robot's path (POSE, points 5 cm apart)
  for (const auto& p : data.trail) j["path_m"].push_back({p.first, p.second});
  j["outside_map"] = nlohmann::json::array();
  for (const auto& o : summary.outside_map) {
    j["outside_map"].push_back({{"kind", o.kind},
                                {"id", o.id},
                                {"x_m", o.x_m},
                                {"y_m", o.y_m},
                                {"std_m", o.std_m},
                                {"why", o.why}});
  }
  j["files"] = {{"map_png", "map.png"},
                {"geotiff", geotiff ? nlohmann::json("map.tif") : nlohmann::json(nullptr)},
                {"json", "report.json"}};
  if (!summary.truth.empty()) {
    j["truth"] = nlohmann::json::array();
    for (const auto& t : summary.truth) {
      j["truth"].push_back({{"id", t.truth_id},
                            {"name", t.name},
                            {"x_m", t.x_m},
                            {"y_m", t.y_m},
                            {"found", t.found},
                            {"found_after_s", Json(t.found_after_s)},
                            {"dropped", t.dropped},
                            {"person_id", t.person_id},
                            {"how", t.how},
                            {"error_m", t.error_m}});
    }
    j["false_positives"] = summary.false_positives;
    j["sound_source_truth"] = nlohmann::json::array();
    for (const auto& m : summary.source_truth)
      j["sound_source_truth"].push_back({{"name", m.name},
                                         {"kind", m.kind},
                                         {"x_m", m.x_m},
                                         {"y_m", m.y_m},
                                         {"found", m.found},
                                         {"source_id", m.source_id},
                                         {"error_m", m.error_m},
                                         {"mapped_class", m.mapped_class},
                                         {"class_right", m.class_right},
                                         {"is_person", m.is_person}});
    j["non_voice_people"] = summary.non_voice_people;
    const Alignment& fit = summary.trail_fit;
    j["alignment"] = {{"method", summary.alignment.method},
                      {"yaw_rad", summary.alignment.yaw_rad},
                      {"x_m", summary.alignment.translation.x()},
                      {"y_m", summary.alignment.translation.y()},
                      {"pairs", summary.alignment.pairs},
                      {"trail_rms_m", summary.alignment.rms_m},
                      {"trail_fit",
                       {{"method", fit.method},
                        {"yaw_rad", fit.yaw_rad},
                        {"x_m", fit.translation.x()},
                        {"y_m", fit.translation.y()},
                        {"rms_m", fit.rms_m}}}};
    j["match_radius_m"] = summary.match_radius_m;
  }
  // Mission metrics (mission_metrics.h); null where the log cannot tell.
  const MissionMetricsResult& m = summary.metrics;
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& p : m.coverage) curve.push_back({p.time_s, p.mapped_m2, p.fraction});
  j["coverage"] = {{"reachable_m2", Json(m.reachable_m2)},
                   {"mapped_m2", Json(m.mapped_m2)},
                   {"mapped_fraction", Json(m.mapped_fraction)},
                   {"curve", curve}};
  const auto truth_or_null = [&](const nlohmann::json& v) {
    return m.have_truth ? v : nlohmann::json(nullptr);
  };
  j["mission_s"] = truth_or_null(m.mission_s);
  j["distance_m"] = truth_or_null(m.distance_m);
  j["collisions"] = truth_or_null(m.collisions);
  j["stuck_s"] = Json(m.stuck_s);
  j["longest_stuck_s"] = Json(m.longest_stuck_s);
  j["longest_confined_s"] = Json(m.longest_confined_s);
  j["came_home"] = truth_or_null(m.came_home);
  j["home_after_s"] = Json(m.home_after_s);
  j["home_error_m"] = Json(m.home_error_m);
  j["explore_state"] =
      m.last_explore_state.empty() ? nlohmann::json(nullptr) : nlohmann::json(m.last_explore_state);
  std::ofstream(directory + "/report.json") << j.dump(2) << "\n";

  std::ofstream html(directory + "/report.html");
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>sarmap mission "
          "report</title><style>"
          "body{font:15px "
          "system-ui,sans-serif;margin:2em;max-width:1100px}table{border-collapse:collapse}"
          "td,th{padding:.25em .8em;border-bottom:1px solid "
          "#ddd;text-align:left}.missed{color:#c0392b}"
          ".found{color:#1e8449}img{max-width:100%;border:1px solid #ccc}</style></head><body>"
       << "<h1>sarmap mission report</h1><p>Log <code>" << Html(data.log_path)
       << "</code>: " << static_cast<int>(data.duration_s) << " s, " << data.messages
       << " messages. <b>" << summary.people_found << "</b> people and <b>"
       << summary.sources_mapped << "</b> sound sources on the map.</p>";
  if (!summary.truth.empty()) {
    int found = 0;
    for (const auto& t : summary.truth) found += t.found;
    html << "<h2>Found versus the simulator's truth</h2><p>" << found << " of "
         << summary.truth.size() << " people found within " << summary.match_radius_m << " m; "
         << summary.false_positives
         << " reported people match nobody.</p><table><tr><th>person</th><th>true position "
            "(m)</th><th>result</th>"
            "<th>how</th><th>error (m)</th></tr>";
    for (const auto& t : summary.truth) {
      char pos[64], err[32];
      snprintf(pos, sizeof(pos), "%.2f, %.2f", t.x_m, t.y_m);
      snprintf(err, sizeof(err), "%.2f", t.error_m);
      html << "<tr><td>" << Html(t.name) << "</td><td>" << pos << "</td><td class=\""
           << (t.found ? "found\">found" : "missed\">missed") << "</td><td>" << Html(t.how)
           << "</td><td>" << (t.found ? err : "") << "</td></tr>";
    }
    html << "</table>";
  }
  if (m.have_truth) {
    html << "<h2>Mission</h2><table>"
         << "<tr><th>duration (since the first truth)</th><td>" << Seconds(m.mission_s)
         << "</td></tr>"
         << "<tr><th>distance driven</th><td>" << Fixed(m.distance_m, 2) << " m</td></tr>"
         << "<tr><th>collisions</th><td>" << m.collisions
         << "</td></tr><tr><th>reachable floor mapped</th><td>";
    if (m.mapped_m2) {
      html << Fixed(*m.mapped_m2, 1) << " of " << Fixed(*m.reachable_m2, 1) << " m&sup2; ("
           << Fixed(100 * *m.mapped_fraction, 0) << "%)";
    } else {
      html << "not measured (needs SIM_FLOOR, SIM_TRUTH and MAP)";
    }
    html << "</td></tr><tr><th>stuck</th><td>"
         << (m.stuck_s ? Seconds(m.stuck_s) + " in total, longest " + Seconds(m.longest_stuck_s) +
                             "; longest going nowhere: " + Seconds(m.longest_confined_s)
                       : std::string("not judged (no EXPLORE_STATUS)"))
         << "</td></tr><tr><th>came home</th><td>"
         << (m.came_home ? "after " + Seconds(m.home_after_s)
                         : "no" + (m.last_explore_state.empty()
                                       ? ""
                                       : " (last state: " + Html(m.last_explore_state) + ")"))
         << "</td></tr>";
    for (const auto& t : summary.truth) {
      html << "<tr><th>" << Html(t.name) << "</th><td>"
           << (t.found     ? "found after " + Seconds(t.found_after_s)
               : t.dropped ? std::string("found, then lost")
                           : std::string("not found"))
           << "</td></tr>";
    }
    html << "</table>";
    if (wrote_plot) {
      html << "<h3>Explored area against time</h3><img src=\"coverage.png\" alt=\"mapped reachable "
              "floor against time\">";
    }
  }
  html << "<h2>Map</h2><img src=\"map.png\" alt=\"map with people and sound sources\">"
       << (m.mapped_m2 ? "<p>Orange: reachable floor SLAM did not map.</p>" : "")
       << "<h2>People</h2>"
          "<table><tr><th>#</th><th>position "
          "(m)</th><th>how</th><th>confidence</th><th>said</th><th>count</th></tr>";
  {
    for (const auto& p : PeopleOnMap(data, summary)) {
      char pos[64];
      snprintf(pos, sizeof(pos), "%.2f, %.2f", p.position_m[0], p.position_m[1]);
      html << "<tr><td>" << p.id << "</td><td>" << pos << "</td><td>" << HowFound(p.cues)
           << "</td><td>" << static_cast<int>(100 * p.confidence) << "%</td><td>" << Html(p.keyword)
           << "</td><td>" << p.people_count << "</td></tr>";
    }
  }
  html << "</table><h2>Sound sources</h2><table><tr><th>#</th><th>position "
          "(m)</th><th>state</th><th>what</th><th>person</th></tr>";
  {
    for (const auto& s : SourcesOnMap(data, summary)) {
      char pos[64];
      snprintf(pos, sizeof(pos), "%.2f, %.2f", s.position_m[0], s.position_m[1]);
      html << "<tr><td>" << s.id << "</td><td>" << pos << "</td><td>"
           << (s.state == sarmap::sound_source_t::STATE_CONVERGED ? "converged" : "initialising")
           << "</td><td>" << SoundClassName(s.sound_class) << " ("
           << static_cast<int>(100 * s.class_confidence) << "%)</td><td>"
           << (s.is_person
                   ? (s.priority == sarmap::sound_source_t::PRIORITY_CALL ? "yes, calling" : "yes")
                   : "")
           << "</td></tr>";
    }
  }
  html << "</table>";
  if (!summary.source_truth.empty()) {
    html << "<h2>Sound sources against the "
            "simulator</h2><table><tr><th>source</th><th>kind</th><th>mapped as</th>"
            "<th>error</th><th>person</th></tr>";
    for (const auto& m : summary.source_truth)
      html << "<tr><td>" << Html(m.name) << "</td><td>" << m.kind << "</td><td>"
           << (m.found ? m.mapped_class + (m.class_right ? "" : " (wrong)") : "not placed")
           << "</td><td>" << (m.found ? Fixed(m.error_m, 2) + " m" : "—") << "</td><td>"
           << (m.is_person ? "yes" : "") << "</td></tr>";
    html << "</table>";
  }
  if (!summary.outside_map.empty()) {
    html << "<h2>Unconverged / outside the map</h2><p>Not counted as found and not drawn: "
            "estimates far outside the map or with a standard deviation over "
         << kUnlocalisedStdM
         << " m.</p><table><tr><th>what</th><th>#</th><th>position (m)</th>"
            "<th>std (m)</th><th>why</th></tr>";
    for (const auto& o : summary.outside_map) {
      char pos[64], sd[32];
      snprintf(pos, sizeof(pos), "%.1f, %.1f", o.x_m, o.y_m);
      snprintf(sd, sizeof(sd), "%.3g", o.std_m);
      html << "<tr><td>" << o.kind << "</td><td>" << o.id << "</td><td>" << pos << "</td><td>" << sd
           << "</td><td>" << Html(o.why) << "</td></tr>";
    }
    html << "</table>";
  }
  html
      << "<h2>Files</h2><p><a href=\"map.png\">map.png</a> (the map drawn above) &middot; "
      << (geotiff
              ? "<a href=\"map.tif\">map.tif</a> (GeoTIFF, RoboCup Rescue style: one pixel per map "
                "cell, georeferenced in the map frame) &middot; "
              : "")
      << "<a href=\"report.json\">report.json</a></p></body></html>\n";
}

}  // namespace logtools
}  // namespace sarmap
