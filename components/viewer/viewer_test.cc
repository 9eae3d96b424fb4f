#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>

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

// PM_INFO and NODE_STATUS from ever new names: without the limits the page's lists grow without
// end (/api/state reaches 42 MB).
TEST(ViewerStateTest, ProcessAndNodeListsShrinkAndStayBounded) {
  ViewerLimits limits;
  limits.forget_after_s = 30;
  ViewerState state(limits);
  const double t0 = 1000;
  state.SetProcesses("compute", {{"", "sarmap-slam", "running", 1, 0, 1, 1}}, t0);
  state.SetNode({"sarmap-slam", "ok", 0, t0});
  const std::string long_name(1000, 'x');
  for (int i = 0; i < 200; ++i) {
    std::vector<ProcessView> many(100, ProcessView{"", long_name, "running", 1, 0, 1, 1});
    state.SetProcesses("flood-" + std::to_string(i) + long_name, std::move(many), t0 + 1);
    state.SetNode({"node-" + std::to_string(i) + long_name, long_name, 0, t0 + 1});
  }
  auto j = nlohmann::json::parse(state.Json(t0 + 1));
  EXPECT_EQ(j["processes"].size(),
            static_cast<size_t>(limits.max_deputies * limits.max_commands_per_deputy));
  EXPECT_EQ(j["nodes"].size(), static_cast<size_t>(limits.max_nodes));
  for (const auto& p : j["processes"]) {
    EXPECT_LE(p["deputy"].get<std::string>().size(), static_cast<size_t>(limits.max_text_bytes));
    EXPECT_LE(p["command"].get<std::string>().size(), static_cast<size_t>(limits.max_text_bytes));
  }
  const size_t bounded_bytes = state.Json(t0 + 1).size();
  EXPECT_LT(bounded_bytes, 1u << 20);
  printf(
      "FIGURE /api/state after 200 deputies x 100 commands and 200 nodes, names 1000 bytes: %zu "
      "bytes\n",
      bounded_bytes);
  // Not heard from for forget_after_s: gone from the page; the list shrinks back.
  state.SetProcesses("compute", {{"", "sarmap-slam", "running", 1, 0, 1, 1}}, t0 + 40);
  state.SetNode({"sarmap-slam", "ok", 0, t0 + 40});
  j = nlohmann::json::parse(state.Json(t0 + 40));
  ASSERT_EQ(j["processes"].size(), 1u);
  EXPECT_EQ(j["processes"][0]["deputy"], "compute");
  ASSERT_EQ(j["nodes"].size(), 1u);
  EXPECT_EQ(j["nodes"][0]["name"], "sarmap-slam");
  EXPECT_TRUE(nlohmann::json::parse(state.Json(t0 + 100))["processes"].empty());
}

TEST(ViewerStateTest, AnyStringFromTheBusGivesValidJson) {
  ViewerState state;
  PersonView p{1,     0,     0,    Ellipse(), 0.5,
               false, false, true, 1,         "\xff\xfe<b>\"\\\n" + std::string(300, 'a')};
  state.SetPeople({p, p});
  state.SetProcesses(std::string("d\xc3", 2), {{"", "\xe2\x82", "running", 1, 0, 1, 1}}, 0);
  std::string json;
  ASSERT_NO_THROW(json = state.Json(0));
  const auto j = nlohmann::json::parse(json);
  EXPECT_EQ(j["people"].size(), 2u);
  EXPECT_LE(j["people"][0]["keyword"].get<std::string>().size(), 200u + 6u);  // + replacements
  EXPECT_EQ(ClipText("ab\xc3\xa9", 3), "ab");  // never half a character
}

// A client that sends its request a byte every 0.3 s. Returns when the server hangs up (or
// after `limit_s`).
void TrickleClient(int port, double limit_s, std::atomic<int>* hung_up) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    close(fd);
    return;
  }
  const std::string request =
      "GET /api/state HTTP/1.1\r\nHost: x\r\nX-Slow: " + std::string(1000, 'a');
  for (size_t i = 0; i < request.size() && i * 0.3 < limit_s; ++i) {
    if (send(fd, &request[i], 1, MSG_NOSIGNAL) != 1) {
      ++*hung_up;
      break;
    }
    usleep(300000);
  }
  close(fd);
}

// Nine slow connections: with per-read timeouts only, each holds a worker thread for as long as
// it keeps sending and everyone else is locked out of the page.
TEST(ViewerServerTest, SlowClientsDoNotLockOthersOut) {
  ViewerState state;
  FillDemoScene(&state);
  ServerOptions options{"127.0.0.1", 0, ""};
  options.threads = 4;  // fewer workers than slow clients
  options.connection_limit_s = 2;
  options.io_timeout_s = 1;
  ViewerServer server(&state, options);
  server.Start();
  std::atomic<int> hung_up{0};
  std::vector<std::thread> slow;
  for (int i = 0; i < 9; ++i) slow.emplace_back(TrickleClient, server.port(), 60.0, &hung_up);
  usleep(500000);  // the slow ones first
  httplib::Client client("127.0.0.1", server.port());
  client.set_read_timeout(30, 0);
  client.set_connection_timeout(30, 0);
  auto res = client.Get("/api/state");
  ASSERT_TRUE(res) << httplib::to_string(res.error());
  EXPECT_EQ(res->status, 200);
  EXPECT_TRUE(nlohmann::json::parse(res->body)["map"]["available"].get<bool>());
  for (auto& t : slow) t.join();
  EXPECT_EQ(hung_up.load(), 9);  // every slow client was cut off, none sent its request
  server.Stop();
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
