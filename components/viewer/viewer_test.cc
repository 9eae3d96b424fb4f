#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "viewer/demo_scene.h"
#include "viewer/viewer_server.h"
// After Eigen: <resolv.h> (through httplib) defines a macro `_res` that Eigen uses as a name.
#include <httplib.h>

namespace sarmap {
namespace viewer {
namespace {

TEST(ViewerStateTest, ThreeSigmaEllipse) {
  const Ellipse e = ThreeSigmaEllipse((Eigen::Matrix2d() << 4, 0, 0, 1).finished());
  EXPECT_NEAR(e.major_m, 6.0, 1e-9);
  EXPECT_NEAR(e.minor_m, 3.0, 1e-9);
  EXPECT_NEAR(std::abs(std::sin(e.angle_rad)), 0.0, 1e-9);
  // Rotated by 45 degrees.
  const Ellipse r = ThreeSigmaEllipse((Eigen::Matrix2d() << 2.5, 1.5, 1.5, 2.5).finished());
  EXPECT_NEAR(r.major_m, 6.0, 1e-9);
  EXPECT_NEAR(std::abs(std::tan(r.angle_rad)), 1.0, 1e-9);
}

TEST(ViewerStateTest, JsonCarriesEverythingThePageDraws) {
  ViewerState state;
  FillDemoScene(&state);
  const auto j = nlohmann::json::parse(state.Json(common::SteadySeconds()));
  EXPECT_TRUE(j["map"]["available"].get<bool>());
  EXPECT_EQ(j["people"].size(), 3u);
  EXPECT_EQ(j["people"][1]["cue"], "heard");
  EXPECT_EQ(j["people"][1]["keyword"], "help");
  EXPECT_EQ(j["people"][2]["cue"], "both");
  EXPECT_EQ(j["people"][2]["count"], 2);
  EXPECT_EQ(j["sources"].size(), 2u);
  EXPECT_EQ(j["processes"].size(), 2u);
  EXPECT_NEAR(j["robot"]["x_m"].get<double>(), 4.5, 1e-9);
  EXPECT_GT(j["trail"].size(), 30u);
  EXPECT_EQ(j["scan"].size(), 40u);
  EXPECT_EQ(j["mission"]["state"], "seeking_sound");
  EXPECT_EQ(j["mission"]["goal_kind"], "sound");
  EXPECT_NEAR(j["mission"]["goal"][0].get<double>(), 2.9, 1e-9);
  EXPECT_EQ(j["mission"]["path"].size(), 11u);
  // A deputy not heard from for over 3 s is shown as lost.
  const auto later = nlohmann::json::parse(state.Json(common::SteadySeconds() + 10));
  EXPECT_EQ(later["processes"][0]["state"], "deputy lost");
  // The map PNG: right size, unknown grey, walls black.
  const auto png = state.MapPng();
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png[1], 'P');
}

TEST(ViewerServerTest, ServesThePageReadOnlyBehindTheToken) {
  ViewerState state;
  ViewerServer server(&state, {"127.0.0.1", 0, "s3cret-token"});
  server.Start();
  httplib::Client client("127.0.0.1", server.port());
  EXPECT_EQ(client.Get("/")->status, 401);
  EXPECT_EQ(client.Get("/api/state?token=wrong-token!")->status, 401);
  auto page = client.Get("/?token=s3cret-token");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<canvas id=\"map\">"), std::string::npos);
  httplib::Headers bearer = {{"Authorization", "Bearer s3cret-token"}};
  auto api = client.Get("/api/state", bearer);
  ASSERT_TRUE(api);
  EXPECT_EQ(api->status, 200);
  EXPECT_FALSE(nlohmann::json::parse(api->body)["map"]["available"].get<bool>());
  EXPECT_EQ(client.Get("/api/map.png", bearer)->status, 404);  // no map yet
  FillDemoScene(&state);
  auto png = client.Get("/api/map.png", bearer);
  EXPECT_EQ(png->status, 200);
  EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(client.Post("/api/state", bearer, "x", "text/plain")->status, 405);
  server.Stop();
}

}  // namespace
}  // namespace viewer
}  // namespace sarmap
