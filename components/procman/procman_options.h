#pragma once
// Options of the sheriff and the deputy (config/procman.yaml), one struct for both.

#include <string>

#include "common/options.h"

namespace sarmap {
namespace procman {

struct ProcmanOptions {
  std::string orders_channel = "PM_ORDERS";
  std::string info_channel = "PM_INFO";
  std::string output_channel = "PM_OUTPUT";
  std::string key_file = "~/.config/sarmap/procman.key";
  // Deputy.
  double info_period_s = 1.0;
  double output_period_s = 0.1;
  int output_max_bytes = 16384;
  int output_buffer_bytes = 65536;
  double respawn_base_s = 0.1;
  double respawn_max_s = 10.0;
  double respawn_stable_run_s = 5.0;
  double order_window_s = 5.0;
  // Sheriff.
  double resend_period_s = 1.0;
  double deputy_lost_after_s = 2.0;
  double deputy_gone_after_s = 10.0;
  double discovery_timeout_s = 3.0;
  double command_timeout_s = 15.0;
  int output_tail_lines = 10;

  template <class V>
  void Visit(V& v) {
    v("orders_channel", orders_channel, "sheriff -> deputies: signed desired state (pm_orders_t)");
    v("info_channel", info_channel, "deputies -> sheriff: state of every command (pm_info_t)");
    v("output_channel", output_channel,
      "deputies -> sheriff: captured stdout/stderr (pm_output_t)");
    v("key_file", key_file,
      "shared HMAC key of orders and reports, the same file on every computer (~/ is the "
      "user's home; --key overrides)");
    v("info_period_s", info_period_s, "deputy: PM_INFO period (also sent on every change)",
      Positive());
    v("output_period_s", output_period_s, "deputy: at most one PM_OUTPUT per this period",
      Positive());
    v("output_max_bytes", output_max_bytes, "deputy: output bytes per command per PM_OUTPUT",
      AtLeast(256));
    v("output_buffer_bytes", output_buffer_bytes,
      "deputy: output buffered per command; beyond it the oldest is dropped (and counted)");
    v("respawn_base_s", respawn_base_s, "deputy: first respawn delay after a crash", Positive());
    v("respawn_max_s", respawn_max_s, "deputy: longest respawn delay (doubles per quick crash)");
    v("respawn_stable_run_s", respawn_stable_run_s, "deputy: a run this long resets the back-off",
      NonNegative());
    v("order_window_s", order_window_s,
      "deputy: an order's counter must be within this of the deputy's session clock; sheriff: "
      "the same for other sheriffs' orders it follows",
      AtLeast(1.0));
    v("resend_period_s", resend_period_s, "sheriff: desired state re-sent this often", Positive());
    v("deputy_lost_after_s", deputy_lost_after_s, "sheriff: a deputy silent this long is lost");
    v("deputy_gone_after_s", deputy_gone_after_s,
      "sheriff: a script waiting on a deputy silent this long fails (killed, crashed, cut off)");
    v("discovery_timeout_s", discovery_timeout_s,
      "sheriff: how long one-shot commands wait to hear the deputies", Positive());
    v("command_timeout_s", command_timeout_s,
      "sheriff: how long start/stop/restart wait for the commands to get there", Positive());
    v("output_tail_lines", output_tail_lines, "sheriff: output lines shown under the status table",
      AtLeast(0));
  }
  void Validate(common::Validator& check) const {
    check.That(output_buffer_bytes >= output_max_bytes, "output_buffer_bytes",
               "must be >= output_max_bytes");
    check.That(respawn_max_s >= respawn_base_s, "respawn_max_s", "must be >= respawn_base_s");
    check.That(deputy_lost_after_s > info_period_s, "deputy_lost_after_s",
               "must be > info_period_s");
    check.That(deputy_gone_after_s >= deputy_lost_after_s, "deputy_gone_after_s",
               "must be >= deputy_lost_after_s");
    check.That(!orders_channel.empty() && !info_channel.empty() && !output_channel.empty(),
               "channels", "must not be empty");
    check.That(!key_file.empty(), "key_file", "must not be empty");
  }
};

}  // namespace procman
}  // namespace sarmap
