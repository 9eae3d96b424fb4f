// Hostile encodings of every LCM type: CheckWire and DecodeMessage reject them without
// crashing or allocating what the bytes do not justify, and a Node that receives them goes on.
#include "common/decode.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <vector>

#include "common/node.h"
#include "sarmap/message_samples.h"
#include "tests/largest_allocation.h"

namespace sarmap {
namespace common {
namespace {

// Far above any encoding these tests build (a few kB), far below what a hostile count asks.
constexpr size_t kAllocationLimit = 1 << 20;

template <class T>
std::vector<uint8_t> Encode(const T& msg) {
  std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_EQ(msg.encode(out.data(), 0, static_cast<int>(out.size())), static_cast<int>(out.size()));
  return out;
}

// A sample of T whose arrays are all non-empty where the seed allows: several seeds per type
// so that every count and string is exercised.
template <class T>
std::vector<std::vector<uint8_t>> Samples() {
  std::vector<std::vector<uint8_t>> out;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    std::mt19937_64 rng(seed);
    T msg;
    sarmap::samples::Fill(msg, rng);
    out.push_back(Encode(msg));
  }
  return out;
}

// Where the string lengths and array counts sit in a valid encoding (a second reader of the
// generated layout, independent of WireWalker).
class FieldFinder {
 public:
  struct Field {
    size_t offset;
    int bytes;
    std::string name;
  };
  FieldFinder(const uint8_t* data, size_t size) : data_(data), size_(size), pos_(8) {}

  bool Skip(const char*, uint64_t bytes) {
    pos_ += bytes;
    return pos_ <= size_;
  }
  bool Integer(const char* name, int bytes, int64_t* value) {
    if (pos_ + bytes > size_) return false;
    counts.push_back({pos_, bytes, name});
    *value = Read(bytes);
    return true;
  }
  bool String(const char* name, int64_t) {
    if (pos_ + 4 > size_) return false;
    strings.push_back({pos_, 4, name});
    const int64_t length = Read(4);
    pos_ += static_cast<size_t>(length);
    return length >= 1 && pos_ <= size_;
  }
  template <class S>
  bool Struct(const char*, int64_t, const S* tag) {
    return WalkWire(*this, tag);
  }
  bool Count(const char*, std::initializer_list<int64_t> dims, size_t, uint64_t* n) {
    *n = 1;
    for (int64_t d : dims) *n *= static_cast<uint64_t>(d);
    return true;
  }

  std::vector<Field> strings;
  std::vector<Field> counts;

 private:
  int64_t Read(int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | data_[pos_ + i];
    pos_ += bytes;
    const int shift = 64 - 8 * bytes;
    return static_cast<int64_t>(v << shift) >> shift;
  }
  const uint8_t* data_;
  size_t size_;
  size_t pos_;
};

template <class T>
FieldFinder Find(const std::vector<uint8_t>& wire) {
  FieldFinder finder(wire.data(), wire.size());
  EXPECT_TRUE(WalkWire(finder, static_cast<const T*>(nullptr))) << T::getTypeName();
  return finder;
}

void Put(std::vector<uint8_t>* wire, const FieldFinder::Field& f, int64_t value) {
  for (int i = 0; i < f.bytes; ++i) {
    (*wire)[f.offset + i] =
        static_cast<uint8_t>(static_cast<uint64_t>(value) >> (8 * (f.bytes - 1 - i)));
  }
}

// What every hostile encoding must satisfy: CheckWire says no with a reason, and the whole
// DecodeMessage path neither crashes nor allocates from the hostile value.
template <class T>
void ExpectRejected(const std::vector<uint8_t>& wire, const std::string& what) {
  std::string why;
  EXPECT_FALSE(CheckWire<T>(wire.data(), wire.size(), &why)) << T::getTypeName() << " " << what;
  EXPECT_FALSE(why.empty());
  EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  T msg;
  sarmap::testing::StartMeasuringAllocations();
  EXPECT_FALSE(DecodeMessage(wire.data(), wire.size(), &msg, &why));
  EXPECT_LT(sarmap::testing::LargestAllocation(), kAllocationLimit)
      << T::getTypeName() << " " << what;
}

template <class T>
void ValidEncodingsPass() {
  for (const auto& wire : Samples<T>()) {
    std::string why;
    EXPECT_TRUE(CheckWire<T>(wire.data(), wire.size(), &why)) << why;
    T msg;
    EXPECT_EQ(msg.decode(wire.data(), 0, static_cast<int>(wire.size())),
              static_cast<int>(wire.size()));
  }
}

template <class T>
int HostileStringLengthsAreRejected() {
  int cases = 0;
  for (const auto& valid : Samples<T>()) {
    const FieldFinder fields = Find<T>(valid);
    for (const auto& f : fields.strings) {
      for (int64_t length : {int64_t{std::numeric_limits<int32_t>::min()}, int64_t{-1}, int64_t{0},
                             int64_t{std::numeric_limits<int32_t>::max()},
                             static_cast<int64_t>(valid.size() - f.offset - 4 + 1)}) {
        std::vector<uint8_t> wire = valid;
        Put(&wire, f, length);
        ExpectRejected<T>(wire, f.name + " length " + std::to_string(length));
        ++cases;
      }
    }
  }
  return cases;
}

template <class T>
int HostileArrayCountsAreRejected() {
  int cases = 0;
  for (const auto& valid : Samples<T>()) {
    const FieldFinder fields = Find<T>(valid);
    for (const auto& f : fields.counts) {
      // A narrower count cannot ask for much, and none exists yet; extend this test with one.
      EXPECT_GE(f.bytes, 4) << T::getTypeName() << "." << f.name;
      for (int64_t count : {int64_t{-1}, int64_t{std::numeric_limits<int32_t>::min()},
                            int64_t{10000000}, int64_t{std::numeric_limits<int32_t>::max()}}) {
        std::vector<uint8_t> wire = valid;
        Put(&wire, f, count);
        ExpectRejected<T>(wire, f.name + " count " + std::to_string(count));
        ++cases;
      }
    }
  }
  return cases;
}

template <class T>
void EveryTruncationIsRejected() {
  for (const auto& valid : Samples<T>()) {
    for (size_t size = 0; size < valid.size(); ++size) {
      const std::vector<uint8_t> wire(valid.begin(), valid.begin() + size);
      ExpectRejected<T>(wire, "truncated to " + std::to_string(size));
    }
    std::vector<uint8_t> longer = valid;
    longer.push_back(0);
    ExpectRejected<T>(longer, "one trailing byte");
  }
}

// Random flips of 1-4 bytes past the fingerprint. Whatever CheckWire accepts, the generated
// decoder reads exactly and re-encodes to the same bytes: the walker and the decoder agree.
template <class T>
void RandomFlipsNeverCrash(std::mt19937_64& rng, int* accepted, int* rejected) {
  for (const auto& valid : Samples<T>()) {
    for (int trial = 0; trial < 100; ++trial) {
      std::vector<uint8_t> wire = valid;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int i = 0; i < flips; ++i) {
        wire[8 + rng() % (wire.size() - 8)] ^= static_cast<uint8_t>(1 + rng() % 255);
      }
      T msg;
      std::string why;
      sarmap::testing::StartMeasuringAllocations();
      (void)DecodeMessage(wire.data(), wire.size(), &msg, &why);
      EXPECT_LT(sarmap::testing::LargestAllocation(), kAllocationLimit) << T::getTypeName();
      if (CheckWire<T>(wire.data(), wire.size(), nullptr)) {
        ++*accepted;
        T again;
        ASSERT_EQ(again.decode(wire.data(), 0, static_cast<int>(wire.size())),
                  static_cast<int>(wire.size()));
        EXPECT_EQ(Encode(again), wire) << T::getTypeName();
      } else {
        ++*rejected;
      }
    }
  }
}

TEST(DecodeTest, ValidEncodingsOfEveryTypePass) {
#define CASE(T) ValidEncodingsPass<sarmap::T>();
  SARMAP_FOR_EACH_LCM_TYPE(CASE)
#undef CASE
}

TEST(DecodeTest, HostileStringLengthsAreRejectedForEveryType) {
  // Every message type has header.frame at least.
#define CASE(T) EXPECT_GT(HostileStringLengthsAreRejected<sarmap::T>(), 0) << #T;
  SARMAP_FOR_EACH_MESSAGE_TYPE(CASE)
#undef CASE
}

TEST(DecodeTest, HostileArrayCountsAreRejectedForEveryType) {
  int cases = 0;
#define CASE(T) cases += HostileArrayCountsAreRejected<sarmap::T>();
  SARMAP_FOR_EACH_MESSAGE_TYPE(CASE)
#undef CASE
  EXPECT_GT(cases, 100);
}

TEST(DecodeTest, EveryTruncationIsRejectedForEveryType) {
#define CASE(T) EveryTruncationIsRejected<sarmap::T>();
  SARMAP_FOR_EACH_MESSAGE_TYPE(CASE)
#undef CASE
}

TEST(DecodeTest, RandomByteFlipsNeverCrashAnyType) {
  std::mt19937_64 rng(24);
  int accepted = 0, rejected = 0;
#define CASE(T) RandomFlipsNeverCrash<sarmap::T>(rng, &accepted, &rejected);
  SARMAP_FOR_EACH_MESSAGE_TYPE(CASE)
#undef CASE
  // Both branches are exercised: flips in numbers pass, flips in lengths and counts do not.
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(rejected, 1000);
  std::printf("%d flipped encodings accepted, %d rejected\n", accepted, rejected);
}

TEST(DecodeTest, NulBytesInsideStringsAreRejected) {
  sarmap::velocity_command_t cmd{};
  cmd.header.frame = "base";
  cmd.source = "explore";
  const std::vector<uint8_t> valid = Encode(cmd);
  const FieldFinder fields = Find<sarmap::velocity_command_t>(valid);
  ASSERT_EQ(fields.strings.size(), 2u);
  std::vector<uint8_t> wire = valid;
  wire[fields.strings[0].offset + 4 + 1] = 0;  // "b\0se"
  ExpectRejected<sarmap::velocity_command_t>(wire, "NUL inside");
  wire = valid;
  wire[fields.strings[0].offset + 4 + 4] = 'x';  // the terminating NUL
  ExpectRejected<sarmap::velocity_command_t>(wire, "no NUL at the end");
}

TEST(DecodeTest, ReasonsNameTheField) {
  sarmap::sound_map_t map{};
  map.header.frame = "map";
  std::vector<uint8_t> wire = Encode(map);
  const FieldFinder fields = Find<sarmap::sound_map_t>(wire);
  Put(&wire, fields.strings[0], std::numeric_limits<int32_t>::min());
  std::string why;
  EXPECT_FALSE(CheckWire<sarmap::sound_map_t>(wire.data(), wire.size(), &why));
  EXPECT_NE(why.find("sound_map_t: header.frame: string length -2147483648"), std::string::npos)
      << why;
}

// The datagrams that killed every node: a header.frame length of INT32_MIN (a 2 GB read), and
// a 36-byte SOUND_MAP claiming ten million sources (a 1.4 GB allocation). A Node counts each
// as malformed, allocates nothing for it and goes on to accept the next valid message.
class NodeUnderAttackTest : public ::testing::Test {
 protected:
  NodeUnderAttackTest() : node_("decode_test", "memq://") {
    node_.SetStatusChannel("");
    node_.Subscribe<sarmap::sound_map_t>(
        "SOUND_MAP", [this](const sarmap::sound_map_t&, const ReceiveInfo&) { ++received_; });
    sarmap::sound_map_t map{};
    map.header.utime = 1;
    map.header.frame = "map";
    valid_ = Encode(map);
    const FieldFinder fields = Find<sarmap::sound_map_t>(valid_);
    frame_ = fields.strings.at(0);
    count_ = fields.counts.at(0);
  }

  // Publishes `wire` and then a valid message, and handles both.
  void Receive(const std::vector<uint8_t>& wire) {
    sarmap::testing::StartMeasuringAllocations();
    for (const std::vector<uint8_t>* w :
         {&wire, const_cast<const std::vector<uint8_t>*>(&valid_)}) {
      node_.lcm().publish("SOUND_MAP", w->data(), static_cast<unsigned int>(w->size()));
      ASSERT_TRUE(node_.SpinOnce(1.0));
    }
    largest_allocation_ = sarmap::testing::LargestAllocation();
  }

  Node node_;
  int received_ = 0;
  std::vector<uint8_t> valid_;
  FieldFinder::Field frame_{}, count_{};
  size_t largest_allocation_ = 0;
};

TEST_F(NodeUnderAttackTest, FrameLengthOfInt32MinIsCountedAndTheNodeGoesOn) {
  std::vector<uint8_t> wire = valid_;
  Put(&wire, frame_, std::numeric_limits<int32_t>::min());
  Receive(wire);
  const ChannelStats& stats = node_.stats().at("SOUND_MAP");
  EXPECT_EQ(stats.dropped_malformed, 1);
  EXPECT_EQ(stats.received, 1);
  EXPECT_EQ(received_, 1);
}

TEST_F(NodeUnderAttackTest, TenMillionSourcesIn36BytesAllocateNothing) {
  std::vector<uint8_t> wire = valid_;
  Put(&wire, count_, 10000000);
  ASSERT_EQ(wire.size(), 36u);
  Receive(wire);
  EXPECT_LT(largest_allocation_, kAllocationLimit);
  const ChannelStats& stats = node_.stats().at("SOUND_MAP");
  EXPECT_EQ(stats.dropped_malformed, 1);
  EXPECT_EQ(stats.received, 1);
  EXPECT_EQ(received_, 1);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
