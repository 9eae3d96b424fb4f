#include "explore/explore.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <set>

#include "explore/explore_messages.h"

namespace sarmap {
namespace explore {
namespace {

// A 58-degree scan (Kinect-like), 60 beams, right to left.
Scan MakeScan(double right_m, double left_m) {
  Scan s;
  s.angle_min_rad = -0.5;
  s.angle_increment_rad = 1.0 / 59;
  s.range_min_m = 0.45;
  s.range_max_m = 4.6;
  for (int i = 0; i < 60; ++i) s.ranges_m.push_back(static_cast<float>(i < 30 ? right_m : left_m));
  return s;
}

TEST(ReactiveExplorerTest, ForwardWhenClearTurnsToTheOpenSideWhenClose) {
  ReactiveExplorer r{ReactiveOptions()};
  bool danger = true;
  Velocity v = r.Step(MakeScan(2.0, 2.5), &danger);
  EXPECT_FALSE(danger);
  EXPECT_GT(v.linear_mps, 0);
  EXPECT_EQ(v.angular_radps, 0);

  Scan close = MakeScan(2.0, 3.0);
  close.ranges_m[10] = 0.5f;  // something under 0.6 m on the right
  v = r.Step(close, &danger);
  EXPECT_TRUE(danger);
  EXPECT_EQ(v.linear_mps, 0);
  EXPECT_GT(v.angular_radps, 0);  // left has the larger mean range
  // Keeps turning the same way while in danger even if the right now looks better.
  Scan still = MakeScan(3.2, 2.0);
  still.ranges_m[40] = 0.5f;
  EXPECT_GT(r.Step(still).angular_radps, 0);
}

TEST(ReactiveExplorerTest, TooManyUnknownReadingsAndNarrowPlacesTurnToTheUnknownSide) {
  ReactiveExplorer r{ReactiveOptions()};
  Scan s = MakeScan(0.8, 0.9);                       // both means under 1 m
  for (int i = 0; i < 12; ++i) s.ranges_m[i] = NAN;  // 20 % unknown, all on the right
  bool danger = false;
  const Velocity v = r.Step(s, &danger);
  EXPECT_TRUE(danger);
  EXPECT_LT(v.angular_radps, 0);  // towards the right: more unknown, possibly open
  const ScanMetrics m = AnalyseScan(s, ReactiveOptions());
  EXPECT_NEAR(m.unknown_rate, 0.2, 1e-9);
  EXPECT_NEAR(m.unknown_right, 0.4, 1e-9);
}

// A 6 x 4 m room, known only around the robot at the left end; the rest unknown.
Grid PartlyKnownRoom() {
  Grid g;
  g.resolution_m = 0.1;
  g.width = 60;
  g.height = 40;
  g.origin_x_m = 0;
  g.origin_y_m = 0;
  g.cells.assign(g.width * g.height, -1);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < 25; ++x) {
      const bool wall = y == 0 || y == g.height - 1 || x == 0;
      g.cells[y * g.width + x] = wall ? 100 : 0;
    }
  }
  return g;
}

// PartlyKnownRoom with its unknown part walled off: nothing left to explore.
Grid ClosedRoom() {
  Grid g = PartlyKnownRoom();
  for (auto& cell : g.cells) cell = cell < 0 ? 100 : cell;
  return g;
}

// PartlyKnownRoom with its unknown part known free inside the outer cells: a 6 x 4 m room open
// to the east (its last column stays unknown).
Grid KnownRoom() {
  Grid g = PartlyKnownRoom();
  for (int y = 1; y < g.height - 1; ++y) {
    for (int x = 25; x < g.width - 1; ++x) g.cells[y * g.width + x] = 0;
  }
  return g;
}

ExploreOptions NoLookAround() {
  ExploreOptions o;
  o.goals.look_around = false;
  return o;
}

TEST(ExploreMapTest, FrontierOfTheKnownPartAndAPathThatKeepsItsDistanceFromWalls) {
  ExploreMap m{PlannerOptions()};
  m.SetMap(PartlyKnownRoom());
  m.UpdateCostMap();
  const CostField field = m.Plan(Eigen::Vector2d(1.0, 2.0));
  const auto frontiers = m.Frontiers(field);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_NEAR(frontiers[0].goal_m.x(), 2.45, 0.11);  // the edge of the known part
  EXPECT_NEAR(frontiers[0].size_m, 0.1 * frontiers[0].cells.size(), 1e-9);
  // Cells within the robot radius (0.25 m) of the wall at y = 0..0.1 are not traversable.
  EXPECT_FALSE(m.Traversable(Eigen::Vector2d(1.0, 0.3)));
  EXPECT_TRUE(m.Traversable(Eigen::Vector2d(1.0, 0.45)));
  // A path along the room prefers the middle (clearance cost) over hugging the wall.
  const auto path = m.PathTo(field, Eigen::Vector2d(2.0, 0.45));
  ASSERT_GT(path.size(), 3u);
  double max_y = 0;
  for (const auto& p : path) max_y = std::max(max_y, p.y());
  EXPECT_GT(max_y, 0.6);
  // Everything known: no frontier left.
  m.SetMap(ClosedRoom());
  m.UpdateCostMap();
  EXPECT_TRUE(m.Frontiers(m.Plan(Eigen::Vector2d(1.0, 2.0))).empty());
}

TEST(ExploreMapTest, ScansFillTheGridNoReturnIsFreeToRangeAndTheRobotsOwnPlaceIsFree) {
  const common::Rigid2d pose(1.0, 2.0, 0.0);
  {
    ExploreMap m{PlannerOptions()};
    m.SetMap(PartlyKnownRoom());
    EXPECT_FALSE(m.Known(Eigen::Vector2d(4.0, 2.0)));
    m.IntegrateScan(pose, MakeScan(INFINITY, INFINITY));  // no return anywhere: free up to 4.6 m
    EXPECT_TRUE(m.Known(Eigen::Vector2d(4.0, 2.0)));
    EXPECT_FALSE(m.Occupied(Eigen::Vector2d(4.0, 2.0)));
    // What the rays crossed stays free through a MAP that has no verdict there (a room SLAM
    // saw once through its door)...
    m.SetMap(PartlyKnownRoom());
    EXPECT_TRUE(m.Known(Eigen::Vector2d(4.0, 2.0)));
    EXPECT_FALSE(m.Occupied(Eigen::Vector2d(4.0, 2.0)));
    // ...and MAP's obstacles win over it.
    Grid walled = PartlyKnownRoom();
    walled.at(40, 20) = 100;
    m.SetMap(walled);
    EXPECT_TRUE(m.Occupied(Eigen::Vector2d(4.05, 2.05)));
    // MAP's obstacles are not carried into the next MAP: SLAM moves its walls as it
    // re-optimises, and the old copies would close doorways.
    m.SetMap(PartlyKnownRoom());
    EXPECT_FALSE(m.Occupied(Eigen::Vector2d(4.05, 2.05)));
  }
  ExploreMap m{PlannerOptions()};
  m.SetMap(PartlyKnownRoom());
  Scan wall = MakeScan(0.0f, 0.0f);  // no information anywhere...
  wall.ranges_m[30] = 4.0f;          // ...but one return straight ahead
  m.IntegrateScan(pose, wall);
  const double a = wall.angle_min_rad + 30 * wall.angle_increment_rad;
  const Eigen::Vector2d hit(1.0 + 4.0 * std::cos(a), 2.0 + 4.0 * std::sin(a));
  EXPECT_TRUE(m.Occupied(hit));
  EXPECT_FALSE(m.Known(Eigen::Vector2d(4.0, 3.0)));  // rays without information are skipped
  // The return stays an obstacle through a new MAP that has the cell uncertain or unknown (a low
  // object SLAM saw in few scans), and goes when the MAP calls it free.
  m.SetMap(PartlyKnownRoom());
  EXPECT_TRUE(m.Occupied(hit));
  Grid free = PartlyKnownRoom();
  for (auto& c : free.cells) c = 0;
  m.SetMap(free);
  EXPECT_FALSE(m.Occupied(hit));
  // A return that a later ray crosses was not there (noise at an edge): gone.
  m.SetMap(PartlyKnownRoom());
  m.IntegrateScan(pose, wall);
  EXPECT_TRUE(m.Occupied(hit));
  Scan through = MakeScan(0.0f, 0.0f);
  through.ranges_m[30] = INFINITY;
  m.IntegrateScan(pose, through);
  EXPECT_FALSE(m.Occupied(hit));
  m.SetMap(PartlyKnownRoom());
  EXPECT_FALSE(m.Occupied(hit));
  // The robot's own footprint is free once it has been there; only the body's radius of it
  // counts as seen.
  EXPECT_FALSE(m.Known(Eigen::Vector2d(4.2, 3.2)));
  m.AddTrail(Eigen::Vector2d(4.0, 3.0));
  EXPECT_TRUE(m.Known(Eigen::Vector2d(4.2, 3.2)));
}

TEST(ExploreMapTest, SeenIsWhatMapKnewTheSensorLookedAtOrTheBodyStoodOn) {
  ExploreMap m{PlannerOptions()};
  m.SetMap(PartlyKnownRoom());
  const auto seen = [&m](double x, double y) {
    const Eigen::Vector2i c = m.grid().CellOf(Eigen::Vector2d(x, y));
    return m.Seen(c.x(), c.y());
  };
  EXPECT_TRUE(seen(1.0, 1.0));  // MAP knows it
  EXPECT_FALSE(seen(4.0, 3.0));
  // The trail's free stamp (assume_free_radius_m) is seen only under the body.
  m.AddTrail(Eigen::Vector2d(4.0, 3.0));
  EXPECT_TRUE(seen(4.15, 3.05));   // 0.16 m from the trail
  EXPECT_FALSE(seen(4.35, 3.05));  // 0.35 m: assumed free, not seen
  EXPECT_TRUE(m.Known(Eigen::Vector2d(4.35, 3.05)));
  // A beam without information was still looked along over the near field beyond the
  // minimum range, and that stays seen through a new MAP; nearer than the minimum range, or
  // beyond the near field, it was not.
  m.IntegrateScan(common::Rigid2d(4.0, 1.0, 0.0), MakeScan(0.0f, 0.0f));
  m.SetMap(PartlyKnownRoom());
  EXPECT_TRUE(seen(4.8, 1.0));
  EXPECT_FALSE(m.Known(Eigen::Vector2d(4.8, 1.0)));
  EXPECT_FALSE(seen(4.35, 1.0));
  EXPECT_FALSE(seen(6.5, 1.0));
  // Once MAP knew a cell, it stays seen.
  Grid known = PartlyKnownRoom();
  for (auto& c : known.cells) c = 0;
  m.SetMap(known);
  m.SetMap(PartlyKnownRoom());
  EXPECT_TRUE(seen(5.5, 3.5));
}

TEST(ExploreMapTest, ALowObjectStaysWhenRaysFromCloserThanItsVisibleRangePassOverIt) {
  ExploreMap m{PlannerOptions()};
  m.SetMap(PartlyKnownRoom());
  // Rubble straight ahead at x = 3.0 m, seen from x = 1.0 m; its top is in the camera's view
  // from 0.9 m on.
  Scan seen = MakeScan(0.0f, 0.0f);
  seen.visible_from_m.assign(seen.ranges_m.size(), 0.0f);
  seen.ranges_m[30] = 2.0f;
  seen.visible_from_m[30] = 0.9f;
  m.IntegrateScan(common::Rigid2d(1.0, 2.0, 0.0), seen);
  const double a = seen.angle_min_rad + 30 * seen.angle_increment_rad;
  const Eigen::Vector2d rubble(1.0 + 2.0 * std::cos(a), 2.0 + 2.0 * std::sin(a));
  ASSERT_TRUE(m.Occupied(rubble));
  // From 0.6 m before it the camera looks over it: the ray's "no return" does not clear it...
  Scan over = MakeScan(0.0f, 0.0f);
  over.visible_from_m.assign(over.ranges_m.size(), 0.0f);
  over.ranges_m[30] = INFINITY;
  const common::Rigid2d close(rubble.x() - 0.6 * std::cos(a), rubble.y() - 0.6 * std::sin(a), 0.0);
  m.IntegrateScan(close, over);
  EXPECT_TRUE(m.Occupied(rubble));
  // ...nor does a MAP that calls it free (SLAM's rays from close by passed over it too).
  Grid free = PartlyKnownRoom();
  for (auto& c : free.cells) c = 0;
  m.SetMap(free);
  EXPECT_TRUE(m.Occupied(rubble));
  // From 1.5 m, where its top would be in view, a ray through it says it is gone.
  const common::Rigid2d far(rubble.x() - 1.5 * std::cos(a), rubble.y() - 1.5 * std::sin(a), 0.0);
  m.IntegrateScan(far, over);
  EXPECT_FALSE(m.Occupied(rubble));
  // A laser's scan (no visible-from ranges) is seen down to its minimum range: cleared close by.
  m.IntegrateScan(common::Rigid2d(1.0, 2.0, 0.0), [&] {
    Scan laser = seen;
    laser.visible_from_m.clear();
    return laser;
  }());
  ASSERT_TRUE(m.Occupied(rubble));
  Scan laser_over = over;
  laser_over.visible_from_m.clear();
  m.IntegrateScan(close, laser_over);
  EXPECT_FALSE(m.Occupied(rubble));
}

// A 6 x 4 m space, all seen free (the camera sees through glass), with a pier at x = 5.0..5.2 m,
// y = 3.0..3.2 m.
Grid FreeSpaceWithPier() {
  Grid g;
  g.resolution_m = 0.1;
  g.width = 60;
  g.height = 40;
  g.cells.assign(g.width * g.height, 0);
  for (int y = 30; y <= 31; ++y) {
    for (int x = 50; x <= 51; ++x) g.cells[y * g.width + x] = 100;
  }
  return g;
}

TEST(ExploreMapTest, ContactsInLineAreOneGlassPaneExtendedToThePierAndKnownObstaclesNeedNoMark) {
  ExploreMap m{PlannerOptions()};
  m.SetMap(FreeSpaceWithPier());
  const double touching = m.options().robot_radius_m;  // base centre to the surface
  // The mark lies on the line y = 3.0..3.2 (where the front of the base met the surface).
  const auto marked = [&m](double x) {
    for (double y = 2.975; y < 3.25; y += 0.05) {
      if (m.Occupied(Eigen::Vector2d(x, y))) return true;
    }
    return false;
  };
  // Two bumps heading north into y = 3 m, 1.5 m apart: one invisible surface.
  EXPECT_TRUE(m.AddContact(common::Rigid2d(2.0, 3.0 - touching, M_PI / 2)));
  EXPECT_EQ(m.glass_lines(), 0);
  EXPECT_TRUE(m.AddContact(common::Rigid2d(3.5, 3.0 - touching + 0.05, M_PI / 2 - 0.4)));
  EXPECT_EQ(m.glass_lines(), 1);
  EXPECT_TRUE(marked(2.75));      // between the bumps
  EXPECT_TRUE(marked(4.8));       // extended to the pier...
  EXPECT_FALSE(marked(5.5));      // ...and not beyond it
  m.SetMap(FreeSpaceWithPier());  // kept through every MAP
  EXPECT_TRUE(marked(2.75));
  // Touching the pier, which the map has: no mark.
  EXPECT_FALSE(m.AddContact(common::Rigid2d(5.1, 3.0 - touching, M_PI / 2)));
  EXPECT_EQ(m.contacts(), 2);
  // A bump heading along the line (east) is not part of the pane.
  EXPECT_TRUE(m.AddContact(common::Rigid2d(1.0, 1.0, 0.0)));
  EXPECT_EQ(m.glass_lines(), 1);
  const double front = m.options().robot_radius_m + 0.1;  // where a bump is marked
  EXPECT_TRUE(m.Occupied(Eigen::Vector2d(1.0 + front, 1.0)));
  // Forgetting the lone bumps keeps the pane.
  EXPECT_TRUE(m.ClearLoneContacts());
  EXPECT_EQ(m.contacts(), 2);
  EXPECT_FALSE(m.Occupied(Eigen::Vector2d(1.0 + front, 1.0)));
  EXPECT_TRUE(marked(2.75));
  EXPECT_FALSE(m.ClearLoneContacts());
}

TEST(SafetyLayerTest, NoReturnIsFreeBlindCorridorIsBlockedAndOnlyForwardSpeedIsLimited) {
  SafetyOptions o;
  // +inf readings (nothing within range) are free space, not unknowns that stop the robot.
  EXPECT_TRUE(std::isinf(ScanClearanceAhead(MakeScan(INFINITY, INFINITY), o)));
  // An obstacle 0.8 m straight ahead.
  Scan s = MakeScan(INFINITY, INFINITY);
  s.ranges_m[29] = s.ranges_m[30] = 0.8f;
  EXPECT_NEAR(ScanClearanceAhead(s, o), 0.8, 0.01);
  // The same range off to the side (outside the corridor) does not count.
  Scan side = MakeScan(INFINITY, INFINITY);
  side.ranges_m[2] = 0.8f;
  EXPECT_TRUE(std::isinf(ScanClearanceAhead(side, o)));
  // Columns straight ahead without information: something nearer than the camera sees.
  Scan blind = MakeScan(INFINITY, INFINITY);
  for (int i = 15; i < 45; ++i) blind.ranges_m[i] = 0.0f;
  EXPECT_EQ(ScanClearanceAhead(blind, o), 0.0);
}

TEST(ExploreControllerTest, ExploresTowardsTheFrontierAndTheSafetyLayerNeverTurnsTheRobot) {
  ExploreController c{NoLookAround()};
  c.OnMap(PartlyKnownRoom());
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  Velocity v = c.OnScan(0.0, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(v.source, "planner");
  EXPECT_GT(v.linear_mps, 0.1);
  EXPECT_EQ(c.status().state, "exploring");
  EXPECT_EQ(c.status().goal_kind, "frontier");
  ASSERT_TRUE(c.status().goal_m);
  EXPECT_GT(c.status().goal_m->x(), 2.0);
  // An obstacle 0.5 m ahead that the map does not have: forward speed 0, heading untouched.
  Scan blocked = MakeScan(INFINITY, INFINITY);
  blocked.ranges_m[29] = blocked.ranges_m[30] = 0.5f;
  const Velocity held = c.OnScan(0.1, blocked);
  EXPECT_EQ(held.linear_mps, 0.0);
  EXPECT_NEAR(held.angular_radps, v.angular_radps, 0.2);
  // Facing away from the goal: turn on the spot.
  c.OnPose(common::Rigid2d(1.0, 2.0, M_PI), 0.0);
  const Velocity turn = c.OnScan(0.2, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(turn.linear_mps, 0.0);
  EXPECT_NE(turn.angular_radps, 0.0);
}

// A room (x 0.5..3, y 0.5..3.5) with a 1 m door (y 1.5..2.5) in its 0.1 m east wall, and
// behind the door a corridor 1 m wide running north (x 3.1..4.1) to y = 12; the map knows the
// site up to y = 4.5, beyond which the corridor goes on unseen (the frontier). Everything else
// is wall.
bool InRoomDoorCorridor(const Eigen::Vector2d& p) {
  const bool room = p.x() >= 0.5 && p.x() < 3.0 && p.y() >= 0.5 && p.y() < 3.5;
  const bool door = p.x() >= 3.0 && p.x() < 3.1 && p.y() >= 1.5 && p.y() < 2.5;
  const bool corridor = p.x() >= 3.1 && p.x() < 4.1 && p.y() >= 0.5 && p.y() < 12.0;
  return room || door || corridor;
}

TEST(ExploreControllerTest, TheFollowerDoesNotCutTheInnerCornerOfATurn) {
  Grid map;
  map.resolution_m = 0.05;
  map.width = 100;
  map.height = 250;
  map.cells.assign(map.width * map.height, 100);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const Eigen::Vector2d p = map.CentreOf(x, y);
      if (InRoomDoorCorridor(p)) map.at(x, y) = p.y() < 4.5 ? 0 : -1;
    }
  }
  // The true distance from a point to the walls (the squares of the cells outside the corridor).
  const auto wall_distance = [&](const Eigen::Vector2d& p) {
    double d = INFINITY;
    for (int y = 0; y < map.height; ++y) {
      for (int x = 0; x < map.width; ++x) {
        const Eigen::Vector2d c = map.CentreOf(x, y);
        if (InRoomDoorCorridor(c)) continue;
        const Eigen::Vector2d gap =
            ((p - c).cwiseAbs().array() - 0.5 * map.resolution_m).max(0.0).matrix();
        d = std::min(d, gap.norm());
      }
    }
    return d;
  };
  // The camera's scan, ray-cast in the true corridor.
  const auto scan_at = [&](const common::Rigid2d& pose, double t) {
    Scan s = MakeScan(INFINITY, INFINITY);
    s.stamp_s = t;
    for (size_t i = 0; i < s.ranges_m.size(); ++i) {
      const double a = pose.yaw_rad() + s.angle_min_rad + i * s.angle_increment_rad;
      for (double r = 0; r <= s.range_max_m; r += 0.02) {
        if (!InRoomDoorCorridor(pose.translation() +
                                r * Eigen::Vector2d(std::cos(a), std::sin(a)))) {
          s.ranges_m[i] = r < s.range_min_m ? 0.0f : static_cast<float>(r);
          break;
        }
      }
    }
    return s;
  };
  // Without the clearance cost the path runs at the planner's radius round the jamb, as it does
  // wherever the map leaves no more room.
  ExploreOptions o = NoLookAround();
  o.planner.clearance_weight = 0;
  // As config/explore.yaml: the planner keeps 0.3 m (the base's 0.25 and a margin), the
  // safety layer's corridor is inside the base.
  o.planner.robot_radius_m = 0.3;
  o.safety.corridor_half_width_m = 0.22;
  ExploreController c{o};
  c.OnMap(map);
  common::Rigid2d pose(1.0, 2.0, 0.0);
  double closest_m = INFINITY;
  const double dt = 0.1;
  for (double t = 0; t < 30 && pose.translation().y() < 4.0; t += dt) {
    c.OnPose(pose, t);
    const Velocity v = c.OnScan(t, scan_at(pose, t));
    const double yaw = pose.yaw_rad() + v.angular_radps * dt;
    pose = common::Rigid2d(
        pose.translation() + v.linear_mps * dt * Eigen::Vector2d(std::cos(yaw), std::sin(yaw)),
        yaw);
    closest_m = std::min(closest_m, wall_distance(pose.translation()));
  }
  // Round the corner and on up the corridor (steering at the lookahead point beyond the jamb,
  // the robot heads into the jamb and the safety layer holds it in the doorway)...
  EXPECT_GE(pose.translation().y(), 4.0);
  // ... with the base (0.25 m) never nearer a wall than the planner's radius allows, less the
  // grid's quantisation.
  EXPECT_GT(closest_m, 0.27);
}

TEST(ExploreControllerTest, ATurnPastAnUnseenCornerLooksAtItFirst) {
  // The robot heads 0.6 rad left of the frontier to its right: the follower drives a right
  // turn. A patch the sensor has never seen (a shelf's corner beside a doorway) lies inside
  // that turn, 0.64 m away, 0.76 rad right of the heading: outside the 0.5 rad half view, beyond
  // the 0.45 m minimum range.
  const common::Rigid2d pose(1.0, 2.0, 0.6);
  const Eigen::Vector2d corner = pose * Eigen::Vector2d(0.45, -0.45);
  Grid map = PartlyKnownRoom();
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const Eigen::Vector2d p(map.origin_x_m + (x + 0.5) * map.resolution_m,
                              map.origin_y_m + (y + 0.5) * map.resolution_m);
      if ((p - corner).cwiseAbs().maxCoeff() <= 0.15) map.cells[y * map.width + x] = -1;
    }
  }
  for (const double lookahead_m : {0.0, 0.5}) {
    ExploreOptions o = NoLookAround();
    o.safety.unseen_lookahead_m = lookahead_m;
    ExploreController c{o};
    c.OnMap(map);
    c.OnPose(pose, 0.0);
    const Velocity v = c.OnScan(0.0, MakeScan(INFINITY, INFINITY));
    if (lookahead_m == 0) {
      // Without the rule the turn is driven, and it sweeps the patch.
      EXPECT_EQ(v.source, "planner");
      EXPECT_GT(v.linear_mps, 0.1);
      EXPECT_LT(v.angular_radps, -0.3);
      continue;
    }
    EXPECT_EQ(v.source, "look");
    EXPECT_EQ(v.linear_mps, 0.0);
    EXPECT_LT(v.angular_radps, -0.3);  // towards the patch
    EXPECT_EQ(c.status().looks, 1);
    // Turned to face it, the sensor sees free floor there: the planner drives again.
    const common::Rigid2d facing(1.0, 2.0, pose.yaw_rad() - 0.76);
    c.OnPose(facing, 0.5);
    Scan seen = MakeScan(INFINITY, INFINITY);
    seen.stamp_s = 0.5;
    c.OnScan(0.5, seen);
    c.OnPose(pose, 1.0);
    seen.stamp_s = 1.0;
    const Velocity after = c.OnScan(1.0, seen);
    EXPECT_EQ(after.source, "planner");
    EXPECT_EQ(c.status().looks, 1);
  }
}

// The beam of MakeScan nearest `bearing_rad`.
int BeamAt(const Scan& s, double bearing_rad) {
  return static_cast<int>(std::lround((bearing_rad - s.angle_min_rad) / s.angle_increment_rad));
}

TEST(LocalObstaclesTest, ReturnsStayInTheOdometryFrameUntilOldFarOrSeenThrough) {
  const Scan nothing = MakeScan(INFINITY, INFINITY);
  Scan one = nothing;
  one.ranges_m[BeamAt(one, 0.0)] = 1.0f;
  const double beam_rad = one.angle_min_rad + BeamAt(one, 0.0) * one.angle_increment_rad;
  const double beam_x = std::cos(beam_rad), beam_y = std::sin(beam_rad);
  {
    LocalObstacles memory(10.0, 1.5);
    memory.Add(0.0, common::Rigid2d(), one);
    ASSERT_EQ(memory.size(), 1u);
    // 0.8 m on, then a quarter turn left: the return is 0.2 m to the right, out of the scan's
    // view, and stays there through a scan that reads nothing.
    const common::Rigid2d turned(0.8, 0.0, M_PI / 2);
    memory.Add(1.0, turned, nothing);
    const std::vector<Eigen::Vector2d> p = memory.InBase(turned);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_NEAR(p[0].x(), beam_y, 1e-9);
    EXPECT_NEAR(p[0].y(), 0.8 - beam_x, 1e-9);
    EXPECT_NEAR(NearestDistance(Eigen::Vector2d::Zero(), p), std::hypot(0.8 - beam_x, beam_y),
                1e-9);
    memory.Add(10.5, turned, nothing);  // seen 10.5 s ago: older than 10 s
    EXPECT_EQ(memory.size(), 0u);
  }
  {
    LocalObstacles memory(10.0, 1.5);
    memory.Add(0.0, common::Rigid2d(), one);
    memory.Add(0.1, common::Rigid2d(-0.6, 0.0, 0.0), nothing);  // 1.6 m away: dropped
    EXPECT_EQ(memory.size(), 0u);
  }
  {
    // The beam reads past it: gone; unless the beam sees that spot only from further away (a
    // low object the camera looks over), or reads it again.
    LocalObstacles memory(10.0, 1.5);
    memory.Add(0.0, common::Rigid2d(), one);
    Scan over = nothing;
    over.visible_from_m.assign(over.ranges_m.size(), 1.5f);
    memory.Add(0.1, common::Rigid2d(), over);
    EXPECT_EQ(memory.size(), 1u);
    memory.Add(0.2, common::Rigid2d(), one);
    EXPECT_EQ(memory.size(), 1u);
    memory.Add(0.3, common::Rigid2d(), nothing);
    EXPECT_EQ(memory.size(), 0u);
  }
}

TEST(ExploreControllerTest, AnObstacleSeenEarlierStopsTheRobotWhereSlamMisplacedIt) {
  // Something 0.2 m left of the robot's line, 0.9 m ahead when seen, while SLAM has the robot
  // 1 m off to the side (the map puts the obstacle there); then SLAM corrects the pose. 0.6 m
  // on, the obstacle is 0.3 m ahead, nearer than the camera's minimum range and out of its
  // view; the scan reads nothing. Kept in the odometry frame it stops the robot; kept in the
  // map frame (no odometry) it is as misplaced as the map.
  for (const double memory_s : {10.0, 0.0}) {
    for (const bool with_odometry : {true, false}) {
      ExploreOptions o = NoLookAround();
      o.safety.memory_s = memory_s;
      ExploreController c{o};
      c.OnMap(PartlyKnownRoom());
      c.OnPose(common::Rigid2d(0.9, 3.0, 0.0), 0.0);
      if (with_odometry) c.OnOdometry(common::Rigid2d(5.0, -1.0, 0.0), 0.0);
      Scan seen = MakeScan(INFINITY, INFINITY);
      seen.ranges_m[BeamAt(seen, std::atan2(0.2, 0.9))] = static_cast<float>(std::hypot(0.9, 0.2));
      c.OnScan(0.0, seen);
      Scan later = MakeScan(INFINITY, INFINITY);
      later.stamp_s = 1.7;
      c.OnPose(common::Rigid2d(1.5, 2.0, 0.0), 1.7);
      if (with_odometry) c.OnOdometry(common::Rigid2d(5.6, -1.0, 0.0), 1.7);
      const Velocity v = c.OnScan(1.7, later);
      if (memory_s > 0 && with_odometry) {
        EXPECT_EQ(v.linear_mps, 0.0);
        EXPECT_EQ(v.source, "safety");
      } else {
        EXPECT_GT(v.linear_mps, 0.1) << "memory " << memory_s << " s, odometry " << with_odometry;
      }
    }
  }
}

TEST(ExploreControllerTest, StuckRobotBacksOffTurnsAndGivesUpTheGoal) {
  ExploreOptions o = NoLookAround();
  o.recovery.attempts_per_goal = 1;
  ExploreController c{o};
  c.OnMap(PartlyKnownRoom());
  const common::Rigid2d pose(1.0, 2.0, 0.0);
  c.OnPose(pose, 0.0);
  double t = 0;
  // The robot never moves (wheels spinning against something the sensors miss).
  bool backed_off = false, turned = false;
  for (; t < 40 && c.status().recoveries < 2; t += 0.1) {
    const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
    backed_off |= v.source == "recovery" && v.linear_mps < 0;
    turned |= v.source == "recovery" && v.angular_radps != 0;
  }
  EXPECT_GE(c.status().recoveries, 1);
  EXPECT_TRUE(backed_off);
  EXPECT_TRUE(turned);
  // Told to drive, it did not move: an obstacle the sensors miss (glass) is now in its map.
  EXPECT_GE(c.status().contacts, 1);
  EXPECT_TRUE(c.map().Occupied(pose * Eigen::Vector2d(o.planner.robot_radius_m + 0.1, 0.0)));
  // Without contact detection, the first recovery comes after stuck_timeout_s, not before.
  o.recovery.contact_ratio = 0;
  ExploreController fresh{o};
  fresh.OnMap(PartlyKnownRoom());
  fresh.OnPose(pose, 0.0);
  for (double u = 0; u < o.recovery.stuck_timeout_s - 0.5; u += 0.1)
    fresh.OnScan(u, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(fresh.status().recoveries, 0);
  EXPECT_GT(fresh.status().stuck_s, o.recovery.stuck_timeout_s - 1.0);
  for (double u = o.recovery.stuck_timeout_s - 0.5; u < o.recovery.stuck_timeout_s + 0.5;
       u += 0.1) {
    fresh.OnScan(u, MakeScan(INFINITY, INFINITY));
  }
  EXPECT_EQ(fresh.status().recoveries, 1);
  // After two recoveries on one goal it is blacklisted.
  EXPECT_GE(c.status().blacklisted, 1);
}

TEST(ExploreControllerTest, APoseThatLagsTheScanStopsTheRobotWithoutCountingAsStuck) {
  const ExploreOptions o = NoLookAround();
  ExploreController c{o};
  c.OnMap(PartlyKnownRoom());
  const common::Rigid2d pose(1.0, 2.0, 0.0);
  c.OnPose(pose, 0.0);
  Scan scan = MakeScan(INFINITY, INFINITY);
  EXPECT_GT(c.OnScan(0.0, scan).linear_mps, 0.1);
  // SLAM stalls: the scans go on, the pose stays at stamp 0 for longer than any stuck timeout.
  // They see a wall 1.25 m ahead that the stale pose would put in the wrong place: it stays out
  // of the explorer's map.
  const Scan wall = MakeScan(1.25, 1.25);
  const Eigen::Vector2d wall_m = pose * Eigen::Vector2d(1.25, 0.0);
  const double stall_s = 2 * o.recovery.stuck_timeout_s;
  for (double t = 0.1; t < stall_s; t += 0.1) {
    scan = t <= o.safety.max_pose_age_s ? MakeScan(INFINITY, INFINITY) : wall;
    scan.stamp_s = t;
    const Velocity v = c.OnScan(t, scan);
    if (t <= o.safety.max_pose_age_s) continue;
    ASSERT_EQ(v.source, "pose_wait") << "t " << t;
    EXPECT_EQ(v.linear_mps, 0.0);
    EXPECT_EQ(v.angular_radps, 0.0);
  }
  EXPECT_FALSE(c.map().Occupied(wall_m));
  // SLAM is back: the robot drives on, neither stuck nor in contact with anything.
  scan = MakeScan(INFINITY, INFINITY);
  for (double t = stall_s; t < stall_s + 1.0; t += 0.1) {
    scan.stamp_s = t;
    c.OnPose(pose * common::Rigid2d(0.3 * (t - stall_s), 0.0, 0.0), t);
    EXPECT_EQ(c.OnScan(t, scan).source, "planner") << "t " << t;
  }
  EXPECT_EQ(c.status().recoveries, 0);
  EXPECT_EQ(c.status().contacts, 0);
  // With the check off, a lagging pose drives as before.
  ExploreOptions off = o;
  off.safety.max_pose_age_s = 0;
  ExploreController unchecked{off};
  unchecked.OnMap(PartlyKnownRoom());
  unchecked.OnPose(pose, 0.0);
  scan = wall;
  scan.stamp_s = 10.0;
  EXPECT_NE(unchecked.OnScan(10.0, scan).source, "pose_wait");
  EXPECT_TRUE(unchecked.map().Occupied(wall_m));
}

// The base's pose after `v` for `dt_s`, unless that puts it into `blocked` (an obstacle neither
// the scan nor the map shows): then it stays.
common::Rigid2d Drive(const common::Rigid2d& pose, const Velocity& v, double dt_s,
                      const std::function<bool(const Eigen::Vector2d&)>& blocked) {
  const common::Rigid2d next =
      pose * common::Rigid2d(v.linear_mps * dt_s, 0.0, v.angular_radps * dt_s);
  return blocked(next.translation())
             ? common::Rigid2d(pose.translation().x(), pose.translation().y(), next.yaw_rad())
             : next;
}

// SLAM's pose a metre off puts the robot inside what its map calls walls: no plan leads out,
// and turning or backing off on that map cannot help. After escape_after recoveries so, the
// robot drives on the scan alone for escape_s, then plans again.
TEST(ExploreControllerTest, ShutInRecoveryAfterRecoveryDrivesOnTheScanAlone) {
  for (const int escape_after : {2, 0}) {
    ExploreOptions o = NoLookAround();
    o.recovery.escape_after = escape_after;
    ExploreController c{o};
    Grid walled = PartlyKnownRoom();
    for (int y = 5; y < 35; ++y) {
      for (int x = 5; x < 24; ++x) walled.cells[y * walled.width + x] = 100;
    }
    c.OnMap(walled);
    common::Rigid2d pose(1.5, 2.0, 0.0);
    int recoveries_before_escape = -1;
    double escape_start_s = -1, escape_end_s = -1;
    for (double t = 0; t < 90; t += 0.1) {
      c.OnPose(pose, t);
      const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
      if (v.source == "escape") {
        if (escape_start_s < 0) {
          escape_start_s = t;
          recoveries_before_escape = c.status().recoveries - 1;
        }
        if (escape_end_s < 0 || t - escape_end_s < 0.15) escape_end_s = t;  // the first escape
        // Open space ahead on the scan: it drives, while the map calls its place a wall.
        if (c.map().Occupied(pose.translation())) {
          EXPECT_GT(v.linear_mps, 0.0) << "t " << t;
        }
      }
      pose = Drive(pose, v, 0.1, [](const Eigen::Vector2d&) { return false; });
    }
    if (escape_after > 0) {
      ASSERT_GE(escape_start_s, 0.0);
      EXPECT_EQ(recoveries_before_escape, escape_after);
      EXPECT_NEAR(escape_end_s - escape_start_s, o.recovery.escape_s, 0.2);
    } else {
      EXPECT_LT(escape_start_s, 0.0);
    }
  }
}

// Wheels that turn but do not move the base (something the sensors miss holds it, or the map is
// not where the robot is): plans exist, and each ends in a contact in the same place. After more
// than escape_after recoveries within escape_radius_m in escape_window_s the robot escapes on the
// scan; without the rule it goes on recovering there.
TEST(ExploreControllerTest, RecoveriesRepeatingInOnePlaceEscapeOnTheScan) {
  for (const double window_s : {60.0, 0.0}) {
    ExploreOptions o = NoLookAround();
    o.recovery.escape_window_s = window_s;
    ExploreController c{o};
    c.OnMap(PartlyKnownRoom());
    common::Rigid2d pose(1.0, 2.0, 0.0);
    int recoveries_before_escape = -1;
    for (double t = 0; t < 90 && recoveries_before_escape < 0; t += 0.1) {
      c.OnPose(pose, t);
      Scan open = MakeScan(INFINITY, INFINITY);
      open.stamp_s = t;
      const Velocity v = c.OnScan(t, open);
      if (v.source == "escape") recoveries_before_escape = c.status().recoveries - 1;
      pose = Drive(pose, v, 0.1, [](const Eigen::Vector2d&) { return true; });
    }
    if (window_s > 0) {
      EXPECT_EQ(recoveries_before_escape, o.recovery.escape_after);
    } else {
      EXPECT_LT(recoveries_before_escape, 0);
      EXPECT_GT(c.status().recoveries, o.recovery.escape_after + 2);
    }
  }
}

// Where the pose is plausible (the robot stands on a free cell of its map), the escape keeps the
// map's obstacles that the scan does not show (low debris close by): held by them, it turns on
// the spot instead of driving on.
TEST(ExploreControllerTest, AnEscapeFromAPlausiblePoseKeepsTheMapsObstaclesTheScanDoesNotShow) {
  ExploreController c{NoLookAround()};
  Grid pocket = PartlyKnownRoom();
  const Eigen::Vector2d start_m(1.5, 2.0);
  for (int y = 5; y < 35; ++y) {
    for (int x = 5; x < 24; ++x) {
      const Eigen::Vector2d centre((x + 0.5) * 0.1, (y + 0.5) * 0.1);
      if ((centre - start_m).norm() > 0.25) pocket.cells[y * pocket.width + x] = 100;
    }
  }
  c.OnMap(pocket);
  // Distance from the base centre to the nearest obstacle of the map.
  const auto clearance = [&](const Eigen::Vector2d& p) {
    double d = INFINITY;
    for (int y = 0; y < pocket.height; ++y) {
      for (int x = 0; x < pocket.width; ++x) {
        if (pocket.cells[y * pocket.width + x] < 65) continue;
        d = std::min(d, (Eigen::Vector2d((x + 0.5) * 0.1, (y + 0.5) * 0.1) - p).norm());
      }
    }
    return d;
  };
  const double start_clearance_m = clearance(start_m);
  common::Rigid2d pose(start_m.x(), start_m.y(), 0.0);
  int escape_scans = 0, turning_escape_scans = 0;
  double yaw_turned_rad = 0;
  for (double t = 0; t < 60; t += 0.1) {
    c.OnPose(pose, t);
    Scan scan = MakeScan(INFINITY, INFINITY);  // nothing the scan shows
    scan.stamp_s = t;
    const Velocity v = c.OnScan(t, scan);
    if (v.source == "escape") {
      ++escape_scans;
      if (v.linear_mps < 0.02 && std::abs(v.angular_radps) > 0.1) ++turning_escape_scans;
      yaw_turned_rad += std::abs(v.angular_radps) * 0.1;
    }
    pose = Drive(pose, v, 0.1, [](const Eigen::Vector2d&) { return false; });
    // Never nearer the map's obstacles than where it started (a cell's rounding aside).
    ASSERT_GE(clearance(pose.translation()), start_clearance_m - 0.06)
        << "t " << t << " " << v.source;
  }
  EXPECT_GT(escape_scans, 50);
  EXPECT_GT(turning_escape_scans, escape_scans / 2);
  EXPECT_GT(yaw_turned_rad, M_PI);
}

// Something neither the scan nor the map shows stops the escaping robot: a contact, as when
// following a plan. It backs off (here the map behind is a wall: it does not) and turns, and the
// escape goes on until escape_s.
TEST(ExploreControllerTest, AContactWhileEscapingBacksOffTurnsAndTheEscapeGoesOn) {
  ExploreOptions o = NoLookAround();
  ExploreController c{o};
  Grid walled = PartlyKnownRoom();  // SLAM's pose inside what the map calls walls: the scan drives
  for (int y = 5; y < 35; ++y) {
    for (int x = 5; x < 24; ++x) walled.cells[y * walled.width + x] = 100;
  }
  c.OnMap(walled);
  common::Rigid2d pose(1.5, 2.0, 0.0);
  // Low debris all around, 0.6 m from where the robot stands: the base cannot enter it.
  const auto debris = [](const Eigen::Vector2d& p) {
    return (p - Eigen::Vector2d(1.5, 2.0)).norm() > 0.6 - 0.25;
  };
  double escape_start_s = -1, contact_s = -1, turn_s = -1, resumed_s = -1;
  for (double t = 0; t < 90 && resumed_s < 0; t += 0.1) {
    c.OnPose(pose, t);
    Scan scan = MakeScan(INFINITY, INFINITY);
    scan.stamp_s = t;
    const Velocity v = c.OnScan(t, scan);
    if (v.source == "escape" && escape_start_s < 0) escape_start_s = t;
    if (escape_start_s >= 0 && contact_s < 0 && v.source != "escape") contact_s = t;
    if (contact_s >= 0 && turn_s < 0 && v.source == "recovery" && v.angular_radps != 0) turn_s = t;
    if (turn_s >= 0 && v.source == "escape") resumed_s = t;
    pose = Drive(pose, v, 0.1, debris);
  }
  ASSERT_GE(escape_start_s, 0.0);
  ASSERT_GE(contact_s, 0.0) << "the escape never stopped at the debris";
  ASSERT_GE(turn_s, 0.0) << "no turn after the contact";
  ASSERT_GE(resumed_s, 0.0) << "the escape did not go on";
  EXPECT_LT(contact_s - escape_start_s, 6.0);  // reached at 0.25 m/s, then one contact window
  EXPECT_LT(resumed_s, escape_start_s + o.recovery.escape_s);
}

TEST(ExploreControllerTest, NothingLeftToExploreGoesHomeAndStops) {
  ExploreController c{NoLookAround()};
  const Grid done = ClosedRoom();
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);  // home
  c.OnMap(done);
  c.OnPose(common::Rigid2d(2.0, 2.0, M_PI), 0.0);
  double t = 0;
  common::Rigid2d pose(2.0, 2.0, M_PI);
  for (; t < 30 && c.status().state != "home"; t += 0.1) {
    const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
    // Integrate the command: the robot does what it is told.
    pose = pose * common::Rigid2d(v.linear_mps * 0.1, 0.0, v.angular_radps * 0.1);
    c.OnPose(pose, 0.0);
  }
  EXPECT_EQ(c.status().state, "home");
  EXPECT_LT((pose.translation() - Eigen::Vector2d(1.0, 2.0)).norm(), 0.35);
  EXPECT_EQ(c.OnScan(t + 1, MakeScan(INFINITY, INFINITY)).linear_mps, 0.0);
}

// Exploration ends when no plan reaches a frontier; if frontiers are reached again on the way
// home (a doorway SLAM drew closed is open in the next map), the robot explores again.
TEST(ExploreControllerTest, FrontiersReachedAgainOnTheWayHomeResumeTheExploration) {
  ExploreController c{NoLookAround()};
  const Grid done = ClosedRoom();
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);  // home
  c.OnMap(done);
  common::Rigid2d pose(2.5, 2.0, M_PI);
  c.OnPose(pose, 0.0);
  double t = 0;
  auto step = [&] {
    const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
    pose = pose * common::Rigid2d(v.linear_mps * 0.1, 0.0, v.angular_radps * 0.1);
    c.OnPose(pose, 0.0);
    t += 0.1;
  };
  while (t < 10 && c.status().state != "returning") step();
  ASSERT_EQ(c.status().state, "returning");
  c.OnMap(PartlyKnownRoom());  // the unknown part is back
  while (t < 20 && c.status().state == "returning") step();
  EXPECT_EQ(c.status().state, "exploring");
  EXPECT_EQ(c.status().goal_kind, "frontier");

  // Returning for the time budget is not undone by frontiers.
  ExploreOptions o = NoLookAround();
  o.goals.time_budget_s = 1;
  ExploreController budget{o};
  budget.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  budget.OnMap(PartlyKnownRoom());
  common::Rigid2d p2(2.5, 2.0, M_PI);
  budget.OnPose(p2, 0.0);
  bool explored_again = false, returned = false;
  for (double u = 0; u < 20 && budget.status().state != "home"; u += 0.1) {
    const Velocity v = budget.OnScan(u, MakeScan(INFINITY, INFINITY));
    p2 = p2 * common::Rigid2d(v.linear_mps * 0.1, 0.0, v.angular_radps * 0.1);
    budget.OnPose(p2, 0.0);
    returned |= budget.status().state == "returning";
    explored_again |= returned && budget.status().state == "exploring";
  }
  EXPECT_TRUE(returned);
  EXPECT_FALSE(explored_again);
}

// when_explored: sweep: with nothing left to explore the robot searches the site again, the
// longest-unvisited place first, and the time budget still brings it home.
TEST(ExploreControllerTest, SweepRevisitsTheExploredSiteUntilTheTimeBudget) {
  ExploreOptions o = NoLookAround();
  o.goals.when_explored = "sweep";
  o.goals.sweep_cell_m = 1.0;
  o.goals.sweep_min_age_s = 20;
  const Grid done = ClosedRoom();  // a closed 2.5 x 4 m room
  auto run = [&](const ExploreOptions& options, double seconds,
                 std::set<std::pair<int, int>>* cells) {
    ExploreController c{options};
    common::Rigid2d pose(1.0, 1.0, 0.0);
    c.OnPose(pose, 0.0);
    c.OnMap(done);
    for (double t = 0; t < seconds && c.status().state != "home"; t += 0.1) {
      const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
      pose = pose * common::Rigid2d(v.linear_mps * 0.1, 0.0, v.angular_radps * 0.1);
      c.OnPose(pose, 0.0);
      if (cells)
        cells->insert({static_cast<int>(std::floor(pose.translation().x())),
                       static_cast<int>(std::floor(pose.translation().y()))});
    }
    return std::make_pair(c.status().state, pose);
  };
  std::set<std::pair<int, int>> cells;
  const auto [state, pose] = run(o, 150, &cells);
  EXPECT_EQ(state, "sweeping");
  // The room's eight 1 m cells (2 of its 3 columns are whole): most of them driven through.
  EXPECT_GE(cells.size(), 6u);
  // With a time budget, home at the end.
  o.goals.time_budget_s = 60;
  const auto [end_state, end_pose] = run(o, 120, nullptr);
  EXPECT_EQ(end_state, "home");
  EXPECT_LT((end_pose.translation() - Eigen::Vector2d(1.0, 1.0)).norm(), 0.35);
}

TEST(ExploreControllerTest, HeardPersonBecomesAGoalInViewOfThem) {
  ExploreOptions o = NoLookAround();
  o.mode = "sound_guided";
  ExploreController c{o};
  const Grid g = KnownRoom();
  c.OnMap(g);
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  HeardPerson p;
  p.id = 7;
  p.position_m = Eigen::Vector2d(5.0, 1.0);
  p.position_std_m = 0.5;
  c.OnPeopleMap({p}, {p.position_m});
  c.OnScan(0.0, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(c.status().state, "seeking_sound");
  ASSERT_TRUE(c.status().goal_m);
  const double d = (*c.status().goal_m - p.position_m).norm();
  EXPECT_GE(d, o.sound.min_view_m - 0.1);
  EXPECT_LE(d, o.sound.max_view_m + 0.1);
  // Behind a wall: no cell in view, so the cheapest one in range (parallax for the microphones).
  Grid walled = g;
  for (int y = 1; y < walled.height - 1; ++y)
    walled.cells[y * walled.width + 44] = 100;  // x = 4.4 m
  ExploreController cover{o};
  cover.OnMap(walled);
  cover.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  cover.OnPeopleMap({p}, {p.position_m});
  cover.OnScan(0.0, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(cover.status().goal_kind, "sound");
  ASSERT_TRUE(cover.status().goal_m);
  EXPECT_LT(cover.status().goal_m->x(), 4.4);
  EXPECT_LE((*cover.status().goal_m - p.position_m).norm(), o.sound.max_view_m + 0.1);
  // Placed too uncertainly: not a goal (frontier exploration instead).
  ExploreController vague{o};
  vague.OnMap(PartlyKnownRoom());
  vague.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  p.position_std_m = 5.0;
  vague.OnPeopleMap({p}, {p.position_m});
  vague.OnScan(0.0, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(vague.status().goal_kind, "frontier");
}

// A voice on SOUND_MAP that nobody on PEOPLE_MAP explains is a goal (the robot goes near to
// listen); one within seen_radius_m of a person on PEOPLE_MAP is that person.
TEST(ExploreControllerTest, AVoiceNobodyOnThePeopleMapExplainsBecomesAGoal) {
  ExploreOptions o = NoLookAround();
  o.mode = "sound_guided";
  o.sound.voices = true;
  const Grid g = KnownRoom();
  HeardPerson voice;
  voice.id = 3;
  voice.position_m = Eigen::Vector2d(5.0, 1.0);
  voice.position_std_m = 1.0;
  const auto goal_kind = [&](const ExploreOptions& options, std::vector<Eigen::Vector2d> people_m) {
    ExploreController c{options};
    c.OnMap(g);
    c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
    c.OnPeopleMap({}, std::move(people_m));
    c.OnVoices({voice});
    c.OnScan(0.0, MakeScan(INFINITY, INFINITY));
    if (c.status().goal_kind == "sound") {
      const double d = (*c.status().goal_m - voice.position_m).norm();
      EXPECT_GE(d, options.sound.min_view_m - 0.1);
      EXPECT_LE(d, options.sound.max_view_m + 0.1);
    }
    return c.status().goal_kind;
  };
  EXPECT_EQ(goal_kind(o, {}), "sound");
  // Someone on the people map 1 m away: the voice is theirs.
  EXPECT_EQ(goal_kind(o, {Eigen::Vector2d(5.0, 2.0)}), "frontier");
  // ... 2 m away: not theirs.
  EXPECT_EQ(goal_kind(o, {Eigen::Vector2d(5.0, 3.0)}), "sound");
  ExploreOptions off = o;
  off.sound.voices = false;
  EXPECT_EQ(goal_kind(off, {}), "frontier");
  voice.position_std_m = 2.0;  // placed too uncertainly
  EXPECT_EQ(goal_kind(o, {}), "frontier");
}

// At a voice the robot stands still for listen_s (a call heard with the robot still is kept by
// the sound map), then the voice's place is visited and exploration goes on.
TEST(ExploreControllerTest, AtAVoiceTheRobotStandsStillForListenS) {
  ExploreOptions o = NoLookAround();
  o.mode = "sound_guided";
  o.sound.voices = true;
  Grid room = ClosedRoom();  // a closed 2.5 x 4 m room
  HeardPerson voice;
  voice.id = 3;
  voice.position_m = Eigen::Vector2d(3.5, 2.0);
  voice.position_std_m = 1.0;
  const auto longest_still_s = [&](double listen_s) {
    ExploreOptions options = o;
    options.sound.listen_s = listen_s;
    ExploreController c{options};
    common::Rigid2d pose(1.0, 1.0, 0.0);
    c.OnPose(pose, 0.0);
    c.OnMap(room);
    c.OnVoices({voice});
    double still_s = 0, longest = 0;
    bool sought = false;
    for (double t = 0; t < 60; t += 0.1) {
      const Velocity v = c.OnScan(t, MakeScan(INFINITY, INFINITY));
      sought |= c.status().goal_kind == "sound";
      const bool still = v.linear_mps == 0 && v.angular_radps == 0;
      still_s = still && c.status().goal_kind == "sound" ? still_s + 0.1 : 0;
      longest = std::max(longest, still_s);
      pose = pose * common::Rigid2d(v.linear_mps * 0.1, 0.0, v.angular_radps * 0.1);
      c.OnPose(pose, 0.0);
    }
    EXPECT_TRUE(sought);
    EXPECT_NE(c.status().goal_kind, "sound");  // visited: not a goal again
    return longest;
  };
  EXPECT_NEAR(longest_still_s(8.0), 8.0, 0.25);
  EXPECT_NEAR(longest_still_s(3.0), 3.0, 0.25);
}

TEST(ExploreControllerTest, TeleopOverridesOnThisProcessClockClampedAndEmergencyStopHolds) {
  ExploreController c{NoLookAround()};
  c.OnMap(PartlyKnownRoom());
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  TeleopCommand t;
  t.receive_time_s = 1.0;
  t.override_active = true;
  t.linear_mps = 1e6;  // clamped
  c.OnTeleop(t);
  const Velocity v = c.OnScan(1.2, MakeScan(2, 2));
  EXPECT_EQ(v.source, "teleop");
  EXPECT_EQ(v.linear_mps, ExploreOptions().teleop_max_linear_mps);
  EXPECT_NE(c.OnScan(2.0, MakeScan(INFINITY, INFINITY)).source, "teleop");  // override timed out
  t.receive_time_s = 3.0;
  t.emergency_stop = true;
  c.OnTeleop(t);
  const Velocity stop = c.OnScan(9.0, MakeScan(2, 2));  // holds after the timeout too
  EXPECT_EQ(stop.source, "stop");
  EXPECT_EQ(stop.linear_mps, 0);
}

TEST(ExploreControllerTest, ADriveDuringAnEmergencyStopDoesNotReleaseIt) {
  ExploreController c{NoLookAround()};
  c.OnMap(PartlyKnownRoom());
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0), 0.0);
  TeleopCommand stop;
  stop.receive_time_s = 1.0;
  stop.emergency_stop = true;
  c.OnTeleop(stop);
  EXPECT_EQ(c.OnScan(1.1, MakeScan(2, 2)).source, "stop");
  // The operator drives the stopped robot: obeyed while the override lasts...
  TeleopCommand drive;
  drive.receive_time_s = 2.0;
  drive.override_active = true;
  drive.linear_mps = 0.2;
  c.OnTeleop(drive);
  const Velocity driven = c.OnScan(2.1, MakeScan(2, 2));
  EXPECT_EQ(driven.source, "teleop");
  EXPECT_DOUBLE_EQ(driven.linear_mps, 0.2);
  // ...ended by zero-speed overrides, after which the robot is stopped again, not autonomous.
  drive.receive_time_s = 2.2;
  drive.linear_mps = 0;
  c.OnTeleop(drive);
  const Velocity after = c.OnScan(5.0, MakeScan(INFINITY, INFINITY));
  EXPECT_EQ(after.source, "stop");
  EXPECT_EQ(after.linear_mps, 0);
  EXPECT_TRUE(c.emergency_stop());
  // A message with neither stop nor override is the release.
  TeleopCommand release;
  release.receive_time_s = 6.0;
  c.OnTeleop(release);
  EXPECT_FALSE(c.emergency_stop());
  EXPECT_NE(c.OnScan(6.1, MakeScan(INFINITY, INFINITY)).source, "stop");
}

TEST(StatusMessageTest, EveryNthPathPointAndTheLastOne) {
  ExploreStatus s;
  s.state = "exploring";
  s.goal_m = Eigen::Vector2d(3.0, 1.0);
  s.goal_kind = "frontier";
  for (int i = 0; i < 10; ++i) s.path.emplace_back(0.1 * i, 0.0);
  const sarmap::explore_status_t m = ToStatusMessage(s, 42, 4);
  ASSERT_EQ(m.num_path, 4);  // points 0, 4, 8 and the last, 9
  EXPECT_FLOAT_EQ(m.path_x_m[2], 0.8f);
  EXPECT_FLOAT_EQ(m.path_x_m[3], 0.9f);
  EXPECT_TRUE(m.has_goal);
  EXPECT_EQ(m.header.utime, 42);
  EXPECT_EQ(ToStatusMessage(s, 42).num_path, 10);
}

TEST(ExploreMessagesTest, HeardPeopleAreGoalsWithTheirLargestStd) {
  sarmap::people_map_t m{};
  sarmap::mapped_person_t heard{};
  heard.id = 4;
  heard.position_m[0] = 2.0;
  heard.position_m[1] = -1.0;
  heard.covariance[0] = 0.25;  // x std 0.5 m
  heard.covariance[4] = 1.0;   // y std 1.0 m: the largest
  heard.cues = sarmap::mapped_person_t::CUE_HEARD | sarmap::mapped_person_t::CUE_SEEN_DEPTH;
  sarmap::mapped_person_t seen_only = heard;
  seen_only.id = 5;
  seen_only.cues = sarmap::mapped_person_t::CUE_SEEN_RGBD;
  m.people = {heard, seen_only};
  m.num_people = 2;
  const std::vector<HeardPerson> goals = HeardPeopleFromMessage(m);
  ASSERT_EQ(goals.size(), 1u);
  EXPECT_EQ(goals[0].id, 4);
  EXPECT_NEAR(goals[0].position_m.x(), 2.0, 1e-12);
  EXPECT_NEAR(goals[0].position_m.y(), -1.0, 1e-12);
  EXPECT_NEAR(goals[0].position_std_m, 1.0, 1e-9);
  EXPECT_TRUE(goals[0].seen);
}

TEST(ExploreMessagesTest, VoicesArePlacedSourcesClassedVoice) {
  sarmap::sound_map_t m{};
  sarmap::sound_source_t voice{};
  voice.id = 9;
  voice.has_position = true;
  voice.position_m[0] = 1.0;
  voice.position_m[1] = 2.0;
  voice.covariance[0] = 0.04;
  voice.covariance[4] = 0.09;  // y std 0.3 m: the largest
  voice.covariance[8] = 1.0;   // height: not planar
  voice.priority = sarmap::sound_source_t::PRIORITY_CALL;
  sarmap::sound_source_t machine = voice;
  machine.id = 10;
  machine.priority = sarmap::sound_source_t::PRIORITY_NONE;
  sarmap::sound_source_t bearing = voice;
  bearing.id = 11;
  bearing.has_position = false;
  sarmap::sound_source_t broken = voice;
  broken.id = 12;
  broken.covariance[0] = NAN;
  m.sources = {voice, machine, bearing, broken};
  m.num_sources = 4;
  const std::vector<HeardPerson> voices = VoicesFromMessage(m);
  ASSERT_EQ(voices.size(), 1u);
  EXPECT_EQ(voices[0].id, 9);
  EXPECT_NEAR(voices[0].position_m.y(), 2.0, 1e-12);
  EXPECT_NEAR(voices[0].position_std_m, 0.3, 1e-9);
  EXPECT_FALSE(voices[0].seen);
}

TEST(ExploreMessagesTest, PeoplePositionsAreEveryoneOnTheMap) {
  sarmap::people_map_t m{};
  sarmap::mapped_person_t seen{};
  seen.position_m[0] = 3.0;
  seen.cues = sarmap::mapped_person_t::CUE_SEEN_RGBD;
  sarmap::mapped_person_t heard = seen;
  heard.position_m[1] = 4.0;
  heard.cues = sarmap::mapped_person_t::CUE_HEARD;
  m.people = {seen, heard};
  m.num_people = 2;
  const std::vector<Eigen::Vector2d> people = PeoplePositionsFromMessage(m);
  ASSERT_EQ(people.size(), 2u);
  EXPECT_NEAR(people[1].y(), 4.0, 1e-12);
  EXPECT_EQ(HeardPeopleFromMessage(m).size(), 1u);
}

}  // namespace
}  // namespace explore
}  // namespace sarmap
