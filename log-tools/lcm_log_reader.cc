#include "log-tools/lcm_log_reader.h"

#include <stdexcept>

#include "common/channels.h"
#include "sarmap/message_registry.h"

namespace sarmap {
namespace logtools {
namespace {

constexpr uint32_t kSync = 0xEDA1DA01;
constexpr int kHeaderSize = 4 + 8 + 8 + 4 + 4;
constexpr int32_t kMaxChannelLength = 256;
constexpr int32_t kMaxDataLength = 1 << 30;

uint64_t BigEndian(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

LcmLogReader::LcmLogReader(const std::string& path) {
  file_ = fopen(path.c_str(), "rb");
  if (!file_) throw std::runtime_error(path + ": cannot open the log");
  fseeko(file_, 0, SEEK_END);
  file_size_ = ftello(file_);
  fseeko(file_, 0, SEEK_SET);
}

LcmLogReader::~LcmLogReader() {
  if (file_) fclose(file_);
}

bool LcmLogReader::ReadAt(int64_t offset, void* out, size_t size) {
  if (offset < 0 || offset + static_cast<int64_t>(size) > file_size_) return false;
  if (fseeko(file_, offset, SEEK_SET) != 0) return false;
  return fread(out, 1, size, file_) == size;
}

// Scans forward from `from` for a sync word that starts a plausible event header.
bool LcmLogReader::Resync(int64_t from) {
  std::vector<uint8_t> buffer(1 << 16);
  for (int64_t pos = from; pos + kHeaderSize <= file_size_;) {
    const size_t want = static_cast<size_t>(std::min<int64_t>(buffer.size(), file_size_ - pos));
    if (!ReadAt(pos, buffer.data(), want)) return false;
    for (size_t i = 0; i + kHeaderSize <= want; ++i) {
      if (BigEndian(&buffer[i], 4) != kSync) continue;
      const int32_t channel_length = static_cast<int32_t>(BigEndian(&buffer[i + 20], 4));
      const int32_t data_length = static_cast<int32_t>(BigEndian(&buffer[i + 24], 4));
      if (channel_length > 0 && channel_length <= kMaxChannelLength && data_length >= 0 &&
          data_length <= kMaxDataLength) {
        offset_ = pos + static_cast<int64_t>(i);
        return true;
      }
    }
    if (want < static_cast<size_t>(kHeaderSize)) break;
    pos += static_cast<int64_t>(want) - kHeaderSize + 1;
  }
  offset_ = file_size_;
  return false;
}

bool LcmLogReader::Next(LogEvent* event) {
  while (offset_ < file_size_) {
    uint8_t header[kHeaderSize];
    const int64_t start = offset_;
    std::string problem;
    if (!ReadAt(start, header, kHeaderSize)) {
      problem = "truncated event header (" + std::to_string(file_size_ - start) + " bytes left)";
    } else if (BigEndian(header, 4) != kSync) {
      problem = "bad sync word";
    } else {
      const int32_t channel_length = static_cast<int32_t>(BigEndian(header + 20, 4));
      const int32_t data_length = static_cast<int32_t>(BigEndian(header + 24, 4));
      if (channel_length <= 0 || channel_length > kMaxChannelLength || data_length < 0 ||
          data_length > kMaxDataLength) {
        problem = "implausible event header (channel length " + std::to_string(channel_length) +
                  ", data length " + std::to_string(data_length) + ")";
      } else if (start + kHeaderSize + channel_length + data_length > file_size_) {
        problem = "truncated event: needs " + std::to_string(kHeaderSize + channel_length + data_length) +
                  " bytes, " + std::to_string(file_size_ - start) + " left";
      } else {
        event->event_number = static_cast<int64_t>(BigEndian(header + 4, 8));
        event->timestamp_us = static_cast<int64_t>(BigEndian(header + 12, 8));
        event->file_offset = start;
        event->channel.resize(channel_length);
        event->data.resize(data_length);
        ReadAt(start + kHeaderSize, event->channel.data(), channel_length);
        if (data_length > 0) ReadAt(start + kHeaderSize + channel_length, event->data.data(), data_length);
        offset_ = start + kHeaderSize + channel_length + data_length;
        last_event_ = event->event_number;
        return true;
      }
    }
    LogProblem p{start, last_event_, problem};
    const bool found = Resync(start + 1);
    p.resync_offset = found ? offset_ : -1;
    problems_.push_back(p);
    if (!found) return false;
  }
  return false;
}

std::string DescribeProblem(const LogProblem& problem) {
  std::string text = "the log breaks at byte " + std::to_string(problem.file_offset);
  if (problem.after_event >= 0)
    text += " (after event " + std::to_string(problem.after_event) + ")";
  text += ": " + problem.what;
  text += problem.resync_offset >= 0
              ? "; read on from byte " + std::to_string(problem.resync_offset)
              : "; nothing readable after it";
  return text;
}

std::string SarmapTypeName(const std::vector<uint8_t>& data) {
  if (data.size() < 8) return "";
  const int64_t hash = static_cast<int64_t>(BigEndian(data.data(), 8));
#define SARMAP_MATCH_TYPE(T) \
  if (hash == sarmap::T::getHash()) return #T;
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_MATCH_TYPE)
#undef SARMAP_MATCH_TYPE
  return "";
}

bool ReadSarmapHeader(const std::vector<uint8_t>& data, int64_t* utime, int64_t* seq) {
  if (data.size() < 24 || SarmapTypeName(data).empty()) return false;
  *utime = static_cast<int64_t>(BigEndian(data.data() + 8, 8));
  *seq = static_cast<int64_t>(BigEndian(data.data() + 16, 8));
  return true;
}

LogMessageFilter::LogMessageFilter(const common::StampGateOptions& options) : gates_(options) {}

bool LogMessageFilter::Accept(const LogEvent& event) {
  const std::string type = SarmapTypeName(event.data);
  // Only sarmap messages are checked against the bus key: nothing reads the others (liblcm's
  // LCM_SELF_TEST).
  size_t payload_size = 0;
  if (!type.empty() && !bus_auth_.Verify(event.channel, event.data.data(), event.data.size(),
                                         &payload_size, nullptr)) {
    ++not_signed_;
    return false;
  }
  for (const auto& spec : common::DefaultChannels()) {
    if (event.channel == spec.channel && type != spec.type) {
      ++wrong_type_;
      return false;
    }
  }
  int64_t utime, seq;
  if (!ReadSarmapHeader(event.data, &utime, &seq)) return true;
  const int stream =
      stream_of_channel_.emplace(event.channel, static_cast<int>(stream_of_channel_.size()))
          .first->second;
  return gates_.Accept(stream, utime, 1e-6 * static_cast<double>(event.timestamp_us));
}

std::string LogMessageFilter::Summary() const {
  if (wrong_type_ == 0 && off_clock() == 0 && not_signed_ == 0) return "";
  std::string summary = std::to_string(wrong_type_) +
                        " messages of another type than their channel's and " +
                        std::to_string(off_clock()) +
                        " stamped far ahead of their channel's clock skipped";
  if (bus_auth_.keyed()) {
    summary += ", and " + std::to_string(not_signed_) + " not signed with the bus key";
  }
  return summary;
}

}  // namespace logtools
}  // namespace sarmap
