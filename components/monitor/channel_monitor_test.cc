#include "monitor/channel_monitor.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace monitor {
namespace {

TEST(ChannelMonitorTest, RateOverTheWindowAndGaps) {
  ChannelMonitor m(2.0);
  for (int i = 0; i < 60; ++i) m.OnMessage("DEPTH", 10.0 + i / 30.0, i == 30 ? 2 : 0);
  EXPECT_NEAR(m.RateHz("DEPTH", 12.0), 30.0, 0.6);
  EXPECT_NEAR(m.RateHz("DEPTH", 13.5), 7.5, 0.6);  // only the last 0.5 s remains in the window
  EXPECT_EQ(m.channels().at("DEPTH").gaps, 2);
  EXPECT_EQ(m.RateHz("NONE", 12.0), 0.0);
  EXPECT_NE(m.Table(12.0).find("DEPTH"), std::string::npos);
}

}  // namespace
}  // namespace monitor
}  // namespace sarmap
