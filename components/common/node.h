#pragma once
// The runtime every sarmap process shares: typed, defensive publish/subscribe over LCM, a
// main loop with timers, clean shutdown on SIGINT/SIGTERM, and per-channel receive
// statistics published on NODE_STATUS once a second.
//
//   Node node("sarmap-slam", url);
//   node.Subscribe<sarmap::laser_scan_t>("SCAN", [&](const sarmap::laser_scan_t& scan,
//                                                    const ReceiveInfo& info) { ... });
//   auto pose_pub = node.Advertise<sarmap::pose_t>("POSE");
//   pose_pub.Publish(&pose);   // fills header.seq
//   return node.Run();         // until SIGINT/SIGTERM or Stop()
//
// With a bus key (SetBusKey, or `--bus-key-file` through the NodeArgs constructor) every message
// published carries a signature and every message received must carry a valid one, else it is
// counted and dropped before it is decoded (common/bus_auth.h).
//
// Every message goes through DecodeMessage (common/decode.h): a malformed, truncated or
// wrong-type message, or one that fails CheckMessage(), is counted and dropped with a
// (rate-limited) log line; an exception from a callback is counted and logged. Neither stops
// the node.

#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/bus_auth.h"
#include "common/bus_publish.h"
#include "common/decode.h"
#include "common/logging.h"
#include "common/sequence.h"
#include "common/time.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_output_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"

namespace sarmap {
namespace common {

// LCM URL used when none is given: $SARMAP_LCM_URL, else $LCM_DEFAULT_URL, else
// kDefaultLcmUrl (host-local: ttl=0, and a large receive buffer for images).
std::string DefaultLcmUrl();
constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";

struct ReceiveInfo {
  std::string channel;
  double receive_time_s = 0;  // the node's clock (steady; a replay's: log time), s
  int64_t missed_before = 0;  // messages lost on this channel just before this one
};

struct ChannelStats {
  std::string type_name;
  int64_t received = 0;
  int64_t dropped_malformed = 0;
  int64_t handler_errors = 0;
  PublisherSequences sequence;  // per publisher (PublisherOf)
  int64_t last_utime = 0;
};

// Who published a message, for the gap accounting of a channel that several publishers share,
// each numbering its own messages: "" (the channel's one publisher) but for the types whose
// messages name their sender.
template <class T>
std::string PublisherOf(const T&) {
  return std::string();
}
std::string PublisherOf(const sarmap::slam_anchor_request_t& msg);  // the SLAM client
std::string PublisherOf(const sarmap::node_status_t& msg);          // node, host and pid
std::string PublisherOf(const sarmap::pm_info_t& msg);              // the deputy
std::string PublisherOf(const sarmap::pm_output_t& msg);            // the deputy

class Node {
 public:
  // Throws std::runtime_error when LCM cannot be initialised on `lcm_url`.
  Node(const std::string& name, const std::string& lcm_url = "");
  // From a node's command line: its LCM URL and, with --bus-key-file, the bus key. Throws
  // std::runtime_error as above, or when the key file is missing, short or readable by others.
  Node(const std::string& name, const NodeArgs& args);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return name_; }
  const std::string& lcm_url() const { return lcm_url_; }
  lcm::LCM& lcm() { return *lcm_; }

  // Signs what this node publishes and refuses what it receives unsigned or badly signed. Applies
  // to publishers advertised before the call too.
  void SetBusKey(AuthKey key);
  bool bus_keyed() const { return bus_auth_->keyed(); }

  template <class T>
  using Callback = std::function<void(const T&, const ReceiveInfo&)>;

  // queue_capacity: messages LCM buffers for this subscription before dropping the oldest;
  // 1 for "latest frame only" consumers.
  template <class T>
  void Subscribe(const std::string& channel, Callback<T> callback, int queue_capacity = 30);

  template <class T>
  class Publisher {
   public:
    // Sets msg->header.seq to this publisher's counter, then publishes (signed on a keyed bus).
    void Publish(T* msg) {
      msg->header.seq = seq_++;
      Send(*msg);
    }
    // As Publish, with `finish(msg)` run once the sequence number is set (to sign the message:
    // common/command_auth.h).
    template <class F>
    void Publish(T* msg, F&& finish) {
      msg->header.seq = seq_++;
      finish(msg);
      Send(*msg);
    }
    const std::string& channel() const { return channel_; }

   private:
    friend class Node;
    Publisher(lcm::LCM* lcm, std::string channel, std::shared_ptr<BusAuth> bus_auth)
        : lcm_(lcm), channel_(std::move(channel)), bus_auth_(std::move(bus_auth)) {}
    void Send(const T& msg) { PublishOnBus(lcm_, bus_auth_.get(), channel_, msg); }
    lcm::LCM* lcm_;
    std::string channel_;
    std::shared_ptr<BusAuth> bus_auth_;
    int64_t seq_ = 0;
  };
  template <class T>
  Publisher<T> Advertise(const std::string& channel) {
    return Publisher<T>(lcm_.get(), channel, bus_auth_);
  }

  // Calls `callback` every `period_s` of the node's clock (scheduling only; results must use
  // message time).
  void AddTimer(double period_s, std::function<void()> callback);

  // The node's clock, in seconds: receive times (and so the stamp gates that judge a message's
  // stamp against its arrival), timers and uptime. Steady time by default; a log replay
  // (log-tools/node_replay.h) sets the log's receive time, so that a replayed node decides as it
  // did live. Timers already added restart their period from the new clock's present.
  void SetClock(std::function<double()> now_s);
  double Now() const { return clock_ ? clock_() : SteadySeconds(); }

  // Handles messages and timers until Stop(), SIGINT or SIGTERM: NODE_STATUS every second,
  // and every kReleaseFreeMemoryPeriod_s the allocator's free pages given back to the system
  // (common/memory.h). Returns 0, or 1 if LCM failed.
  int Run();
  // Handles what arrives within `timeout_s`; false once the node should stop.
  bool SpinOnce(double timeout_s);
  void Stop() { stop_ = true; }
  bool stopping() const;

  // Free text reported in NODE_STATUS.message.
  void SetStatusMessage(std::string text) { status_message_ = std::move(text); }
  // Channel that status goes to ("" disables); NODE_STATUS by default.
  void SetStatusChannel(std::string channel) { status_channel_ = std::move(channel); }
  void PublishStatus();

  // A decoded message the node's own checks refused (e.g. a stamp far from its stream's clock,
  // common/stamp_gate.h): counted with the malformed ones on `channel` in NODE_STATUS and logged
  // (rate-limited).
  void Reject(const std::string& channel, const std::string& why) {
    Dropped(channel, &stats_[channel], why);
  }

  const std::map<std::string, ChannelStats>& stats() const { return stats_; }
  int64_t total_dropped() const;

 private:
  class SubscriptionBase {
   public:
    virtual ~SubscriptionBase() = default;
    virtual void Handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) = 0;
  };
  template <class T>
  class TypedSubscription;

  // After the first subscription: the kernel filter of common/lcm_guard.h on the socket
  // liblcm has just opened.
  void GuardReceiveSocket();
  void Dropped(const std::string& channel, ChannelStats* stats, const std::string& why);
  void HandlerError(const std::string& channel, ChannelStats* stats, const std::string& what);

  std::string name_;
  std::string lcm_url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::shared_ptr<BusAuth> bus_auth_ = std::make_shared<BusAuth>();
  bool receive_guarded_ = false;
  std::vector<std::unique_ptr<SubscriptionBase>> subscriptions_;
  std::map<std::string, ChannelStats> stats_;
  std::map<std::string, RateLimiter> drop_log_limit_;
  struct Timer {
    double period_s;
    double next_s;
    std::function<void()> callback;
  };
  std::vector<Timer> timers_;
  std::function<double()> clock_;  // empty: steady time
  bool stop_ = false;
  double start_s_;
  std::string status_message_;
  std::string status_channel_ = "NODE_STATUS";
  Publisher<sarmap::node_status_t> status_pub_;
};

template <class T>
class Node::TypedSubscription : public Node::SubscriptionBase {
 public:
  TypedSubscription(Node* node, Callback<T> callback, ChannelStats* stats)
      : node_(node), callback_(std::move(callback)), stats_(stats) {}

  void Handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) override {
    // liblcm 1.3.1 hands on a 4-8 byte "LC02" datagram as a message of 2^32 - 5 bytes made of
    // whatever its buffer held (common/decode.h): refused before the bus check reads the
    // trailer at its end.
    if (rbuf->data_size > kMaxMessageBytes) {
      node_->Dropped(channel, stats_, "impossible size " + std::to_string(rbuf->data_size) + " (a short LC02 datagram)");
      return;
    }
    std::string why;
    size_t size = rbuf->data_size;
    if (!node_->bus_auth_->Verify(channel, static_cast<const uint8_t*>(rbuf->data), size, &size,
                                  &why)) {
      node_->Dropped(channel, stats_, why);
      return;
    }
    T msg;
    if (!DecodeMessage(rbuf->data, size, &msg, &why)) {
      node_->Dropped(channel, stats_, why);
      return;
    }
    ReceiveInfo info;
    info.channel = channel;
    info.receive_time_s = node_->Now();
    info.missed_before = stats_->sequence.Observe(PublisherOf(msg), msg.header.seq);
    ++stats_->received;
    stats_->last_utime = msg.header.utime;
    try {
      callback_(msg, info);
    } catch (const std::exception& e) {
      node_->HandlerError(channel, stats_, e.what());
    }
  }

 private:
  Node* node_;
  Callback<T> callback_;
  ChannelStats* stats_;
};

template <class T>
void Node::Subscribe(const std::string& channel, Callback<T> callback, int queue_capacity) {
  ChannelStats& stats = stats_[channel];
  stats.type_name = T::getTypeName();
  auto sub = std::make_unique<TypedSubscription<T>>(this, std::move(callback), &stats);
  // LCM treats the channel as a regular expression; anchor it so "AUDIO" is not "AUDIO_X".
  lcm::Subscription* s = lcm_->subscribe("^" + channel + "$", &SubscriptionBase::Handle,
                                         static_cast<SubscriptionBase*>(sub.get()));
  if (s) s->setQueueCapacity(queue_capacity);
  subscriptions_.push_back(std::move(sub));
  if (!receive_guarded_) GuardReceiveSocket();
}

}  // namespace common
}  // namespace sarmap
