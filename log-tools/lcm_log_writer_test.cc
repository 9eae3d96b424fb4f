// LcmLogWriter: what it writes is what the tolerant reader reads back, and a file it cannot
// create is an error naming it.
#include "log-tools/lcm_log_writer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

#include "log-tools/lcm_log_reader.h"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

TEST(LcmLogWriterTest, EventsReadBackInOrderWithTheirTimesAndBytes) {
  const std::string path =
      ::testing::TempDir() + "/lcm_log_writer_" + std::to_string(getpid()) + ".lcmlog";
  {
    LcmLogWriter log(path);
    for (int i = 0; i < 3; ++i) {
      pose_t pose{};
      pose.header.utime = 1000 + i;
      pose.header.frame = "map";
      pose.orientation[0] = 1;
      log.Write("POSE", pose, 5000 + i);
    }
    const std::vector<uint8_t> junk = {1, 2, 3};
    log.WriteBytes("JUNK", junk, 9000);
    EXPECT_EQ(log.events(), 4);
    log.Flush();
  }
  LcmLogReader reader(path);
  LogEvent event;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(reader.Next(&event));
    EXPECT_EQ(event.event_number, i);
    EXPECT_EQ(event.timestamp_us, 5000 + i);
    EXPECT_EQ(event.channel, "POSE");
    pose_t pose;
    ASSERT_EQ(pose.decode(event.data.data(), 0, static_cast<int>(event.data.size())),
              static_cast<int>(event.data.size()));
    EXPECT_EQ(pose.header.utime, 1000 + i);
  }
  ASSERT_TRUE(reader.Next(&event));
  EXPECT_EQ(event.channel, "JUNK");
  EXPECT_EQ(event.data, std::vector<uint8_t>({1, 2, 3}));
  EXPECT_FALSE(reader.Next(&event));
  EXPECT_TRUE(reader.problems().empty());
  std::remove(path.c_str());
}

TEST(LcmLogWriterTest, AFileThatCannotBeCreatedIsAnErrorNamingIt) {
  try {
    LcmLogWriter log("/nonexistent-dir/x.lcmlog");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.lcmlog"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
