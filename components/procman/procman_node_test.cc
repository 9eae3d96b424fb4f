// Deputy and sheriff in-process over memq://: hostile datagrams on their channels are
// counted and dropped, and both go on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <vector>

#include "procman/deputy.h"
#include "procman/pmd_config.h"
#include "procman/sheriff.h"

namespace sarmap {
namespace procman {
namespace {

const Key kKey(32, 0x42);

// Orders for deputy `deputy_id` whose one command line holds a NUL byte ("sleep\0 1"): LCM's
// encoders never write that, so it comes only from a hostile sender. It used to make the HMAC
// re-encoding throw and end the process.
std::vector<uint8_t> OrdersWithNul(const std::string& deputy_id, uint8_t hmac_byte) {
  sarmap::pm_orders_t orders;
  orders.header.utime = 1;
  orders.header.seq = 0;
  orders.sheriff_id = "attacker";
  orders.deputy_id = deputy_id;
  orders.counter = 1;
  sarmap::pm_command_order_t c;
  c.command_id = "x";
  c.exec = "sleep_1";
  c.stop_signal = 2;
  c.stop_time_allowed_s = 1;
  orders.commands.push_back(c);
  orders.num_commands = 1;
  std::fill(std::begin(orders.hmac_sha256), std::end(orders.hmac_sha256), hmac_byte);
  std::vector<uint8_t> wire(static_cast<size_t>(orders.getEncodedSize()));
  EXPECT_EQ(orders.encode(wire.data(), 0, static_cast<int>(wire.size())),
            static_cast<int>(wire.size()));
  const char exec[] = "sleep_1";
  auto at = std::search(wire.begin(), wire.end(), exec, exec + strlen(exec));
  EXPECT_NE(at, wire.end());
  at[5] = 0;
  return wire;
}

// Publishes each datagram and handles it.
void Deliver(lcm::LCM* lcm, const std::vector<std::vector<uint8_t>>& datagrams) {
  for (const auto& wire : datagrams) {
    lcm->publish("PM_ORDERS", wire.data(), static_cast<unsigned int>(wire.size()));
    ASSERT_GT(lcm->handleTimeout(1000), 0);
  }
}

TEST(ProcmanNodeTest, DeputyDropsOrdersWithANulByteAndGoesOn) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  ProcmanOptions options;
  Deputy deputy(&lcm, options, "d1", kKey, "");
  Deliver(&lcm, {OrdersWithNul("d1", 0x55), OrdersWithNul("d1", 0)});
  EXPECT_EQ(deputy.malformed_orders(), 2);
  EXPECT_EQ(deputy.refused_orders(), 0);  // never got as far as the signature
}

TEST(ProcmanNodeTest, SheriffDropsOrdersWithANulByteAndGoesOn) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  ProcmanOptions options;
  const Config config = ParseConfig(R"(cmd "x" { exec = "sleep 1"; deputy = "d1"; })", "test");
  Sheriff sheriff(&lcm, options, config, &kKey, "sheriff/1");
  ASSERT_GT(lcm.handleTimeout(1000), 0);  // its own probe
  Deliver(&lcm, {OrdersWithNul("d1", 0x55), OrdersWithNul("d1", 0)});
  EXPECT_EQ(sheriff.malformed_messages(), 2);
}

// The signature check itself never throws, whatever the orders hold.
TEST(ProcmanNodeTest, SignatureOfUnencodableOrdersIsInvalidNotAnException) {
  sarmap::pm_orders_t orders;
  orders.header.frame = "";
  orders.sheriff_id = std::string("a\0b", 3);
  orders.deputy_id = "d1";
  orders.num_commands = 0;
  std::fill(std::begin(orders.hmac_sha256), std::end(orders.hmac_sha256), 1);
  bool valid = true;
  EXPECT_NO_THROW(valid = SignatureValid(kKey, orders));
  EXPECT_FALSE(valid);
  ReplayGuard guard;
  Verdict verdict = Verdict::kAccepted;
  EXPECT_NO_THROW(verdict = VerifyOrders(kKey, orders, &guard));
  EXPECT_EQ(verdict, Verdict::kForged);
}

}  // namespace
}  // namespace procman
}  // namespace sarmap
