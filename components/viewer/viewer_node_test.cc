// ViewerNode in-process over memq://: what arrives on the bus is in the page's state (and served
// over HTTP); a short token file is refused.
#include "viewer/viewer_node.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/message_conversions.h"
#include "common/time.h"
#include "sarmap/doa_source_t.hpp"

namespace sarmap {
namespace viewer {
namespace {

TEST(ViewerNodeTest, PoseScanPeopleAndSourcesOnTheBusReachThePage) {
  common::Node node("viewer_node_test", "memq://");
  ViewerNodeOptions options;
  options.port = 0;  // any free port
  ViewerNode adapter(options, &node);

  pose_t pose{};
  pose.header.utime = 1'000'000;
  pose.header.frame = "map";
  pose.position_m[0] = 2.0;
  pose.position_m[1] = 1.0;
  pose.orientation[0] = std::cos(M_PI / 4);  // facing +y
  pose.orientation[3] = std::sin(M_PI / 4);
  node.Advertise<pose_t>("POSE").Publish(&pose);

  laser_scan_t scan{};
  scan.header.utime = 1'000'000;
  scan.header.frame = "base";
  scan.angle_min_rad = 0;
  scan.angle_increment_rad = 0.1;
  scan.range_min_m = 0.1f;
  scan.range_max_m = 5.0f;
  scan.ranges_m = {1.0f, std::nanf(""), 9.0f};  // one return, one none, one beyond range
  scan.num_ranges = 3;
  node.Advertise<laser_scan_t>("SCAN").Publish(&scan);

  people_map_t people{};
  people.header.utime = 1'000'000;
  people.header.frame = "map";
  mapped_person_t person{};
  person.id = 7;
  person.position_m[0] = 3.0;
  person.position_m[1] = -1.0;
  person.covariance[0] = person.covariance[4] = person.covariance[8] = 0.01;
  person.confidence = 0.8f;
  person.cues = mapped_person_t::CUE_SEEN_DEPTH | mapped_person_t::CUE_HEARD;
  person.people_count = 1;
  person.keyword = "help";
  people.people.push_back(person);
  people.num_people = 1;
  node.Advertise<people_map_t>("PEOPLE_MAP").Publish(&people);

  sound_map_t sounds{};
  sounds.header.utime = 1'000'000;
  sounds.header.frame = "map";
  sound_source_t source{};
  source.id = 3;
  source.position_m[0] = -2.0;
  source.covariance[0] = source.covariance[4] = source.covariance[8] = 0.04;
  source.has_position = true;
  source.state = sound_source_t::STATE_CONVERGED;
  source.sound_class = doa_source_t::SOUND_CLASS_ALARM;
  sounds.sources.push_back(source);
  sounds.num_sources = 1;
  node.Advertise<sound_map_t>("SOUND_MAP").Publish(&sounds);
  for (int i = 0; i < 10; ++i) node.SpinOnce(0.001);

  const nlohmann::json state = nlohmann::json::parse(adapter.state().Json(common::SteadySeconds()));
  const std::string text = state.dump();
  EXPECT_NE(text.find("\"keyword\":\"help\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"alarm\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"converged\""), std::string::npos) << text;
  // The scan's one return, 1 m ahead of a robot at (2, 1) facing +y: at (2, 2).
  ASSERT_TRUE(state.contains("scan")) << text;
  ASSERT_EQ(state["scan"].size(), 1u) << text;
  EXPECT_NEAR(state["scan"][0][0].get<double>(), 2.0, 1e-6);
  EXPECT_NEAR(state["scan"][0][1].get<double>(), 2.0, 1e-6);

  // The same over HTTP.
  httplib::Client client("127.0.0.1", adapter.port());
  const auto reply = client.Get("/api/state");
  ASSERT_TRUE(reply) << "no reply from port " << adapter.port();
  EXPECT_EQ(reply->status, 200);
  EXPECT_NE(reply->body.find("\"keyword\":\"help\""), std::string::npos);
}

TEST(ViewerNodeTest, AShortTokenFileIsRefused) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "sarmap_viewer_node_test.token").string();
  FILE* f = fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  fputs("short\n", f);
  fclose(f);
  common::Node node("viewer_node_test", "memq://");
  ViewerNodeOptions options;
  options.port = 0;
  options.token_file = path;
  EXPECT_THROW(ViewerNode(options, &node), std::runtime_error);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace viewer
}  // namespace sarmap
