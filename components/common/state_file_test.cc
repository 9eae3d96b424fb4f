#include "common/state_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

namespace sarmap {
namespace common {
namespace {

std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "/state_file_test_" + std::to_string(getpid()) + "_" + name;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteAll(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

TEST(Crc32Test, MatchesTheStandardCheckValue) {
  const std::string check = "123456789";
  EXPECT_EQ(Crc32(check.data(), check.size()), 0xCBF43926u);
  // Continued over two parts: the same as at once.
  EXPECT_EQ(Crc32(check.data() + 4, 5, Crc32(check.data(), 4)), 0xCBF43926u);
  // Nothing more leaves it as it was, whatever the pointer.
  EXPECT_EQ(Crc32(nullptr, 0, 0xCBF43926u), 0xCBF43926u);
  EXPECT_EQ(Crc32(nullptr, 0), 0u);
}

// The definition, one bit at a time (reflected polynomial 0xEDB88320).
uint32_t BitwiseCrc32(const std::string& data) {
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : data) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc & 1) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return ~crc;
}

TEST(Crc32Test, MatchesTheDefinitionOnLongBuffersAndUnalignedSplits) {
  std::mt19937 rng(7);
  std::string data(100003, '\0');
  for (char& c : data) c = static_cast<char>(rng());
  const uint32_t expected = BitwiseCrc32(data);
  EXPECT_EQ(Crc32(data.data(), data.size()), expected);
  for (size_t split : {size_t{0}, size_t{1}, size_t{7}, size_t{4097}, data.size()}) {
    const uint32_t head = Crc32(data.data(), split);
    EXPECT_EQ(Crc32(data.data() + split, data.size() - split, head), expected) << split;
  }
  data[54321] ^= 0x10;  // one flipped bit changes it
  EXPECT_NE(Crc32(data.data(), data.size()), expected);
}

TEST(StateFileTest, RoundTripsABinaryBody) {
  const std::string path = TempPath("roundtrip");
  const std::string body("a\0b\nc\xff", 6);
  WriteSealedState(path, "test-kind", 3, body);
  std::string read;
  EXPECT_EQ(ReadSealedState(path, "test-kind", 3, &read), StateFileRead::kSealed);
  EXPECT_EQ(read, body);
  std::remove(path.c_str());
  EXPECT_EQ(ReadSealedState(path, "test-kind", 3, &read), StateFileRead::kMissing);
}

// A body streamed in small and large pieces (the buffer's size and beyond) is the file
// WriteSealedState makes of the whole body at once, and reads back.
TEST(StateFileTest, AStreamedBodyIsTheSameFileAsAWholeOne) {
  const std::string streamed_path = TempPath("streamed"), whole_path = TempPath("whole");
  std::mt19937 rng(3);
  std::string body;
  {
    SealedStateWriter writer(streamed_path, "test-kind", 4);
    for (size_t piece : {size_t{1}, size_t{7}, size_t{40000}, size_t{3}, size_t{300000},
                         size_t{65536}, size_t{12}}) {
      std::string bytes(piece, '\0');
      for (char& c : bytes) c = static_cast<char>(rng());
      writer.body().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      body += bytes;
    }
    writer.body().put('\n');
    body += '\n';
    writer.Commit();
  }
  WriteSealedState(whole_path, "test-kind", 4, body);
  EXPECT_EQ(ReadAll(streamed_path), ReadAll(whole_path));
  std::string read;
  EXPECT_EQ(ReadSealedState(streamed_path, "test-kind", 4, &read), StateFileRead::kSealed);
  EXPECT_EQ(read, body);
  EXPECT_FALSE(std::ifstream(streamed_path + ".tmp").good());
  std::remove(streamed_path.c_str());
  std::remove(whole_path.c_str());
}

// A save that fails half-way (the writer goes without Commit) leaves the previous file whole.
TEST(StateFileTest, AnUncommittedWriterLeavesThePreviousFile) {
  const std::string path = TempPath("uncommitted");
  WriteSealedState(path, "test-kind", 1, "before");
  {
    SealedStateWriter writer(path, "test-kind", 1);
    writer.body() << "half of the next st";
  }
  std::string read;
  EXPECT_EQ(ReadSealedState(path, "test-kind", 1, &read), StateFileRead::kSealed);
  EXPECT_EQ(read, "before");
  EXPECT_FALSE(std::ifstream(path + ".tmp").good());
  EXPECT_THROW(SealedStateWriter(TempPath("no-such-dir") + "/x", "test-kind", 1),
               std::runtime_error);
  std::remove(path.c_str());
}

// A header whose size is not zero-padded reads as well.
TEST(StateFileTest, ReadsAnUnpaddedHeader) {
  const std::string path = TempPath("unpadded");
  const std::string body = "abc";
  char header[128];
  std::snprintf(header, sizeof(header), "# sarmap-state test-kind v2 bytes 3 crc32 %08x\n",
                Crc32(body.data(), body.size()));
  WriteAll(path, header + body);
  std::string read;
  EXPECT_EQ(ReadSealedState(path, "test-kind", 2, &read), StateFileRead::kSealed);
  EXPECT_EQ(read, body);
  std::remove(path.c_str());
}

TEST(StateFileTest, RefusesFlippedTruncatedForeignAndOtherVersions) {
  const std::string path = TempPath("refuse");
  const std::string body = "people:\n  - id: 1\n    confidence: 0.5\n";
  WriteSealedState(path, "test-kind", 2, body);
  const std::string good = ReadAll(path);
  std::string read;
  const auto refused = [&](const std::string& text, const std::string& kind, int version,
                           const std::string& why) {
    WriteAll(path, text);
    try {
      ReadSealedState(path, kind, version, &read);
      ADD_FAILURE() << "accepted: " << why;
    } catch (const StateFileError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  std::string flipped = good;
  flipped[flipped.size() - 5] ^= 0x04;  // one bit of the body
  refused(flipped, "test-kind", 2, "checksum");
  refused(good.substr(0, good.size() - 3), "test-kind", 2, "truncated");
  refused(good + "x", "test-kind", 2, "appended");
  refused(good, "other-kind", 2, "not other-kind");
  refused(good, "test-kind", 3, "version 2");
  refused("# sarmap-state garbage\n", "test-kind", 2, "unreadable");
  // A file written before sealing: handed back whole, for the caller to decide.
  WriteAll(path, body);
  EXPECT_EQ(ReadSealedState(path, "test-kind", 2, &read), StateFileRead::kUnsealed);
  EXPECT_EQ(read, body);
  EXPECT_EQ(SetAsideStateFile(path), path + ".corrupt");
  EXPECT_EQ(ReadSealedState(path, "test-kind", 2, &read), StateFileRead::kMissing);
  std::remove((path + ".corrupt").c_str());
}

}  // namespace
}  // namespace common
}  // namespace sarmap
