#pragma once
// A tolerant reader of LCM log files (the format lcm-logger writes): each event is
//   sync word 0xEDA1DA01 | event number int64 | timestamp int64 (us) | channel length int32 |
//   data length int32 | channel | data            (all big-endian)
// Unlike lcm::LogFile it does not stop at the first damage: it reports where the log breaks
// (byte offset, last good event) and resynchronises on the next sync word, so the readable
// part of a truncated or corrupt log is still available.

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "common/bus_auth.h"
#include "common/stamp_gate.h"

namespace sarmap {
namespace logtools {

struct LogEvent {
  int64_t event_number = 0;
  int64_t timestamp_us = 0;
  int64_t file_offset = 0;
  std::string channel;
  std::vector<uint8_t> data;
};

struct LogProblem {
  int64_t file_offset;        // where the damage starts
  int64_t after_event;        // event number of the last good event before it (-1: none)
  std::string what;
  int64_t resync_offset = -1; // where reading continued (-1: end of file)
};

// "the log breaks at byte N (after event E): what; read on from byte M" (or "...; nothing
// readable after it").
std::string DescribeProblem(const LogProblem& problem);

class LcmLogReader {
 public:
  // Throws std::runtime_error when the file cannot be opened.
  explicit LcmLogReader(const std::string& path);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  // Next readable event; false at the end of the file.
  bool Next(LogEvent* event);
  const std::vector<LogProblem>& problems() const { return problems_; }
  int64_t file_size() const { return file_size_; }
  int64_t offset() const { return offset_; }

 private:
  bool ReadAt(int64_t offset, void* out, size_t size);
  bool Resync(int64_t from);

  FILE* file_ = nullptr;
  int64_t file_size_ = 0;
  int64_t offset_ = 0;
  int64_t last_event_ = -1;
  std::vector<LogProblem> problems_;
};

// Type name of an LCM message by its fingerprint (first 8 bytes), for sarmap types;
// "" when unknown.
std::string SarmapTypeName(const std::vector<uint8_t>& data);

// header.utime and header.seq of a sarmap message (they follow the fingerprint in every
// sarmap message type); false when the data is too short or the type unknown.
bool ReadSarmapHeader(const std::vector<uint8_t>& data, int64_t* utime, int64_t* seq);

// What of a recorded bus is read back as the stack's own: the log holds every datagram the
// recorder heard, a hostile publisher's too. A message is skipped (and counted) when its type
// (by fingerprint) is not its channel's (common/channels.h; channels not listed there take any
// type), or when its header stamp is far ahead of its channel's clock: common::StampGates, a
// stream per channel, on the log's receive times, as the nodes gate their inputs live (default
// options: more than 5 s ahead; behind passes; a channel's first stamp is checked against the
// clocks of the channels before it). Another type's message on a channel and stamps far ahead
// then never become a report's map, people or trail. With the bus key of a signed bus
// (common/bus_auth.h), a message is also skipped unless it is signed with that key, for its
// channel, and not heard before, as a node with the key decides live.
class LogMessageFilter {
 public:
  explicit LogMessageFilter(const common::StampGateOptions& options = {});
  void SetBusKey(common::AuthKey key) { bus_auth_ = common::BusAuth(std::move(key)); }
  bool Accept(const LogEvent& event);
  int64_t wrong_type() const { return wrong_type_; }
  int64_t off_clock() const { return gates_.dropped(); }
  int64_t not_signed() const { return not_signed_; }
  // "N messages of another type than their channel's and M stamped far ahead of their
  // channel's clock skipped" (and how many were not signed with the bus key), or "" when none
  // was.
  std::string Summary() const;

 private:
  common::BusAuth bus_auth_;
  int64_t not_signed_ = 0;
  common::StampGates gates_;
  std::map<std::string, int> stream_of_channel_;
  int64_t wrong_type_ = 0;
};

}  // namespace logtools
}  // namespace sarmap
