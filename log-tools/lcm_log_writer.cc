#include "log-tools/lcm_log_writer.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

namespace sarmap {
namespace logtools {

LcmLogWriter::LcmLogWriter(const std::string& path) : path_(path) {
  errno = 0;
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good()) {
    throw std::runtime_error("cannot create the log file '" + path + "': " + std::strerror(errno));
  }
}

LcmLogWriter::~LcmLogWriter() = default;

void LcmLogWriter::WriteBytes(const std::string& channel, const void* data, size_t size,
                              int64_t timestamp_us) {
  lcm::LogEvent event;
  event.eventnum = events_;  // lcm::LogFile numbers the events itself
  event.timestamp = timestamp_us;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(size);
  event.data = const_cast<void*>(data);
  errno = 0;
  if (log_->writeEvent(&event) != 0) {
    throw std::runtime_error("error writing the log file '" + path_ + "'" +
                             (errno != 0 ? std::string(": ") + std::strerror(errno) : ""));
  }
  ++events_;
}

void LcmLogWriter::Flush() {
  if (std::fflush(log_->getFilePtr()) != 0) {
    throw std::runtime_error("error writing the log file '" + path_ + "': " + std::strerror(errno));
  }
}

}  // namespace logtools
}  // namespace sarmap
