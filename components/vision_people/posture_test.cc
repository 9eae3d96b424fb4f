// People in other postures than standing: lying on the floor, sitting; one person is one
// detection; things that do not touch the floor are not people.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "vision_people/people_detector.h"
#include "vision_people/synthetic_scene.h"

namespace sarmap {
namespace vision_people {
namespace {

constexpr double kDeg = M_PI / 180;

DetectorOptions DepthOnly() {
  DetectorOptions o;
  o.color.hog = "none";
  return o;
}

void PrintCandidates(const DetectionResult& r) {
  for (const auto* list : {&r.people, &r.rejected}) {
    for (const auto& c : *list) {
      printf(
          "  %s%s pos (%.2f %.2f %.2f) H %.2f bottom %.2f length %.2f width %.2f depth %.2f relief "
          "%.2f "
          "head %.2f/%.2f prom %.2f areas %.3f/%.3f fill %.2f vis %.2f score %.2f\n",
          c.accepted ? "PERSON" : "reject", c.lying ? " lying" : "", c.position_camera.x(),
          c.position_camera.y(), c.position_camera.z(), c.height_m, c.bottom_m, c.length_m,
          c.width_m, c.depth_extent_m, c.relief_m, c.head_width_m, c.shoulder_width_m,
          c.head_prominence_m, c.head_area_m2, c.shoulder_area_m2, c.fill, c.visible_fraction,
          c.depth_score);
    }
  }
}

// Distance on the floor between a detection and a person (camera x, z).
double FloorDistance(const SyntheticScene& scene, const SyntheticPerson& p,
                     const PersonCandidate& c) {
  const Eigen::Vector3d t = scene.PersonInCamera(p);
  return std::hypot(t.x() - c.position_camera.x(), t.z() - c.position_camera.z());
}

TEST(Posture, LyingPeopleFoundFromDepthAlone) {
  int frames = 0, found = 0, extra = 0;
  for (double cam_h : {0.4, 0.9}) {
    for (double pitch_deg : {0.0, -15.0}) {
      for (double yaw_deg : {0.0, 60.0, 120.0}) {
        for (double x : {2.2, 3.4}) {
          SyntheticScene scene;
          scene.camera_height_m = cam_h;
          scene.camera_pitch_rad = pitch_deg * kDeg;
          SyntheticPerson p{x, 0.3, 1.7, yaw_deg * kDeg, SyntheticPerson::kLying};
          scene.people.push_back(p);
          if (scene.VisibleFraction(0) < 0.9) continue;
          PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
          RgbdFrame frame;
          RenderFrame(scene, 31, false, &frame);
          const DetectionResult r = detector.Detect(frame);
          ++frames;
          bool hit = false;
          for (const auto& c : r.people) {
            const bool near = FloorDistance(scene, p, c) < 0.5;
            hit = hit || (near && c.lying);
            extra += !near;
          }
          extra += r.people.size() > 1 ? static_cast<int>(r.people.size()) - 1 : 0;
          found += hit;
          if (!hit) {
            printf("missed: camera %.1f m pitch %.0f, yaw %.0f, x %.1f\n", cam_h, pitch_deg,
                   yaw_deg, x);
            PrintCandidates(r);
          }
        }
      }
    }
  }
  printf("lying: %d/%d found, %d extra detections\n", found, frames, extra);
  ASSERT_GE(frames, 16);  // the others had an end of the body outside the image
  EXPECT_EQ(found, frames);
  EXPECT_EQ(extra, 0);
}

// A body-sized crate on the floor has a flat top: no person. Nor has a low table or a chair.
TEST(Posture, FlatSlabsAndFurnitureAreNotLyingPeople) {
  int false_positives = 0, frames = 0;
  for (double yaw_deg : {0.0, 30.0, 90.0}) {
    for (double h : {0.2, 0.3, 0.45}) {
      SyntheticScene scene;
      scene.camera_height_m = 0.6;
      scene.camera_pitch_rad = -10 * kDeg;
      scene.objects.push_back({SyntheticObject::kSlab, 2.6, 0.2, yaw_deg * kDeg, h});
      scene.objects.push_back({SyntheticObject::kChair, 3.4, -0.9, yaw_deg * kDeg, 0});
      scene.objects.push_back({SyntheticObject::kBox, 3.6, 1.0, 0.3, 0.35});
      PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
      RgbdFrame frame;
      RenderFrame(scene, 5, false, &frame);
      const DetectionResult r = detector.Detect(frame);
      ++frames;
      false_positives += static_cast<int>(r.people.size());
      if (!r.people.empty()) {
        printf("slab yaw %.0f height %.2f:\n", yaw_deg, h);
        PrintCandidates(r);
      }
    }
  }
  EXPECT_EQ(false_positives, 0) << "in " << frames << " frames";
}

TEST(Posture, SittingPeopleFoundOnce) {
  int frames = 0, found = 0, extra = 0;
  // Side-on (yaw +-90) the shoulders lie along the viewing ray, inside the head's ellipse, and
  // the highest point beside the head is the lap, 0.7 m below it (more than shoulders): the
  // shoulders are then looked for in every direction (max_sitting_height_m).
  for (double yaw_deg : {180.0, 135.0, 45.0, 0.0, 90.0, -90.0}) {
    for (double x : {2.5, 3.5}) {
      SyntheticScene scene;
      scene.camera_height_m = 0.7;
      SyntheticPerson p{x, -0.2, 1.75, yaw_deg * kDeg, SyntheticPerson::kSitting};
      scene.people.push_back(p);
      if (scene.VisibleFraction(0) < 0.9) continue;
      PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
      RgbdFrame frame;
      RenderFrame(scene, 41, false, &frame);
      const DetectionResult r = detector.Detect(frame);
      ++frames;
      bool hit = false;
      for (const auto& c : r.people) {
        const bool near = FloorDistance(scene, p, c) < 0.5;
        hit = hit || near;
      }
      extra += std::max(0, static_cast<int>(r.people.size()) - 1);
      found += hit;
      if (!hit || r.people.size() != 1) {
        printf("sitting yaw %.0f x %.1f:\n", yaw_deg, x);
        PrintCandidates(r);
      }
    }
  }
  ASSERT_GE(frames, 4);
  EXPECT_EQ(found, frames);
  EXPECT_EQ(extra, 0);
}

// An arm held up above the head is no head: one person, one detection.
TEST(Posture, RaisedArmIsOnePerson) {
  int frames = 0, found = 0, extra = 0;
  for (double yaw_deg : {180.0, 90.0, 0.0, 135.0}) {
    for (double raised : {0.1, 0.25}) {
      SyntheticScene scene;
      SyntheticPerson p{3.8, 0.2, 1.75, yaw_deg * kDeg};  // the hand in view up to 2.29 m
      p.arm_raised_m = raised;
      scene.people.push_back(p);
      PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
      RgbdFrame frame;
      RenderFrame(scene, 51, false, &frame);
      const DetectionResult r = detector.Detect(frame);
      ++frames;
      bool hit = false;
      for (const auto& c : r.people) hit = hit || FloorDistance(scene, p, c) < 0.5;
      found += hit;
      extra += std::max(0, static_cast<int>(r.people.size()) - 1);
      if (!hit || r.people.size() != 1) {
        printf("raised arm %.2f yaw %.0f:\n", raised, yaw_deg);
        PrintCandidates(r);
      }
    }
  }
  printf("raised arm: %d/%d found, %d extra detections\n", found, frames, extra);
  EXPECT_EQ(found, frames);
  EXPECT_EQ(extra, 0);
}

// A person standing with the back 0.08 m from a wall far away: one cluster, too large and
// too tall for a person (on real Kinect frames the range noise joins a person 0.3 m in front
// of a wall at 4 m the same way); without the wall the person is found.
TEST(Posture, PersonInFrontOfAWallIsFound) {
  int frames = 0, found = 0, found_without_split = 0, extra = 0;
  for (double x : {3.9, 4.3}) {
    for (double y : {-0.6, 0.0, 0.7}) {
      SyntheticScene scene;
      scene.camera_height_m = 1.06;
      scene.back_wall_m = x + 0.23;  // 0.08 m behind the body's back
      SyntheticPerson p{x, y, 1.75, 0.0};
      scene.people.push_back(p);
      if (scene.VisibleFraction(0) < 0.9) continue;
      RgbdFrame frame;
      RenderFrame(scene, 61, false, &frame);
      for (bool split : {true, false}) {
        DetectorOptions o = DepthOnly();
        o.split_walls = split;
        PeopleDetector detector(o, scene.ground(), nullptr);
        const DetectionResult r = detector.Detect(frame);
        bool hit = false;
        for (const auto& c : r.people) hit = hit || FloorDistance(scene, p, c) < 0.5;
        if (!split) {
          found_without_split += hit;
          continue;
        }
        ++frames;
        found += hit;
        extra += std::max(0, static_cast<int>(r.people.size()) - 1);
        if (!hit || r.people.size() != 1) {
          printf("person at %.1f, %.1f, wall at %.2f:\n", x, y, scene.back_wall_m);
          PrintCandidates(r);
        }
      }
    }
  }
  printf("in front of a wall: %d/%d found (%d without the wall split), %d extra detections\n",
         found, frames, found_without_split, extra);
  ASSERT_GE(frames, 4);
  EXPECT_EQ(found, frames);
  EXPECT_EQ(extra, 0);
  EXPECT_LT(found_without_split, frames);  // the case needs the split
}

// Office chairs whose headrests reach 1.0-1.05 m, in the dark, from several sides and
// ranges: no person. (On real frames: URFD's office chair, 1.02-1.05 m, and the dining
// chairs of kinect_slambook2_ch5, 1.01-1.03 m, stood as people in depth alone while the
// lowest standing person was 1.0 m. A headrest at 1.1 m still can.)
TEST(Posture, HighChairBacksAreNobody) {
  int frames = 0, detections = 0, detections_low_limit = 0;
  for (double top : {1.0, 1.05}) {
    for (double yaw_deg : {0.0, 45.0, 90.0, 180.0}) {
      for (double x : {2.0, 3.5}) {
        SyntheticScene scene;
        scene.camera_height_m = 0.9;
        SyntheticObject chair;
        chair.kind = SyntheticObject::kChair;
        chair.x_m = x;
        chair.y_m = 0.3;
        chair.yaw_rad = yaw_deg * kDeg;
        chair.height_m = top;
        scene.objects.push_back(chair);
        RgbdFrame frame;
        RenderFrame(scene, 71, true, &frame);
        ++frames;
        for (double min_height : {DepthShapeOptions().min_height_m, 1.0}) {
          DetectorOptions o = DepthOnly();
          o.shape.min_height_m = min_height;
          PeopleDetector detector(o, scene.ground(), nullptr);
          const DetectionResult r = detector.Detect(frame);
          (min_height == 1.0 ? detections_low_limit : detections) +=
              static_cast<int>(r.people.size());
          if (min_height != 1.0 && !r.people.empty()) {
            printf("chair back %.2f m, yaw %.0f, x %.1f:\n", top, yaw_deg, x);
            PrintCandidates(r);
          }
        }
      }
    }
  }
  printf(
      "high chair backs: %d detections in %d frames (%d with the lowest standing person at 1.0 "
      "m)\n",
      detections, frames, detections_low_limit);
  EXPECT_EQ(detections, 0);
  EXPECT_GT(detections_low_limit, 0);  // the case needs the limit
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
