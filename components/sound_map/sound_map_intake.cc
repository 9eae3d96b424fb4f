#include "sound_map/sound_map_intake.h"

#include "common/logging.h"

namespace sarmap {
namespace sound_map {

using common::Utime;

SoundMapIntake::SoundMapIntake(const SoundMapNodeOptions& options, OnlineSoundMap* map,
                               Publish publish, Request request)
    : options_(options),
      map_(map),
      publish_(std::move(publish)),
      request_(std::move(request)),
      queue_(common::SecondsToUtime(options.reorder_delay_s)) {}

void SoundMapIntake::SendRequest(Utime utime) {
  sarmap::slam_anchor_request_t req;
  req.header.utime = utime;
  req.header.frame = "map";
  req.client_id = options_.client_id;
  req.node_ids = map_->AnchorNodeIds();
  req.num_node_ids = static_cast<int32_t>(req.node_ids.size());
  if (request_) request_(req);
}

void SoundMapIntake::PublishMap(Utime utime) {
  sarmap::sound_map_t msg = SoundMapMessage(*map_, utime);
  if (publish_) publish_(msg);
  last_publish_ = utime;
}

void SoundMapIntake::AfterInput(Utime utime) {
  changed_ = true;
  if (map_->TakeAnchorsChanged()) SendRequest(utime);
  if (utime - last_publish_ >= common::SecondsToUtime(options_.publish_period_s)) PublishMap(utime);
  const auto& c = map_->counters();
  if (c.doa_unsupported_kind > warned_kind_) {
    warned_kind_ = c.doa_unsupported_kind;
    static common::RateLimiter limit(10.0);
    if (limit.Allow(common::SteadySeconds())) {
      SARMAP_LOG(WARN)
          << c.doa_unsupported_kind
          << " DOA(s) of an unusable kind ignored (unknown kind, or ANGLE_1D cone angles "
             "with map.three_d: the 3D map needs azimuth + elevation)";
    }
  }
}

void SoundMapIntake::Push(Utime utime, std::function<void(Utime)> fn) {
  newest_ = std::max(newest_, utime);
  if (!queue_.Push(utime, std::move(fn))) return;
  queue_.Release([this](Utime t, std::function<void(Utime)>& f) {
    f(t);
    AfterInput(t);
  });
}

void SoundMapIntake::Finish() {
  // What still waits in the queue (the last reorder_delay_s of the mission) is applied, and the
  // final map published.
  queue_.Flush([this](Utime t, std::function<void(Utime)>& f) {
    f(t);
    AfterInput(t);
  });
  if (newest_ > 0) PublishMap(newest_);
}

void SoundMapIntake::OnPose(const sarmap::pose_t& msg) {
  const common::Rigid2d pose = PlanarPose(msg);
  const Eigen::Matrix3d cov = common::PlanarCovariance(msg.covariance);
  const int64_t node_id = msg.node_id;
  OnlineSoundMap* map = map_;
  Push(msg.header.utime,
       [map, pose, cov, node_id](Utime t) { map->OnPose(t, pose, cov, node_id); });
}

bool SoundMapIntake::OnAnchors(const sarmap::slam_anchors_t& msg) {
  common::Rigid2d current;
  std::vector<std::pair<int64_t, common::Rigid2d>> anchors;
  Eigen::MatrixXd cov;
  if (!AnchorsFromMessage(msg, &current, &anchors, &cov)) return false;
  const bool loop_closed = msg.loop_closed;
  OnlineSoundMap* map = map_;
  Push(msg.header.utime, [map, current, anchors, cov, loop_closed](Utime t) {
    if (!map->OnSlamAnchors(t, current, anchors, cov, loop_closed)) {
      static common::RateLimiter limit(5.0);
      if (limit.Allow(common::SteadySeconds()))
        SARMAP_LOG(WARN) << "SLAM_ANCHORS rejected (non-finite covariance)";
    }
  });
  return true;
}

void SoundMapIntake::OnDoa(const sarmap::doa_t& msg) {
  std::vector<OnlineSoundMap::Doa> doas = DoasFromMessage(msg);
  const std::string device = msg.device_id;
  OnlineSoundMap* map = map_;
  Push(msg.header.utime, [map, device, doas](Utime t) { map->OnDoa(t, device, doas); });
}

void SoundMapIntake::OnHeard(const sarmap::people_detections_t& msg) {
  // By direction: the heard people's track ids are sarmap-speech's (DOA), not the map
  // stream's (DOA_MAP).
  const auto heard = HeardDirections(msg);
  OnlineSoundMap* map = map_;
  Push(msg.header.utime, [map, heard](Utime) {
    for (const auto& d : heard) map->OnHeardDirection(d);
  });
}

void SoundMapIntake::OnSiteMap(const sarmap::occupancy_grid_t& msg) {
  Eigen::Vector2d lo, hi;
  if (SiteBox(msg, &lo, &hi)) map_->SetSite(lo, hi);
}

}  // namespace sound_map
}  // namespace sarmap
