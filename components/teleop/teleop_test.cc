// sarmap-teleop: requests, plans, stamps, and its messages through the explorer's gate over
// memq:// (signed ones obeyed; unsigned, forged, tampered and replayed ones refused).
#include "teleop/teleop.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/args.h"
#include "common/command_auth.h"
#include "common/node.h"
#include "common/testing/test_keys.h"
#include "sarmap/explore_status_t.hpp"
#include "teleop/teleop_sender.h"

namespace sarmap {
namespace teleop {
namespace {

using common::testing_util::TestKey;

TEST(TeleopTest, RequestsParseAndBadOnesSayWhy) {
  TeleopOptions options;
  EXPECT_EQ(ParseRequest({"stop"}, options).action, Action::kStop);
  EXPECT_EQ(ParseRequest({"release"}, options).action, Action::kRelease);
  const Request drive = ParseRequest({"drive", "-0.2", "0.5", "2.5"}, options);
  EXPECT_EQ(drive.action, Action::kDrive);
  EXPECT_DOUBLE_EQ(drive.linear_mps, -0.2);
  EXPECT_DOUBLE_EQ(drive.angular_radps, 0.5);
  EXPECT_DOUBLE_EQ(drive.duration_s, 2.5);
  EXPECT_DOUBLE_EQ(ParseRequest({"drive", "0.1", "0"}, options).duration_s, 1.0);
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{},
                                             {"go"},
                                             {"stop", "now"},
                                             {"drive", "0.1"},
                                             {"drive", "fast", "0"},
                                             {"drive", "nan", "0"},
                                             {"drive", "0.1", "inf"},
                                             {"drive", "0.1", "0", "0"},
                                             {"drive", "0.1", "0", "1000"},
                                             {"drive", "0.1", "0", "1", "2"}}) {
    EXPECT_THROW(ParseRequest(bad, options), common::ArgError) << (bad.empty() ? "" : bad[0]);
  }
}

TEST(TeleopTest, PlansRepeatStopsAndEndEveryDrive) {
  TeleopOptions options;
  options.rate_hz = 10;
  options.repeat = 4;
  const auto stop = PlanRequest(ParseRequest({"stop"}, options), options);
  ASSERT_EQ(stop.size(), 4u);
  for (const auto& s : stop) EXPECT_TRUE(s.emergency_stop && !s.override_active);

  const auto release = PlanRequest(ParseRequest({"release"}, options), options);
  ASSERT_EQ(release.size(), 4u);
  for (const auto& s : release) EXPECT_TRUE(!s.emergency_stop && !s.override_active);

  const auto drive = PlanRequest(ParseRequest({"drive", "0.3", "-0.4", "1.5"}, options), options);
  ASSERT_EQ(drive.size(), 15u + 4u);
  for (size_t i = 0; i < drive.size(); ++i) {
    EXPECT_NEAR(drive[i].at_s, 0.1 * static_cast<double>(i), 1e-9);
    EXPECT_FALSE(drive[i].emergency_stop);
    // The override ends explicitly, at zero speed and still an override: the end of a drive
    // is not a release, so it never ends an emergency stop.
    EXPECT_TRUE(drive[i].override_active) << i;
    EXPECT_EQ(drive[i].ends_drive, i >= 15) << i;
    EXPECT_EQ(drive[i].linear_mps, i < 15 ? 0.3 : 0.0) << i;
    EXPECT_EQ(drive[i].angular_radps, i < 15 ? -0.4 : 0.0) << i;
  }
}

TEST(TeleopTest, StampsAlwaysIncrease) {
  Stamper stamper;
  EXPECT_EQ(stamper.Next(1000), 1000);
  EXPECT_EQ(stamper.Next(1000), 1001);  // two messages within a microsecond
  EXPECT_EQ(stamper.Next(500), 1002);   // the clock stepped back
  EXPECT_EQ(stamper.Next(2000), 2000);
}

TEST(TeleopTest, StatusConfirmsWhatWasAsked) {
  EXPECT_TRUE(StatusConfirms(Action::kStop, "stop"));
  EXPECT_FALSE(StatusConfirms(Action::kStop, "planner"));
  EXPECT_TRUE(StatusConfirms(Action::kDrive, "teleop"));
  EXPECT_FALSE(StatusConfirms(Action::kDrive, "stop"));
  EXPECT_TRUE(StatusConfirms(Action::kRelease, "planner"));
  EXPECT_FALSE(StatusConfirms(Action::kRelease, "stop"));
  EXPECT_FALSE(StatusConfirms(Action::kRelease, ""));
}

TEST(TeleopTest, OptionsAreValidated) {
  TeleopOptions options;
  options.rate_hz = 1;  // the explorer's 0.5 s dead man would lapse between messages
  common::Validator check;
  common::CheckOptions(options, &check);
  EXPECT_EQ(check.errors().size(), 1u);
}

// The explorer's side of TELEOP: its CommandGate, on the messages as they arrive.
struct Explorer {
  explicit Explorer(common::Node* node, common::AuthKey key) : gate(std::move(key)) {
    node->Subscribe<teleop_t>("TELEOP", [this](const teleop_t& m, const common::ReceiveInfo&) {
      std::string why;
      if (gate.Accept(m, &why)) {
        obeyed.push_back(m);
      } else {
        refused.push_back(why);
      }
    });
  }
  common::CommandGate gate;
  std::vector<teleop_t> obeyed;
  std::vector<std::string> refused;
};

void Handle(common::Node* node, size_t n) {
  for (size_t i = 0; i < n; ++i) ASSERT_GT(node->lcm().handleTimeout(1000), 0);
}

TEST(TeleopTest, ExplorerObeysTheToolsSignedTeleopAndRefusesUnsignedForgedAndReplayed) {
  common::Node node("teleop_test", "memq://");
  const common::AuthKey key = TestKey(1);
  Explorer explorer(&node, key);
  TeleopOptions options;
  options.operator_id = "operator@laptop";

  // The tool with the explorer's key: stop, drive, release, every message obeyed in order.
  TeleopSender tool(&node, options, key);
  ASSERT_TRUE(tool.signs());
  size_t sent = 0;
  for (const std::vector<std::string>& words : std::vector<std::vector<std::string>>{
           {"stop"}, {"drive", "0.2", "0.1", "0.3"}, {"release"}}) {
    for (const Step& step : PlanRequest(ParseRequest(words, options), options)) {
      tool.Send(step);
      ++sent;
      Handle(&node, 1);
    }
  }
  ASSERT_EQ(explorer.obeyed.size(), sent);
  EXPECT_TRUE(explorer.refused.empty());
  EXPECT_TRUE(explorer.obeyed.front().emergency_stop);
  EXPECT_EQ(explorer.obeyed.front().operator_id, "operator@laptop");
  EXPECT_FALSE(explorer.obeyed.back().emergency_stop || explorer.obeyed.back().override_active);

  // Without the key, or with another one: refused, and the explorer stays released.
  Step stop;
  stop.emergency_stop = true;
  TeleopSender unsigned_tool(&node, options, {});
  EXPECT_FALSE(unsigned_tool.signs());
  unsigned_tool.Send(stop);
  TeleopSender forger(&node, options, TestKey(2));
  forger.Send(stop);
  Handle(&node, 2);
  ASSERT_EQ(explorer.refused.size(), 2u);
  for (const auto& why : explorer.refused)
    EXPECT_NE(why.find("not signed"), std::string::npos) << why;

  // A signed drive captured on the way: sped up, or played back, it is refused.
  Step drive;
  drive.override_active = true;
  drive.linear_mps = 0.1;
  const teleop_t captured = tool.Send(drive);
  Handle(&node, 1);
  ASSERT_EQ(explorer.obeyed.size(), sent + 1);
  auto publish_raw = [&](const teleop_t& m) { node.lcm().publish("TELEOP", &m); };
  teleop_t tampered = captured;
  tampered.linear_mps = 5.0;
  tampered.header.utime += 1;
  publish_raw(tampered);
  publish_raw(captured);
  Handle(&node, 2);
  ASSERT_EQ(explorer.refused.size(), 4u);
  EXPECT_NE(explorer.refused[2].find("not signed"), std::string::npos) << explorer.refused[2];
  EXPECT_NE(explorer.refused[3].find("replay"), std::string::npos) << explorer.refused[3];

  // The tool's next stop still acts.
  tool.Send(stop);
  Handle(&node, 1);
  ASSERT_EQ(explorer.obeyed.size(), sent + 2);
  EXPECT_TRUE(explorer.obeyed.back().emergency_stop);
}

TEST(TeleopTest, AnOperatorIdThatCannotBeSignedIsNotSent) {
  common::Node node("teleop_test", "memq://");
  Explorer explorer(&node, TestKey(1));
  TeleopOptions options;
  options.operator_id = std::string("op\0x", 4);
  TeleopSender tool(&node, options, TestKey(1));
  EXPECT_THROW(tool.Send(Step{}), std::runtime_error);
  EXPECT_EQ(node.lcm().handleTimeout(50), 0);  // nothing was published
}

// An explorer that reports on EXPLORE_STATUS what drives it once it obeyed a TELEOP.
struct ReportingExplorer : Explorer {
  ReportingExplorer(common::Node* node, common::AuthKey key, bool reports)
      : Explorer(node, std::move(key)),
        status(node->Advertise<explore_status_t>("EXPLORE_STATUS")) {
    node->Subscribe<teleop_t>(
        "TELEOP", [this, reports](const teleop_t& m, const common::ReceiveInfo&) {
          if (!reports || obeyed.empty()) return;
          explore_status_t s{};
          s.driven_by = m.emergency_stop ? "stop" : m.override_active ? "teleop" : "frontier";
          status.Publish(&s);
        });
  }
  common::Node::Publisher<explore_status_t> status;
};

TEST(TeleopTest, SendAndConfirmWaitsForTheStatusThatShowsTheCommandObeyed) {
  TeleopOptions options;
  options.rate_hz = 50;
  options.confirm_timeout_s = 0.3;
  const Request stop = ParseRequest({"stop"}, options);
  {
    // The explorer obeys and says so: exit 0, every planned step sent.
    common::Node node("teleop_test", "memq://");
    ReportingExplorer explorer(&node, TestKey(1), true);
    EXPECT_EQ(SendAndConfirm(&node, options, stop, TestKey(1)), 0);
    while (node.lcm().handleTimeout(50) > 0) {
    }
    EXPECT_EQ(explorer.obeyed.size(), PlanRequest(stop, options).size());
    EXPECT_TRUE(explorer.obeyed.back().emergency_stop);
  }
  {
    // Another key: refused, nothing confirms it within the timeout: exit 1.
    common::Node node("teleop_test", "memq://");
    ReportingExplorer explorer(&node, TestKey(1), true);
    EXPECT_EQ(SendAndConfirm(&node, options, stop, TestKey(2)), 1);
    EXPECT_TRUE(explorer.obeyed.empty());
    EXPECT_FALSE(explorer.refused.empty());
  }
  {
    // No confirmation asked for: exit 0 once sent.
    options.confirm_timeout_s = 0;
    common::Node node("teleop_test", "memq://");
    ReportingExplorer explorer(&node, TestKey(1), false);
    EXPECT_EQ(SendAndConfirm(&node, options, ParseRequest({"release"}, options), TestKey(1)), 0);
  }
}

}  // namespace
}  // namespace teleop
}  // namespace sarmap
