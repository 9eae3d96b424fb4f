#pragma once
// Writes LCM log files in the format lcm-logger writes (lcm::LogFile numbers the events), for
// the tools and tests that make logs: one place that encodes a message, stamps its receive
// time and turns a failed write into an error naming the file.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lcm {
class LogFile;
}

namespace sarmap {
namespace logtools {

class LcmLogWriter {
 public:
  // Creates (or truncates) `path`; throws std::runtime_error naming it when that fails.
  explicit LcmLogWriter(const std::string& path);
  ~LcmLogWriter();
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;

  // One event: channel, encoded message and receive time (us). Throws std::runtime_error
  // naming the file when the write fails.
  void WriteBytes(const std::string& channel, const void* data, size_t size, int64_t timestamp_us);
  void WriteBytes(const std::string& channel, const std::vector<uint8_t>& data,
                  int64_t timestamp_us) {
    WriteBytes(channel, data.data(), data.size(), timestamp_us);
  }
  // Any lcm-gen message type, encoded.
  template <class Message>
  void Write(const std::string& channel, const Message& message, int64_t timestamp_us) {
    buffer_.resize(static_cast<size_t>(message.getEncodedSize()));
    message.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
    WriteBytes(channel, buffer_.data(), buffer_.size(), timestamp_us);
  }
  // Pushes what is buffered to the file; throws std::runtime_error naming it when that fails.
  void Flush();

  const std::string& path() const { return path_; }
  int64_t events() const { return events_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  std::vector<uint8_t> buffer_;
  int64_t events_ = 0;
};

}  // namespace logtools
}  // namespace sarmap
