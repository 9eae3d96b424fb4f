
#include "slam/slam_node.h"

#include <sys/stat.h>

#include <cmath>
#include <map>
#include <variant>

#include "common/image_messages.h"
#include "common/logging.h"
#include "common/memory.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/stamp_gate.h"
#include "common/state_file.h"
#include "common/time.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "slam/map_io.h"
#include "slam/messages.h"
#include "slam/slam.h"
#include "slam/slam_node_options.h"

namespace sarmap {
namespace slam {
namespace {

using common::Utime;

// At most rate_per_min events per minute, in bursts of up to a tenth of that (at least one).
class TokenBucket {
 public:
  explicit TokenBucket(double rate_per_min)
      : rate_per_s_(rate_per_min / 60),
        capacity_(std::max(1.0, rate_per_min / 6)),
        tokens_(capacity_) {}
  bool Take(double now_s) {
    if (last_s_ > -1e299) tokens_ = std::min(capacity_, tokens_ + (now_s - last_s_) * rate_per_s_);
    last_s_ = now_s;
    if (tokens_ < 1) return false;
    tokens_ -= 1;
    return true;
  }

 private:
  double rate_per_s_, capacity_, tokens_;
  double last_s_ = -1e300;
};

bool FileExists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

}  // namespace

class SlamNode::Impl {
 public:
  Impl(const SlamNodeOptions& options, common::Node* node)
      : options_(options),
        node_(node),
        slam_(options.slam),
        queue_(common::SecondsToUtime(options.queue_delay_s)),
        pose_pub_(node->Advertise<pose_t>(options.pose_channel)),
        map_pub_(node->Advertise<occupancy_grid_t>(options.map_channel)),
        anchors_pub_(node->Advertise<slam_anchors_t>(options.anchors_channel)),
        gates_(options.stamp_gate),
        anchor_replies_(options.anchor_replies_per_min) {
    if (!options_.load_map.empty()) {
      slam_.SetLocalisationOnly(true);
      slam_.Load(options_.load_map);
      if (options_.initial_pose.size() == 3) {
        slam_.SetLocalisationStart(slam::Rigid2d(options_.initial_pose[0], options_.initial_pose[1],
                                                 options_.initial_pose[2]));
      }
      SARMAP_LOG(INFO) << "localisation only in " << options_.load_map << " (" << slam_.num_nodes()
                       << " nodes)";
    } else if (options_.resume && !options_.state_file.empty() && FileExists(options_.state_file)) {
      // A corrupt state file must not make the node crash-loop: one clear line, a clean start.
      try {
        slam_.Load(options_.state_file);
        SARMAP_LOG(INFO) << "resumed mapping from " << options_.state_file << " ("
                         << slam_.num_nodes() << " nodes)";
      } catch (const std::exception& e) {
        const std::string aside = common::SetAsideStateFile(options_.state_file);
        SARMAP_LOG(ERROR) << "not resumed, mapping from scratch: " << e.what()
                          << (aside.empty() ? "" : " (moved to " + aside + ")");
      }
    }
    node->Subscribe<laser_scan_t>(
        options_.scan_channel,
        [this](const laser_scan_t& m, const common::ReceiveInfo& info) {
          if (!StampOk(kScanGate, m.header.utime, info)) return;
          Push(m.header.utime, Input{slam::FromScanMessage(m), info.receive_time_s});
        },
        options_.input_queue_capacity);
    node->Subscribe<odometry_t>(
        options_.odom_channel,
        [this](const odometry_t& m, const common::ReceiveInfo& info) {
          if (!StampOk(kOdomGate, m.header.utime, info)) return;
          OdomInput o{common::UtimeToSeconds(m.header.utime), slam::FromOdometryMessage(m)};
          Push(m.header.utime, Input{o, 0.0});
        },
        options_.input_queue_capacity);
    node->Subscribe<slam_anchor_request_t>(
        options_.anchor_request_channel,
        [this](const slam_anchor_request_t& m, const common::ReceiveInfo& info) {
          OnAnchorRequest(m, info);
        });
    node->AddTimer(1.0, [this]() { UpdateStatus(); });
    // When inputs pause (end of a replay, a stalled sensor), release what waits in the queue
    // after queue_delay_s of wall time instead of holding the last scans back.
    node->AddTimer(0.02, [this]() {
      if (queue_.size() > 0 && common::SteadySeconds() - last_input_s_ > options_.queue_delay_s) {
        queue_.Flush([this](Utime, Input& in) { Process(in); });
      }
    });
  }

  void Finish() {
    queue_.Flush([this](Utime, Input& in) { Process(in); });
    if (!options_.load_map.empty()) return;
    slam_.Optimise();
    if (ComputeCovariance()) PublishAnchors(false);
    SaveState();
    if (!options_.map_output_prefix.empty() && slam_.num_nodes() > 0) {
      slam::SaveMapServerMap(slam_.RenderMap(), options_.map_output_prefix);
      SARMAP_LOG(INFO) << "map written to " << options_.map_output_prefix << ".pgm/.yaml";
    }
  }

 private:
  struct OdomInput {
    double time_s;
    slam::Rigid2d pose;
  };
  struct Input {
    std::variant<slam::LaserScan, OdomInput> data;
    double receive_time_s;
  };

  static constexpr int kScanGate = 0, kOdomGate = 1;

  bool StampOk(int gate, Utime utime, const common::ReceiveInfo& info) {
    if (gates_.Accept(gate, utime, info.receive_time_s)) return true;
    node_->Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
    return false;
  }

  // Clients repeat their request (in case this node restarted); only a changed set is answered
  // at once (a joint covariance over the whole graph), then after every optimisation. Replies
  // are rate-limited per client and overall, and the clients kept are bounded: a flood of
  // requests from new client ids costs a map lookup each.
  void OnAnchorRequest(const slam_anchor_request_t& m, const common::ReceiveInfo& info) {
    const double now_s = common::SteadySeconds();
    const auto refuse = [&](const std::string& why) {
      ++anchor_requests_refused_;
      node_->Reject(info.channel, "anchor request of '" + m.client_id + "' refused: " + why);
    };
    if (m.num_node_ids > options_.max_anchor_ids_per_request) {
      refuse(std::to_string(m.num_node_ids) + " node ids (at most " +
             std::to_string(options_.max_anchor_ids_per_request) + ")");
      return;
    }
    auto known = anchor_requests_.find(m.client_id);
    if (known == anchor_requests_.end()) {
      // Clients that stopped repeating their request free their place.
      for (auto it = anchor_requests_.begin(); it != anchor_requests_.end();) {
        if (now_s - it->second.last_seen_s > options_.anchor_client_timeout_s) {
          it = anchor_requests_.erase(it);
        } else {
          ++it;
        }
      }
      if (static_cast<int>(anchor_requests_.size()) >= options_.max_anchor_clients) {
        refuse("already " + std::to_string(anchor_requests_.size()) + " clients");
        return;
      }
      known = anchor_requests_
                  .emplace(m.client_id, AnchorClient(options_.anchor_replies_per_client_per_min))
                  .first;
    }
    AnchorClient& client = known->second;
    client.last_seen_s = now_s;
    if (client.node_ids == m.node_ids && client.answered) return;
    client.node_ids = m.node_ids;
    client.answered = false;
    // Over the reply rate the request is deferred, not refused: it is kept and served after the
    // next optimisation, so it is not counted as a dropped input.
    if (!client.replies.Take(now_s) || !anchor_replies_.Take(now_s)) {
      ++anchor_requests_deferred_;
      return;
    }
    client.answered = true;
    SARMAP_LOG(INFO) << "client '" << common::EscapeForLog(m.client_id) << "' keeps " << m.num_node_ids << " anchors";
    if (ComputeCovariance()) PublishAnchors(false);
  }

  void Push(Utime utime, Input in) {
    last_input_s_ = common::SteadySeconds();
    // Scans and odometry are ordered as separate streams: a scan made from a depth frame
    // arrives later than the odometry of the same instant, and is still used (the odometry
    // history interpolates at its time) instead of being dropped as late.
    const int stream = std::holds_alternative<OdomInput>(in.data) ? 1 : 0;
    if (!queue_.Push(utime, std::move(in), stream)) {
      if (late_log_.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << "input too late for the time-ordered queue (dropped "
                         << queue_.dropped_late() << " so far)";
      }
    }
    queue_.Release([this](Utime, Input& i) { Process(i); });
  }

  void Process(Input& in) {
    if (auto* o = std::get_if<OdomInput>(&in.data)) {
      std::string why;
      if (!slam_.AddOdometry(o->time_s, o->pose, &why) && odom_log_.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << "odometry rejected (" << slam_.stats().rejected_odometry
                         << " so far): " << why;
      }
      return;
    }
    const slam::LaserScan& scan = std::get<slam::LaserScan>(in.data);
    const slam::ScanResult r = slam_.AddScan(scan);
    if (!r.accepted) {
      if (scan_log_.Allow(common::SteadySeconds())) {
        if (r.waiting_for_odometry) {
          SARMAP_LOG(INFO) << "scan held back (" << slam_.stats().scans_waiting_for_odometry
                           << " so far): " << r.reason;
        } else {
          SARMAP_LOG(WARN) << "scan rejected (" << slam_.stats().rejected_scans
                           << " so far): " << r.reason;
        }
      }
      return;
    }
    const Utime utime = common::SecondsToUtime(scan.time_s);
    if (r.optimised && r.loop_closed) {
      SARMAP_LOG(INFO) << "optimisation " << slam_.optimisation_id() << " with new loop closures ("
                       << slam_.stats().loop_closures << " in total)";
    }
    const bool have_covariance = r.optimised && ComputeCovariance();
    PublishPose(utime, r);
    if (have_covariance) PublishAnchors(r.loop_closed);
    if (scan.time_s - last_map_time_s_ >= options_.map_period_s && options_.load_map.empty() &&
        map_busy_.Allowed(common::SteadySeconds())) {
      last_map_time_s_ = scan.time_s;
      const double start_s = common::SteadySeconds();
      PublishMap(utime);
      map_busy_.Ran(start_s, common::SteadySeconds());
    }
    if (!options_.state_file.empty() && options_.load_map.empty() &&
        scan.time_s - last_save_time_s_ >= options_.state_save_period_s &&
        save_busy_.Allowed(common::SteadySeconds())) {
      last_save_time_s_ = scan.time_s;
      const double start_s = common::SteadySeconds();
      SaveState();
      save_busy_.Ran(start_s, common::SteadySeconds());
    }
    if (in.receive_time_s > 0) {
      latency_sum_s_ += common::SteadySeconds() - in.receive_time_s;
      ++latency_count_;
    }
  }

  // One joint covariance of the latest node and the requested anchors (the latest node's block
  // goes on POSE): it costs a factorisation of the whole graph. False (nothing changed) when
  // it cannot be computed.
  bool ComputeCovariance() {
    if (slam_.num_nodes() == 0) return false;
    std::vector<int64_t> requested;
    for (const auto& [name, client] : anchor_requests_) {
      requested.insert(requested.end(), client.node_ids.begin(), client.node_ids.end());
    }
    std::vector<int> ids = slam_.HoldAnchors(requested);
    Eigen::MatrixXd cov;
    if (!slam_.JointCovariance(ids, &cov)) {
      if (covariance_log_.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << "joint covariance of " << ids.size() << " nodes not computable";
      }
      return false;
    }
    covariance_ids_ = std::move(ids);
    joint_covariance_ = std::move(cov);
    node_covariance_ = joint_covariance_.topLeftCorner<3, 3>();
    return true;
  }

  void PublishPose(Utime utime, const slam::ScanResult& r) {
    pose_t msg{};
    msg.header.utime = utime;
    msg.header.frame = "map";
    msg.child_frame = "base";
    common::FromRigid3d(common::Rigid3d::FromRigid2d(r.map_from_base), msg.position_m, msg.orientation);
    // Uncertainty of the latest node in the map (from the last optimisation) plus the local
    // matching uncertainty of this scan.
    Eigen::Matrix3d cov = node_covariance_;
    const double sxy = options_.pose_sigma_xy_m, syaw = options_.pose_sigma_yaw_deg * M_PI / 180;
    cov(0, 0) += sxy * sxy;
    cov(1, 1) += sxy * sxy;
    cov(2, 2) += syaw * syaw;
    common::SetPlanarCovariance(cov, msg.covariance);
    msg.node_id = r.node_id;
    pose_pub_.Publish(&msg);
  }

  // SLAM_ANCHORS from the last ComputeCovariance().
  void PublishAnchors(bool loop_closed) {
    const std::vector<int>& ids = covariance_ids_;
    const Eigen::MatrixXd& cov = joint_covariance_;
    if (ids.empty()) return;
    slam_anchors_t msg = slam::AnchorsMessage(slam_, ids, cov, loop_closed);
    anchors_pub_.Publish(&msg);
  }

  void PublishMap(Utime utime) {
    const slam::OccupancyMap map = slam_.DrawMap();
    if (map.width == 0) return;
    header_t header{};
    header.utime = utime;
    header.frame = "map";
    occupancy_grid_t msg = common::MakeOccupancyGrid(header, map, true);
    map_pub_.Publish(&msg);
  }

  void SaveState() {
    if (options_.state_file.empty() || slam_.num_nodes() == 0) return;
    try {
      slam_.Save(options_.state_file);
    } catch (const std::exception& e) {
      SARMAP_LOG(ERROR) << "state save failed: " << e.what();
    }
  }

  void UpdateStatus() {
    const auto& s = slam_.stats();
    char text[512];
    std::snprintf(
        text, sizeof(text),
        "nodes %lld (live %d) submaps %lld (live %d) nodes kept for anchors alone %d loops %lld "
        "opt %lld (%.1f s) "
        "rejected scans %lld odom %lld late %lld off-clock stamps %lld (re-anchors "
        "%lld) anchor requests refused %lld deferred %lld mean latency %.1f ms data %.1f MB "
        "maps %lld (%.1f s, %lld from every node)",
        (long long)s.nodes, slam_.num_live_nodes(), (long long)s.submaps, slam_.num_live_submaps(),
        slam_.num_nodes_kept_for_anchors(), (long long)s.loop_closures, (long long)s.optimisations,
        s.optimise_seconds, (long long)s.rejected_scans, (long long)s.rejected_odometry,
        (long long)queue_.dropped_late(), (long long)gates_.dropped(),
        (long long)gates_.reanchors(), (long long)anchor_requests_refused_,
        (long long)anchor_requests_deferred_,
        latency_count_ ? 1e3 * latency_sum_s_ / latency_count_ : 0.0,
        common::Megabytes(slam_.Memory().Total()), (long long)slam_.map_drawing_stats().draws,
        slam_.map_drawing_stats().seconds, (long long)slam_.map_drawing_stats().redraws);
    node_->SetStatusMessage(text);
  }

  slam::SlamNodeOptions options_;
  common::Node* node_;
  slam::Slam slam_;
  common::TimeOrderedQueue<Input> queue_;
  common::Node::Publisher<pose_t> pose_pub_;
  common::Node::Publisher<occupancy_grid_t> map_pub_;
  common::Node::Publisher<slam_anchors_t> anchors_pub_;
  common::StampGates gates_;
  struct AnchorClient {
    explicit AnchorClient(double replies_per_min) : replies(replies_per_min) {}
    std::vector<int64_t> node_ids;
    bool answered = false;  // node_ids were answered at once (not refused by the rate limit)
    double last_seen_s = 0;
    TokenBucket replies;
  };
  std::map<std::string, AnchorClient> anchor_requests_;
  TokenBucket anchor_replies_;
  int64_t anchor_requests_refused_ = 0;   // dropped: too many ids or clients
  int64_t anchor_requests_deferred_ = 0;  // over the reply rate, served after an optimisation
  Eigen::Matrix3d node_covariance_ = Eigen::Matrix3d::Zero();
  std::vector<int> covariance_ids_;  // latest node first, then the anchors
  Eigen::MatrixXd joint_covariance_;
  common::BusyLimiter map_busy_{options_.max_busy_fraction}, save_busy_{options_.max_busy_fraction};
  double last_map_time_s_ = -1e300, last_save_time_s_ = -1e300;
  common::RateLimiter late_log_{2.0}, odom_log_{2.0}, scan_log_{2.0}, covariance_log_{5.0};
  double last_input_s_ = 0;
  double latency_sum_s_ = 0;
  int64_t latency_count_ = 0;
  friend class SlamNode;
};

SlamNode::SlamNode(const SlamNodeOptions& options, common::Node* node)
    : impl_(std::make_unique<Impl>(options, node)) {}
SlamNode::~SlamNode() = default;
void SlamNode::Finish() { impl_->Finish(); }
const Slam& SlamNode::slam() const { return impl_->slam_; }

}  // namespace slam
}  // namespace sarmap
