#include "log-tools/lcm_log_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <lcm/lcm-cpp.hpp>

#include <fstream>

#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

// Writes `n` pose_t events with lcm::LogFile, the library lcm-logger itself uses.
std::string WriteLog(int n) {
  // One file per test and process: CTest runs the cases of this file in parallel.
  const std::string path = ::testing::TempDir() + "/reader_test_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           std::to_string(getpid()) + ".lcmlog";
  lcm::LogFile log(path, "w");
  for (int i = 0; i < n; ++i) {
    sarmap::pose_t pose{};
    pose.header.utime = 1000000 + i * 100000;
    pose.header.seq = i == 5 ? 6 : i;  // seq 5 is "lost"... and 6 appears twice
    pose.header.frame = "map";
    pose.orientation[0] = 1;
    std::vector<uint8_t> buf(pose.getEncodedSize());
    pose.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent event;
    event.eventnum = i;
    event.timestamp = pose.header.utime;
    event.channel = "POSE";
    event.datalen = static_cast<int32_t>(buf.size());
    event.data = buf.data();
    log.writeEvent(&event);
  }
  return path;
}

TEST(LcmLogReaderTest, ReadsEveryEventWithTypeAndHeader) {
  LcmLogReader reader(WriteLog(10));
  LogEvent e;
  int n = 0;
  while (reader.Next(&e)) {
    EXPECT_EQ(e.channel, "POSE");
    EXPECT_EQ(SarmapTypeName(e.data), "pose_t");
    int64_t utime, seq;
    ASSERT_TRUE(ReadSarmapHeader(e.data, &utime, &seq));
    EXPECT_EQ(utime, 1000000 + n * 100000);
    ++n;
  }
  EXPECT_EQ(n, 10);
  EXPECT_TRUE(reader.problems().empty());
}

TEST(LcmLogReaderTest, ReportsTruncationAndCorruptionAndKeepsTheRest) {
  const std::string path = WriteLog(10);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const size_t event_size = bytes.size() / 10;
  // Corrupt the sync word of event 3 and cut the last event in half.
  bytes[3 * event_size] = 0;
  bytes.resize(bytes.size() - event_size / 2);
  const std::string damaged = ::testing::TempDir() + "/damaged.lcmlog";
  std::ofstream(damaged, std::ios::binary) << bytes;

  LcmLogReader reader(damaged);
  LogEvent e;
  std::vector<int64_t> read;
  while (reader.Next(&e)) read.push_back(e.event_number);
  EXPECT_EQ(read, std::vector<int64_t>({0, 1, 2, 4, 5, 6, 7, 8}));
  ASSERT_EQ(reader.problems().size(), 2u);
  EXPECT_EQ(reader.problems()[0].file_offset, static_cast<int64_t>(3 * event_size));
  EXPECT_EQ(reader.problems()[0].after_event, 2);
  EXPECT_EQ(reader.problems()[0].resync_offset, static_cast<int64_t>(4 * event_size));
  EXPECT_NE(reader.problems()[1].what.find("truncated"), std::string::npos);
  EXPECT_EQ(reader.problems()[1].after_event, 8);
  EXPECT_EQ(reader.problems()[1].resync_offset, -1);
  EXPECT_EQ(DescribeProblem(reader.problems()[0]),
            "the log breaks at byte " + std::to_string(3 * event_size) +
                " (after event 2): " + reader.problems()[0].what + "; read on from byte " +
                std::to_string(4 * event_size));
  EXPECT_NE(DescribeProblem(reader.problems()[1]).find("; nothing readable after it"),
            std::string::npos);
}

TEST(LcmLogReaderTest, MissingFileIsAClearError) {
  EXPECT_THROW(LcmLogReader("/nonexistent.lcmlog"), std::runtime_error);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
