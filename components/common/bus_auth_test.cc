#include "common/bus_auth.h"

#include <gtest/gtest.h>

#include <sarmap/pose_t.hpp>
#include <string>
#include <vector>

#include "common/decode.h"
#include "common/node.h"

namespace sarmap {
namespace common {
namespace {

AuthKey Key(uint8_t fill) { return AuthKey(32, fill); }

std::vector<uint8_t> Encode(const sarmap::pose_t& pose) {
  std::vector<uint8_t> bytes(static_cast<size_t>(pose.getEncodedSize()));
  pose.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

sarmap::pose_t Pose(double x_m) {
  sarmap::pose_t pose{};
  pose.header.utime = 1000000;
  pose.header.frame = "map";
  pose.child_frame = "base";
  pose.position_m[0] = x_m;
  pose.orientation[0] = 1;
  return pose;
}

bool Verify(BusAuth* auth, const std::string& channel, const std::vector<uint8_t>& bytes,
            std::string* why = nullptr) {
  size_t payload = 0;
  return auth->Verify(channel, bytes.data(), bytes.size(), &payload, why);
}

TEST(BusAuth, SignedMessagesPassAndTheTrailerIsCutOff) {
  BusAuth publisher(Key(7)), receiver(Key(7));
  const std::vector<uint8_t> plain = Encode(Pose(1.5));
  std::vector<uint8_t> signed_bytes = plain;
  publisher.Sign("POSE", &signed_bytes);
  ASSERT_EQ(signed_bytes.size(), plain.size() + kBusTrailerBytes);
  EXPECT_TRUE(HasBusTrailer(signed_bytes.data(), signed_bytes.size()));
  size_t payload = 0;
  std::string why;
  ASSERT_TRUE(receiver.Verify("POSE", signed_bytes.data(), signed_bytes.size(), &payload, &why))
      << why;
  EXPECT_EQ(payload, plain.size());
}

TEST(BusAuth, ForgedAlteredReaddressedAndOtherKeyMessagesAreRefused) {
  BusAuth publisher(Key(7)), receiver(Key(7)), stranger(Key(8));
  std::vector<uint8_t> good = Encode(Pose(1.5));
  publisher.Sign("POSE", &good);
  std::string why;

  EXPECT_FALSE(Verify(&receiver, "POSE", Encode(Pose(9.0)), &why));  // an open-bus sender
  EXPECT_NE(why.find("not signed"), std::string::npos) << why;

  std::vector<uint8_t> altered = good;
  altered[20] ^= 0x01;  // a byte of the message
  EXPECT_FALSE(Verify(&receiver, "POSE", altered, &why));
  EXPECT_NE(why.find("bad bus signature"), std::string::npos) << why;

  EXPECT_FALSE(Verify(&receiver, "POSE_OTHER", good));  // signed for another channel

  std::vector<uint8_t> foreign = Encode(Pose(1.5));
  stranger.Sign("POSE", &foreign);
  EXPECT_FALSE(Verify(&receiver, "POSE", foreign));

  EXPECT_TRUE(Verify(&receiver, "POSE", good, &why)) << why;
}

TEST(BusAuth, APlayedBackMessageIsRefusedAndARestartedPublisherIsHeard) {
  BusAuth publisher(Key(7)), receiver(Key(7));
  std::vector<uint8_t> first = Encode(Pose(1)), second = Encode(Pose(2));
  publisher.Sign("POSE", &first);
  publisher.Sign("POSE", &second);
  EXPECT_TRUE(Verify(&receiver, "POSE", first));
  EXPECT_TRUE(Verify(&receiver, "POSE", second));
  std::string why;
  EXPECT_FALSE(Verify(&receiver, "POSE", first, &why));  // older than the last one heard
  EXPECT_NE(why.find("played back"), std::string::npos) << why;
  EXPECT_FALSE(Verify(&receiver, "POSE", second));  // the same one again

  // The counter is the process's, shared by its channels: each channel sees it rise.
  std::vector<uint8_t> map_message = Encode(Pose(3));
  publisher.Sign("MAP", &map_message);
  EXPECT_TRUE(Verify(&receiver, "MAP", map_message));

  BusAuth restarted(Key(7));  // a new session whose counter starts again at 1
  std::vector<uint8_t> again = Encode(Pose(4));
  restarted.Sign("POSE", &again);
  EXPECT_TRUE(Verify(&receiver, "POSE", again));
}

TEST(BusAuth, EachChannelRemembersABoundedNumberOfSessions) {
  BusAuth receiver(Key(7));
  BusAuth first(Key(7));
  std::vector<uint8_t> from_first = Encode(Pose(0));
  first.Sign("POSE", &from_first);
  ASSERT_TRUE(Verify(&receiver, "POSE", from_first));
  ASSERT_FALSE(Verify(&receiver, "POSE", from_first));
  // kBusSessionsPerChannel newer publishers push the first one out: its message is then new
  // again to this receiver (and left to the stamp gates).
  for (size_t i = 0; i < kBusSessionsPerChannel; ++i) {
    BusAuth other(Key(7));
    std::vector<uint8_t> bytes = Encode(Pose(1));
    other.Sign("POSE", &bytes);
    ASSERT_TRUE(Verify(&receiver, "POSE", bytes));
  }
  EXPECT_TRUE(Verify(&receiver, "POSE", from_first));
}

TEST(BusAuth, AnUnkeyedBusSignsNothingAndAcceptsEverything) {
  BusAuth open_bus;
  std::vector<uint8_t> bytes = Encode(Pose(1));
  const size_t size = bytes.size();
  open_bus.Sign("POSE", &bytes);
  EXPECT_EQ(bytes.size(), size);
  size_t payload = 0;
  EXPECT_TRUE(open_bus.Verify("POSE", bytes.data(), bytes.size(), &payload, nullptr));
  EXPECT_EQ(payload, size);
}

TEST(BusAuth, ReadersWithoutTheKeyDecodeSignedMessages) {
  BusAuth publisher(Key(7));
  std::vector<uint8_t> bytes = Encode(Pose(2.25));
  publisher.Sign("POSE", &bytes);
  sarmap::pose_t pose;
  std::string why;
  ASSERT_TRUE(DecodeMessage(bytes.data(), bytes.size(), &pose, &why)) << why;
  EXPECT_EQ(pose.position_m[0], 2.25);

  // 52 trailing bytes without the magic are still trailing garbage.
  std::vector<uint8_t> garbage = Encode(Pose(2.25));
  garbage.resize(garbage.size() + kBusTrailerBytes, 0xab);
  EXPECT_FALSE(DecodeMessage(garbage.data(), garbage.size(), &pose, &why));
}

// liblcm 1.3.1 reports a 4-8 byte "LC02" datagram as a message of 2^32 - 5 bytes: the decoder
// refuses the size before it looks for a trailer at the end (which would read 4 GB past the
// datagram).
TEST(BusAuth, AnImpossibleSizeIsRefusedBeforeLookingForATrailer) {
  const std::vector<uint8_t> bytes = Encode(Pose(1.0));
  sarmap::pose_t pose;
  std::string why;
  EXPECT_FALSE(DecodeMessage(bytes.data(), (size_t{1} << 32) - 5, &pose, &why));
  EXPECT_NE(why.find("impossible size"), std::string::npos) << why;
}

// A node with the bus key over memq://: its own signed POSE arrives, a POSE put on the bus
// unsigned (any host on the group could) is counted and dropped before its handler.
TEST(BusAuthNode, AKeyedNodeHearsOnlySignedMessages) {
  Node node("bus_auth_test", "memq://");
  node.SetStatusChannel("");
  node.SetBusKey(Key(7));
  std::vector<double> heard_x;
  node.Subscribe<sarmap::pose_t>("POSE", [&](const sarmap::pose_t& pose, const ReceiveInfo&) {
    heard_x.push_back(pose.position_m[0]);
  });
  auto publisher = node.Advertise<sarmap::pose_t>("POSE");
  sarmap::pose_t pose = Pose(1.0);
  publisher.Publish(&pose);
  ASSERT_TRUE(node.SpinOnce(1.0));

  const std::vector<uint8_t> forged = Encode(Pose(42.0));
  node.lcm().publish("POSE", forged.data(), static_cast<unsigned int>(forged.size()));
  ASSERT_TRUE(node.SpinOnce(1.0));

  ASSERT_EQ(heard_x.size(), 1u);
  EXPECT_EQ(heard_x[0], 1.0);
  EXPECT_EQ(node.stats().at("POSE").dropped_malformed, 1);
}

// A node without the key (a monitor, a viewer) reads a signed bus.
TEST(BusAuthNode, AnUnkeyedNodeReadsASignedBus) {
  Node node("bus_auth_test", "memq://");
  node.SetStatusChannel("");
  int heard = 0;
  node.Subscribe<sarmap::pose_t>("POSE",
                                 [&](const sarmap::pose_t&, const ReceiveInfo&) { ++heard; });
  BusAuth publisher(Key(7));
  std::vector<uint8_t> bytes = Encode(Pose(1.0));
  publisher.Sign("POSE", &bytes);
  node.lcm().publish("POSE", bytes.data(), static_cast<unsigned int>(bytes.size()));
  ASSERT_TRUE(node.SpinOnce(1.0));
  EXPECT_EQ(heard, 1);
  EXPECT_EQ(node.stats().at("POSE").dropped_malformed, 0);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
