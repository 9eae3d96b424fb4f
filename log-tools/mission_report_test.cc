#include "log-tools/mission_report.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "common/bus_auth.h"
#include "log-tools/lcm_log_writer.h"
#include "sarmap/doa_source_t.hpp"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

void SetStart(sarmap::sim_truth_t* t, double x, double y, double yaw) {
  t->start_pose[0] = x;
  t->start_pose[1] = y;
  t->start_pose[2] = yaw;
}

sarmap::mapped_person_t Person(int64_t id, double x, double y, int cues, const std::string& keyword = "") {
  sarmap::mapped_person_t p{};
  p.id = id;
  p.position_m[0] = x;
  p.position_m[1] = y;
  p.covariance[0] = p.covariance[4] = p.covariance[8] = 0.04;
  p.confidence = 0.8f;
  p.cues = static_cast<int8_t>(cues);
  p.keyword = keyword;
  p.people_count = 1;
  return p;
}

TEST(MissionReportTest, FoundVersusTruthFromALog) {
  const std::string path = ::testing::TempDir() + "/mission.lcmlog";
  {
    logtools::LcmLogWriter log(path);
    sarmap::occupancy_grid_t grid{};
    grid.resolution_m = 0.1;
    grid.width = 80;
    grid.height = 60;
    grid.data.assign(80 * 60, 0);
    for (int x = 0; x < 80; ++x) grid.data[x] = grid.data[59 * 80 + x] = 100;
    grid.size = static_cast<int32_t>(grid.data.size());
    log.Write("MAP", grid, 1'000'000);
    for (int i = 0; i < 20; ++i) {
      sarmap::pose_t pose{};
      pose.orientation[0] = 1;
      pose.header.utime = 1'000'000 + i * 100'000;
      pose.position_m[0] = 1 + 0.2 * i;
      pose.position_m[1] = 3;
      log.Write("POSE", pose, pose.header.utime);
    }
    sarmap::people_map_t people{};
    people.people = {Person(1, 2.0, 1.0, sarmap::mapped_person_t::CUE_SEEN_RGBD),
                     Person(2, 6.1, 4.9, sarmap::mapped_person_t::CUE_HEARD, "help"),
                     Person(3, 7.5, 1.0, sarmap::mapped_person_t::CUE_SEEN_DEPTH)};  // nobody there
    people.num_people = 3;
    log.Write("PEOPLE_MAP", people, 3'000'000);
    // A sound source near the map and one that has not converged, hundreds of metres away
    // with a huge covariance: the PNG must still show the map at a readable scale.
    sarmap::sound_map_t sounds{};
    sarmap::sound_source_t near{}, far{};
    near.id = 1;
    near.position_m[0] = 5.0;
    near.position_m[1] = 2.0;
    near.covariance[0] = near.covariance[4] = near.covariance[8] = 0.01;
    far.id = 2;
    far.position_m[0] = 300.0;
    far.position_m[1] = -200.0;
    far.covariance[0] = far.covariance[4] = far.covariance[8] = 1e6;
    // The report reads what the stack accepts (DecodeMessage): a known state each.
    near.state = sarmap::sound_source_t::STATE_CONVERGED;
    far.state = sarmap::sound_source_t::STATE_INITIALISING;
    near.has_position = far.has_position = true;
    sounds.sources = {near, far};
    sounds.num_sources = 2;
    log.Write("SOUND_MAP", sounds, 3'000'000);
    // The simulator's frame is the map frame shifted by (10, -2) and turned by 90 degrees:
    // truth = R(90) * map + (10, -2), i.e. the robot started at (10, -2, 90 deg) in the world.
    const auto to_truth = [](double x, double y) { return std::make_pair(-y + 10.0, x - 2.0); };
    for (int i = 0; i < 20; ++i) {
      sarmap::sim_truth_t t{};
      t.header.utime = 1'000'000 + i * 100'000;
      t.robot_orientation[0] = 1;
      const auto p = to_truth(1 + 0.2 * i, 3);
      t.robot_position_m[0] = p.first;
      t.robot_position_m[1] = p.second;
      SetStart(&t, 10, -2, M_PI / 2);
      log.Write("SIM_TRUTH", t, t.header.utime);
    }
    sarmap::sim_truth_t truth{};
    truth.header.utime = 3'000'000;
    truth.robot_orientation[0] = 1;
    SetStart(&truth, 10, -2, M_PI / 2);
    const double positions[3][2] = {{2.1, 1.1}, {6.0, 5.2}, {4.0, 5.5}};  // map frame
    for (int i = 0; i < 3; ++i) {
      sarmap::sim_person_t p{};
      p.id = i;
      p.name = "person" + std::to_string(i);
      const auto q = to_truth(positions[i][0], positions[i][1]);
      p.position_m[0] = q.first;
      p.position_m[1] = q.second;
      truth.people.push_back(p);
    }
    truth.num_people = 3;
    log.Write("SIM_TRUTH", truth, 3'000'000);
  }
  const MissionData data = LoadMission(path);
  EXPECT_TRUE(data.map);
  EXPECT_GT(data.trail.size(), 10u);
  const MissionSummary s = Summarise(data, 0.5);
  EXPECT_EQ(s.alignment.method, "start pose");
  EXPECT_EQ(s.alignment.pairs, 20);
  EXPECT_NEAR(s.alignment.rms_m, 0.0, 1e-9);
  EXPECT_NEAR(s.alignment.yaw_rad, -M_PI / 2, 1e-9);  // map_from_truth
  // The trail fit (the consistency check) agrees on this drift-free trail.
  EXPECT_EQ(s.trail_fit.method, "trail fit");
  EXPECT_NEAR(s.trail_fit.rms_m, 0.0, 1e-9);
  EXPECT_NEAR(s.trail_fit.yaw_rad, -M_PI / 2, 1e-9);
  ASSERT_EQ(s.truth.size(), 3u);
  EXPECT_TRUE(s.truth[0].found);
  EXPECT_EQ(s.truth[0].how, "seen");
  EXPECT_NEAR(s.truth[0].error_m, std::hypot(0.1, 0.1), 1e-9);
  EXPECT_TRUE(s.truth[1].found);
  EXPECT_EQ(s.truth[1].how, "heard");
  EXPECT_FALSE(s.truth[2].found);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_NE(SummaryText(data, s).find("2 of 3 people found"), std::string::npos);

  const std::string dir = ::testing::TempDir() + "/mission-report";
  WriteReport(data, s, dir);
  struct stat st;
  ASSERT_EQ(stat((dir + "/map.png").c_str(), &st), 0);
  EXPECT_GT(st.st_size, 5000);
  {
    // PNG width and height: big-endian at bytes 16 and 20. The 8 x 6 m map at its scale, not
    // stretched to the far source.
    std::ifstream png(dir + "/map.png", std::ios::binary);
    unsigned char header[24];
    png.read(reinterpret_cast<char*>(header), sizeof(header));
    const auto be32 = [&](int at) {
      return (header[at] << 24) | (header[at + 1] << 16) | (header[at + 2] << 8) | header[at + 3];
    };
    EXPECT_LE(be32(16), 1500);
    EXPECT_LE(be32(20), 1500);
    EXPECT_GE(be32(16), 500);  // still drawn at a readable scale
  }
  std::ifstream json(dir + "/report.json");
  const auto j = nlohmann::json::parse(json);
  EXPECT_EQ(j["truth"].size(), 3u);
  // The source hundreds of metres away is listed apart, not as a mapped source.
  EXPECT_EQ(j["sound_sources"].size(), 1u);
  ASSERT_EQ(j["outside_map"].size(), 1u);
  EXPECT_EQ(j["outside_map"][0]["kind"], "sound source");
  EXPECT_EQ(j["outside_map"][0]["id"], 2);
  EXPECT_EQ(j["false_positives"], 1);
  std::ifstream html_file(dir + "/report.html");
  const std::string html((std::istreambuf_iterator<char>(html_file)), {});
  EXPECT_NE(html.find("missed"), std::string::npos);
}

// The robot never moves (a mission stopped at once, or a base that does not start): every POSE
// is the identity, so a trail fit is undetermined and put the true people elsewhere. The start
// pose aligns exactly: both people found, no false positive, and every mission figure present.
TEST(MissionReportTest, ARobotThatDoesNotMove) {
  const std::string path = ::testing::TempDir() + "/still.lcmlog";
  const double sx = 3.0, sy = 1.0, syaw = 2.0;  // start pose in the world
  // map_from_world: R(-yaw) (w - s).
  const auto to_map = [&](double x, double y) {
    const double dx = x - sx, dy = y - sy;
    return std::make_pair(std::cos(syaw) * dx + std::sin(syaw) * dy,
                          -std::sin(syaw) * dx + std::cos(syaw) * dy);
  };
  const double people[2][2] = {{5.0, 2.0}, {1.0, -1.0}};  // world
  {
    logtools::LcmLogWriter log(path);
    sarmap::explore_status_t status{};
    status.state = "exploring";
    status.has_goal = true;
    status.goal_kind = "frontier";
    status.goal_m[0] = 1.5;
    status.num_path = 2;
    status.path_x_m = {0.0f, 1.5f};
    status.path_y_m = {0.0f, 0.0f};
    log.Write("EXPLORE_STATUS", status, 1'000'000);
    // The reachable floor: 2 x 2 m around the start, at 0.1 m.
    sarmap::occupancy_grid_t floor{};
    floor.resolution_m = 0.1;
    floor.width = floor.height = 20;
    floor.origin_x_m = sx - 1;
    floor.origin_y_m = sy - 1;
    floor.data.assign(400, 0);
    floor.size = 400;
    log.Write("SIM_FLOOR", floor, 1'000'000);
    for (int i = 0; i <= 50; ++i) {
      const int64_t utime = 1'000'000 + i * 100'000;
      sarmap::pose_t pose{};
      pose.header.utime = utime;
      pose.orientation[0] = 1;
      log.Write("POSE", pose, utime);
      sarmap::sim_truth_t t{};
      t.header.utime = utime;
      t.robot_position_m[0] = sx;
      t.robot_position_m[1] = sy;
      t.robot_orientation[0] = std::cos(syaw / 2);
      t.robot_orientation[3] = std::sin(syaw / 2);
      SetStart(&t, sx, sy, syaw);
      for (int k = 0; k < 2; ++k) {
        sarmap::sim_person_t p{};
        p.id = k;
        p.name = "person" + std::to_string(k);
        p.position_m[0] = people[k][0];
        p.position_m[1] = people[k][1];
        t.people.push_back(p);
      }
      t.num_people = 2;
      log.Write("SIM_TRUTH", t, utime);
      if (i == 20) {
        // SLAM's map: 6 x 6 m around its origin, all observed.
        sarmap::occupancy_grid_t grid{};
        grid.resolution_m = 0.05;
        grid.width = grid.height = 120;
        grid.origin_x_m = grid.origin_y_m = -3;
        grid.data.assign(120 * 120, 0);
        grid.size = static_cast<int32_t>(grid.data.size());
        log.Write("MAP", grid, utime);
      }
      if (i == 30) {
        sarmap::people_map_t found{};
        const auto a = to_map(people[0][0], people[0][1]), b = to_map(people[1][0], people[1][1]);
        found.people = {
            Person(1, a.first + 0.1, a.second, sarmap::mapped_person_t::CUE_SEEN_RGBD),
            Person(2, b.first, b.second - 0.2, sarmap::mapped_person_t::CUE_HEARD, "help")};
        found.num_people = 2;
        log.Write("PEOPLE_MAP", found, utime);
      }
    }
  }
  const MissionData data = LoadMission(path);
  const MissionSummary s = Summarise(data, 0.5);
  EXPECT_EQ(s.alignment.method, "start pose");
  EXPECT_NEAR(s.alignment.yaw_rad, -syaw, 1e-12);
  EXPECT_NEAR(s.alignment.rms_m, 0.0, 1e-12);  // POSE stays at the map origin: the start pose
  EXPECT_EQ(s.trail_fit.method, "none (trail too short)");
  ASSERT_EQ(s.truth.size(), 2u);
  EXPECT_TRUE(s.truth[0].found);
  EXPECT_NEAR(s.truth[0].error_m, 0.1, 1e-9);
  EXPECT_TRUE(s.truth[1].found);
  EXPECT_NEAR(s.truth[1].error_m, 0.2, 1e-9);
  EXPECT_EQ(s.false_positives, 0);
  ASSERT_TRUE(s.truth[0].found_after_s);
  EXPECT_NEAR(*s.truth[0].found_after_s, 3.0, 1e-9);
  // Judged (EXPLORE_STATUS exploring) but the 5 s mission is shorter than the 10 s window.
  ASSERT_TRUE(s.metrics.stuck_s);
  EXPECT_EQ(*s.metrics.stuck_s, 0.0);
  ASSERT_TRUE(s.metrics.mapped_fraction);
  EXPECT_DOUBLE_EQ(*s.metrics.mapped_fraction, 1.0);
  EXPECT_NEAR(*s.metrics.reachable_m2, 4.0, 1e-9);

  const std::string dir = ::testing::TempDir() + "/still-report";
  WriteReport(data, s, dir);
  std::ifstream json(dir + "/report.json");
  const auto j = nlohmann::json::parse(json);
  EXPECT_EQ(j["false_positives"], 0);
  EXPECT_EQ(j["alignment"]["method"], "start pose");
  EXPECT_NEAR(j["coverage"]["reachable_m2"].get<double>(), 4.0, 1e-9);
  EXPECT_NEAR(j["coverage"]["mapped_m2"].get<double>(), 4.0, 1e-9);
  EXPECT_DOUBLE_EQ(j["coverage"]["mapped_fraction"].get<double>(), 1.0);
  ASSERT_EQ(j["coverage"]["curve"].size(), 1u);
  EXPECT_EQ(j["coverage"]["curve"][0].size(), 3u);
  EXPECT_NEAR(j["coverage"]["curve"][0][0].get<double>(), 2.0, 1e-9);
  EXPECT_EQ(j["collisions"], 0);
  EXPECT_EQ(j["distance_m"], 0.0);
  EXPECT_EQ(j["stuck_s"], 0.0);
  EXPECT_EQ(j["longest_stuck_s"], 0.0);
  EXPECT_EQ(j["came_home"], false);
  EXPECT_TRUE(j["home_after_s"].is_null());
  EXPECT_NEAR(j["truth"][1]["found_after_s"].get<double>(), 3.0, 1e-9);
  struct stat st;
  EXPECT_EQ(stat((dir + "/coverage.png").c_str(), &st), 0);
  std::ifstream html_file(dir + "/report.html");
  const std::string html((std::istreambuf_iterator<char>(html_file)), {});
  EXPECT_NE(html.find("<h2>Mission</h2>"), std::string::npos);
  EXPECT_NE(html.find("coverage.png"), std::string::npos);
  EXPECT_NE(SummaryText(data, s).find("2 of 2 people found"), std::string::npos);
  EXPECT_NE(SummaryText(data, s).find("coverage: 4.0 of 4.0 m2"), std::string::npos);
}

// Without SIM_TRUTH (a real robot) the mission keys are present and null.
TEST(MissionReportTest, NoTruthMissionKeysAreNull) {
  const std::string path = ::testing::TempDir() + "/no-truth.lcmlog";
  {
    logtools::LcmLogWriter log(path);
    sarmap::people_map_t people{};
    log.Write("PEOPLE_MAP", people, 1'000'000);
  }
  const MissionData data = LoadMission(path);
  const MissionSummary s = Summarise(data, 0.5);
  const std::string dir = ::testing::TempDir() + "/no-truth-report";
  WriteReport(data, s, dir);
  std::ifstream json(dir + "/report.json");
  const auto j = nlohmann::json::parse(json);
  for (const char* key :
       {"collisions", "distance_m", "stuck_s", "longest_stuck_s", "came_home", "home_after_s"}) {
    EXPECT_TRUE(j[key].is_null()) << key;
  }
  EXPECT_TRUE(j["coverage"]["mapped_fraction"].is_null());
  EXPECT_TRUE(j["coverage"]["curve"].empty());
  EXPECT_FALSE(j.contains("truth"));
}

// A log that recorded hostile datagrams (a header.frame length of INT32_MIN, ten million
// sound sources in 36 bytes) loads: they are skipped, the valid messages around them are kept.
TEST(MissionReportTest, HostileMessagesInTheLogAreSkipped) {
  const std::string path = ::testing::TempDir() + "/hostile.lcmlog";
  {
    logtools::LcmLogWriter log(path);
    sarmap::sound_map_t sounds{};
    sounds.header.frame = "map";
    sounds.num_sources = 1;
    sounds.sources.resize(1);
    sounds.sources[0].id = 7;
    sounds.sources[0].state = sarmap::sound_source_t::STATE_CONVERGED;
    log.Write("SOUND_MAP", sounds, 1'000'000);
    sarmap::sound_map_t empty{};
    empty.header.frame = "map";
    std::vector<uint8_t> wire(empty.getEncodedSize());
    empty.encode(wire.data(), 0, static_cast<int>(wire.size()));
    ASSERT_EQ(wire.size(), 36u);  // fingerprint, utime, seq, "map", num_sources
    std::vector<uint8_t> frame_attack = wire, count_attack = wire;
    const uint8_t int32_min[4] = {0x80, 0, 0, 0}, ten_million[4] = {0x00, 0x98, 0x96, 0x80};
    std::copy(int32_min, int32_min + 4, frame_attack.begin() + 24);
    std::copy(ten_million, ten_million + 4, count_attack.begin() + 32);
    for (std::vector<uint8_t>* attack : {&frame_attack, &count_attack}) {
      log.WriteBytes("SOUND_MAP", *attack, 2'000'000);
    }
  }
  const MissionData data = LoadMission(path);
  EXPECT_EQ(data.messages, 3);
  ASSERT_TRUE(data.sources.has_value());
  ASSERT_EQ(data.sources->sources.size(), 1u);
  EXPECT_EQ(data.sources->sources[0].id, 7);
}

// On a signed bus, a PEOPLE_MAP that another host put on the bus is in the log but, read with
// the bus key, never becomes the report's people; without the key the report shows the last.
TEST(MissionReportTest, WithTheBusKeyForgedMessagesDoNotCount) {
  const std::string path = ::testing::TempDir() + "/signed_bus.lcmlog";
  const common::AuthKey key(32, 0x5a);
  {
    logtools::LcmLogWriter log(path);
    common::BusAuth stack(key);
    auto write = [&](const sarmap::people_map_t& m, int64_t utime, bool sign) {
      std::vector<uint8_t> buf(m.getEncodedSize());
      m.encode(buf.data(), 0, static_cast<int>(buf.size()));
      if (sign) stack.Sign("PEOPLE_MAP", &buf);
      log.WriteBytes("PEOPLE_MAP", buf, utime);
    };
    sarmap::people_map_t real{};
    real.header.utime = 1'000'000;
    real.header.frame = "map";
    real.people.push_back(Person(1, 1.0, 1.0, 1));
    real.num_people = 1;
    write(real, 1'000'000, true);
    sarmap::people_map_t forged = real;
    forged.header.utime = 2'000'000;
    forged.people[0] = Person(1, 9.0, 9.0, 1);
    write(forged, 2'000'000, false);
  }
  const MissionData open_bus = LoadMission(path);
  ASSERT_TRUE(open_bus.people.has_value());
  ASSERT_EQ(open_bus.people->people.size(), 1u);
  EXPECT_EQ(open_bus.people->people[0].position_m[0], 9.0);  // the signed people map is read too

  std::vector<std::string> problems;
  const MissionData signed_bus = LoadMission(path, &problems, {}, key);
  ASSERT_TRUE(signed_bus.people.has_value());
  ASSERT_EQ(signed_bus.people->people.size(), 1u);
  EXPECT_EQ(signed_bus.people->people[0].position_m[0], 1.0);
  ASSERT_FALSE(problems.empty());
  EXPECT_NE(problems.back().find("1 not signed with the bus key"), std::string::npos)
      << problems.back();
}

// The simulator's emitters against the sound map: placed sources are matched and their class
// scored; a bearing is listed apart (never placed, drawn or matched); a mapped person on a
// non-voice emitter is counted.
TEST(MissionReportTest, SoundSourcesAreScoredAgainstTheEmitters) {
  const std::string path = ::testing::TempDir() + "/sources.lcmlog";
  {
    logtools::LcmLogWriter log(path);
    for (int i = 0; i < 10; ++i) {  // the robot drives from (0, 0) to (4.5, 0); truth = map
      sarmap::pose_t pose{};
      pose.header.utime = 1'000'000 + i * 100'000;
      pose.header.frame = "map";
      pose.position_m[0] = 0.5 * i;
      pose.orientation[0] = 1;
      log.Write("POSE", pose, pose.header.utime);
      sarmap::sim_truth_t t{};
      t.header.utime = pose.header.utime;
      t.robot_position_m[0] = 0.5 * i;
      t.robot_orientation[0] = 1;
      log.Write("SIM_TRUTH", t, t.header.utime);
    }
    sarmap::sim_truth_t truth{};
    truth.header.utime = 2'000'000;
    truth.robot_position_m[0] = 4.5;
    truth.robot_orientation[0] = 1;
    const struct {
      const char* name;
      int8_t kind;
      double x, y;
    } emitters[] = {{"carol_voice", sarmap::sim_sound_source_t::KIND_VOICE, 2.0, 1.5},
                    {"smoke_alarm", sarmap::sim_sound_source_t::KIND_ALARM, 4.0, -1.0},
                    {"servers", sarmap::sim_sound_source_t::KIND_NOISE, 1.0, -1.5}};
    for (const auto& e : emitters) {
      sarmap::sim_sound_source_t src{};
      src.name = e.name;
      src.kind = e.kind;
      src.position_m[0] = e.x;
      src.position_m[1] = e.y;
      src.person_id = -1;
      truth.sources.push_back(src);
    }
    truth.num_sources = 3;
    log.Write("SIM_TRUTH", truth, 2'000'000);
    sarmap::sound_map_t sounds{};
    sounds.header.utime = 2'000'000;
    sounds.header.frame = "map";
    auto source = [](int64_t id, double x, double y, int8_t cls, bool placed, bool person) {
      sarmap::sound_source_t s{};
      s.id = id;
      s.position_m[0] = x;
      s.position_m[1] = y;
      s.covariance[0] = s.covariance[4] = 0.02;
      s.state = sarmap::sound_source_t::STATE_CONVERGED;
      s.has_position = placed;
      s.sound_class = cls;
      s.class_confidence = 0.9f;
      s.is_person = person;
      return s;
    };
    sounds.sources = {
        source(1, 2.2, 1.4, sarmap::doa_source_t::SOUND_CLASS_VOICE, true, true),
        source(2, 3.8, -1.1, sarmap::doa_source_t::SOUND_CLASS_MUSIC, true, true),
        // The servers heard but not yet ranged: a bearing from (0.5, 0).
        source(3, 0.5, 0.0, sarmap::doa_source_t::SOUND_CLASS_MACHINERY, false, false)};
    sounds.sources[2].bearing_rad = std::atan2(-1.5, 0.5);
    sounds.num_sources = 3;
    log.Write("SOUND_MAP", sounds, 2'000'000);
  }
  const MissionSummary s = Summarise(LoadMission(path), 0.5);
  EXPECT_EQ(s.sources_mapped, 2);
  ASSERT_EQ(s.source_truth.size(), 3u);
  EXPECT_TRUE(s.source_truth[0].found);
  EXPECT_TRUE(s.source_truth[0].class_right);
  EXPECT_NEAR(s.source_truth[0].error_m, std::hypot(0.2, 0.1), 1e-6);
  EXPECT_TRUE(s.source_truth[1].found);
  EXPECT_EQ(s.source_truth[1].mapped_class, "music");
  EXPECT_FALSE(s.source_truth[1].class_right);
  EXPECT_FALSE(s.source_truth[2].found);  // a bearing is not a placed source
  EXPECT_EQ(s.non_voice_people, 1);       // the "person" on the alarm
  bool bearing_listed = false;
  for (const auto& o : s.outside_map)
    bearing_listed |= o.id == 3 && o.why.find("bearing") != std::string::npos;
  EXPECT_TRUE(bearing_listed);
}

// A log of an attacked bus (make demo-hostile): a valid map sent on another type's channel and
// messages stamped a year ahead of their channel's clock are skipped, so the report's map and
// people are the stack's own; a map that passes (stamped behind) with an extent a double barely
// holds still gives a report, not an OpenCV assertion.
TEST(MissionReportTest, AnAttackedBusStillGivesTheStacksReport) {
  const std::string path = ::testing::TempDir() + "/attacked.lcmlog";
  constexpr int64_t kYearUs = 365LL * 24 * 3600 * 1000000;
  sarmap::occupancy_grid_t map{};
  map.resolution_m = 0.1;
  map.width = map.height = 10;
  map.data.assign(100, 0);
  map.size = 100;
  sarmap::occupancy_grid_t huge = map;
  huge.origin_x_m = -1e300;
  huge.origin_y_m = 1e300;
  huge.resolution_m = 1e300;
  sarmap::people_map_t people{};
  people.num_people = 1;
  people.people = {Person(1, 0.5, 0.5, 1)};
  sarmap::people_map_t far_people = people;
  far_people.people[0].position_m[0] = 50;
  {
    logtools::LcmLogWriter log(path);
    for (int i = 0; i < 10; ++i) {
      const int64_t utime = 1'000'000 + i * 100'000;
      map.header.utime = people.header.utime = utime;
      log.Write("MAP", map, utime);
      log.Write("PEOPLE_MAP", people, utime);
      huge.header.utime = far_people.header.utime = utime + kYearUs;
      log.Write("MAP", huge, utime);               // a year ahead
      log.Write("PEOPLE_MAP", far_people, utime);  // a year ahead
      huge.header.utime = utime;
      log.Write("CMD_VEL", huge, utime);  // a map where velocity commands go
    }
  }
  std::vector<std::string> problems;
  MissionData data = LoadMission(path, &problems);
  ASSERT_TRUE(data.map.has_value());
  EXPECT_EQ(data.map->resolution_m, 0.1);
  ASSERT_TRUE(data.people.has_value());
  ASSERT_EQ(data.people->people.size(), 1u);
  EXPECT_EQ(data.people->people[0].position_m[0], 0.5);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("10 messages of another type"), std::string::npos) << problems[0];
  EXPECT_NE(problems[0].find("20 stamped far ahead"), std::string::npos) << problems[0];

  huge.header.utime = 0;  // behind: passes, as it would in a node
  data.map = huge;
  const std::string dir = ::testing::TempDir() + "/attacked_report";
  EXPECT_NO_THROW(WriteReport(data, Summarise(data, 0.5), dir));
  struct stat st;
  EXPECT_EQ(stat((dir + "/map.png").c_str(), &st), 0);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
