#include "common/logging.h"

#include <sys/time.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <stdexcept>

namespace sarmap {
namespace common {
namespace {

std::string& LogName() {
  static std::string name = "sarmap";
  return name;
}
LogLevel g_level = LogLevel::INFO;
std::mutex g_mutex;

const char* LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::DEBUG:
      return "D";
    case LogLevel::INFO:
      return "I";
    case LogLevel::WARN:
      return "W";
    case LogLevel::ERROR:
      return "E";
  }
  return "?";
}

}  // namespace

void SetLogName(const std::string& name) { LogName() = name; }
void SetLogLevel(LogLevel level) { g_level = level; }
LogLevel GetLogLevel() { return g_level; }

LogLevel ParseLogLevel(const std::string& text) {
  if (text == "debug") return LogLevel::DEBUG;
  if (text == "info") return LogLevel::INFO;
  if (text == "warn") return LogLevel::WARN;
  if (text == "error") return LogLevel::ERROR;
  throw std::invalid_argument("log level must be debug, info, warn or error, not '" + text + "'");
}

LogMessage::LogMessage(LogLevel level, const char* file, int line) : level_(level) {
  timeval tv;
  gettimeofday(&tv, nullptr);
  tm local;
  localtime_r(&tv.tv_sec, &local);
  char stamp[32];
  strftime(stamp, sizeof(stamp), "%H:%M:%S", &local);
  const char* base = file;
  for (const char* p = file; *p; ++p) {
    if (*p == '/') base = p + 1;
  }
  char prefix[64];
  snprintf(prefix, sizeof(prefix), ".%03ld ", static_cast<long>(tv.tv_usec / 1000));
  stream_ << LevelName(level_) << " " << stamp << prefix << LogName() << " " << base << ":" << line
          << "] ";
}

LogMessage::~LogMessage() {
  stream_ << '\n';
  std::lock_guard<std::mutex> lock(g_mutex);
  fputs(stream_.str().c_str(), stderr);
  fflush(stderr);
}

bool RateLimiter::Allow(double now_s, long* suppressed) {
  if (now_s - last_s_ >= period_s_ || now_s < last_s_) {  // also recover from clock jumps
    if (suppressed) *suppressed = suppressed_;
    suppressed_ = 0;
    last_s_ = now_s;
    return true;
  }
  ++suppressed_;
  return false;
}

std::string EscapeForLog(std::string_view text, size_t max_bytes) {
  static const char kHex[] = "0123456789abcdef";
  const size_t n = std::min(text.size(), max_bytes);
  std::string out;
  out.reserve(n + 16);
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\\') {
      out += "\\\\";
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (n < text.size()) out += "...(" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace common
}  // namespace sarmap
