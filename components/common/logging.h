#pragma once
// Minimal leveled logging to stderr: one line per event, prefixed with time, level and
// node name, so logs from many processes (captured by the launcher) stay readable.
//
//   SARMAP_LOG(INFO) << "listening on " << url;
//   RateLimiter limit(1.0);  if (limit.Allow(now_s)) SARMAP_LOG(WARN) << ...;

#include <cstddef>
#include <sstream>
#include <string>
#include <string_view>

namespace sarmap {
namespace common {

enum class LogLevel { DEBUG = 0, INFO = 1, WARN = 2, ERROR = 3 };

// Process-wide settings; set once at start-up (by the node runtime).
void SetLogName(const std::string& name);
void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
// Parses "debug", "info", "warn", "error"; throws std::invalid_argument otherwise.
LogLevel ParseLogLevel(const std::string& text);

class LogMessage {
 public:
  LogMessage(LogLevel level, const char* file, int line);
  ~LogMessage();
  std::ostream& stream() { return stream_; }

 private:
  LogLevel level_;
  std::ostringstream stream_;
};

// A string from the bus (a name, an id, a keyword, a decode error quoting one) made safe for a
// log line or a terminal: printable ASCII is kept, a backslash is doubled, and every other byte
// (newlines, control characters, ANSI escapes, anything not ASCII) becomes \xNN, so no message
// can forge a log line or drive the terminal. Input beyond `max_bytes` is cut and counted
// ("...(N bytes)").
std::string EscapeForLog(std::string_view text, size_t max_bytes = 256);

// Allows at most one event per `period_s` (of the caller's clock); counts the rest so the
// next allowed line can say how many were suppressed.
class RateLimiter {
 public:
  explicit RateLimiter(double period_s) : period_s_(period_s) {}
  // True when an event at `now_s` may be logged; `suppressed` gets the number of events
  // swallowed since the last allowed one.
  bool Allow(double now_s, long* suppressed = nullptr);

 private:
  double period_s_;
  double last_s_ = -1e300;
  long suppressed_ = 0;
};

}  // namespace common
}  // namespace sarmap

namespace sarmap {
namespace common {
// Turns the stream expression into void so the macro is one expression (safe in an unbraced if).
struct LogVoidify {
  void operator&(std::ostream&) {}
};
}  // namespace common
}  // namespace sarmap

#define SARMAP_LOG(level)                                                                       \
  (::sarmap::common::LogLevel::level < ::sarmap::common::GetLogLevel())                         \
      ? (void)0                                                                                 \
      : ::sarmap::common::LogVoidify() &                                                        \
            ::sarmap::common::LogMessage(::sarmap::common::LogLevel::level, __FILE__, __LINE__) \
                .stream()
