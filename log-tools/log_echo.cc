// sarmap-log echo: prints the messages of any channel of an LCM log, or of the live bus, as
// JSON lines, decoded generically from the .lcm type definitions read at run time
// (lcm_schema.h, lcm_json.h), like lcm-echo.
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <regex>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/decode.h"
#include "common/lcm_guard.h"
#include "common/node.h"
#include "common/signal_handlers.h"
#include "log-tools/lcm_json.h"
#include "log-tools/lcm_log_reader.h"
#include "sarmap/message_registry.h"

namespace {

using sarmap::common::ArgError;
using sarmap::logtools::LcmJsonOptions;
using sarmap::logtools::LcmTypeSet;

// Why a sarmap node would drop this message (common::DecodeMessage: wire, decoder and value
// checks), "" when it would take it or the type is not one this build knows.
std::string NodeVerdict(const uint8_t* data, size_t size) {
  if (size < 8) return "";
  int64_t hash = 0;
  for (int i = 0; i < 8; ++i)
    hash = static_cast<int64_t>((static_cast<uint64_t>(hash) << 8) | data[i]);
  std::string why;
#define SARMAP_VERDICT(T)                                                    \
  if (hash == sarmap::T::getHash()) {                                        \
    sarmap::T msg;                                                           \
    return sarmap::common::DecodeMessage(data, size, &msg, &why) ? "" : why; \
  }
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_VERDICT)
#undef SARMAP_VERDICT
  return "";
}

volatile sig_atomic_t g_stop = 0;
void OnStop(int) { g_stop = 1; }

struct EchoOptions {
  std::string log;
  bool live = false;
  std::string lcm_url;
  std::string channels = ".*";
  int64_t limit = 0;  // 0: no limit
  double from_s = 0;
  double to_s = std::numeric_limits<double>::infinity();
  bool full = false;
  bool pretty = false;
  bool no_constant_names = false;
  bool no_check = false;
  std::vector<std::string> type_dirs;
  LcmJsonOptions json;

  void Validate() const {
    if (live == !log.empty()) throw ArgError("give a LOG or --live (not both)");
    if (limit < 0) throw ArgError("--limit must be >= 0");
    if (live && (from_s != 0 || std::isfinite(to_s))) {
      throw ArgError("--from/--to apply to a log, not to --live");
    }
    if (!(from_s >= 0) || !(to_s >= from_s)) throw ArgError("need 0 <= --from <= --to");
    if (!log.empty() && access(log.c_str(), R_OK) != 0) {
      throw ArgError(log + ": " + std::strerror(errno));
    }
    if (json.max_array < 0) throw ArgError("--max-array must be >= 0");
    if (json.head < 0) throw ArgError("--head must be >= 0");
  }
};

// Prints the messages that pass the channel filter, counts what could not be decoded.
class Echo {
 public:
  Echo(const LcmTypeSet& types, const EchoOptions& options)
      : types_(types), options_(options), channels_(options.channels) {}

  // false once --limit is reached.
  bool OnMessage(int64_t recv_utime, const std::string& channel, const uint8_t* data, size_t size) {
    if (first_utime_ < 0) first_utime_ = recv_utime;
    if (!std::regex_match(channel, channels_)) return true;
    const auto result = sarmap::logtools::DecodeLcmToJson(types_, data, size, options_.json);
    if (!result.ok) ++errors_;
    const std::string refused = result.ok && !options_.no_check ? NodeVerdict(data, size) : "";
    if (!refused.empty()) ++refused_;
    const std::string line = sarmap::logtools::EchoLine(recv_utime, first_utime_, channel, result,
                                                        size, options_.pretty ? 2 : -1, refused);
    fputs(line.c_str(), stdout);
    fputc('\n', stdout);
    if (options_.live) fflush(stdout);
    return options_.limit == 0 || ++printed_ < options_.limit;
  }

  int64_t first_utime() const { return first_utime_; }
  void set_first_utime(int64_t utime) { first_utime_ = utime; }
  int64_t errors() const { return errors_; }
  int64_t refused() const { return refused_; }

 private:
  const LcmTypeSet& types_;
  const EchoOptions& options_;
  std::regex channels_;
  int64_t first_utime_ = -1;
  int64_t printed_ = 0, errors_ = 0, refused_ = 0;
};

int EchoLog(Echo* echo, const EchoOptions& options) {
  sarmap::logtools::LcmLogReader reader(options.log);
  sarmap::logtools::LogEvent event;
  while (reader.Next(&event)) {
    if (echo->first_utime() < 0) echo->set_first_utime(event.timestamp_us);
    const double t_s = static_cast<double>(event.timestamp_us - echo->first_utime()) / 1e6;
    if (t_s < options.from_s) continue;
    if (t_s > options.to_s) break;
    if (!echo->OnMessage(event.timestamp_us, event.channel, event.data.data(), event.data.size())) {
      break;
    }
  }
  for (const auto& p : reader.problems()) {
    fprintf(stderr, "sarmap-log echo: %s: damaged at byte %lld (after event %lld): %s%s\n",
            options.log.c_str(), static_cast<long long>(p.file_offset),
            static_cast<long long>(p.after_event), p.what.c_str(),
            p.resync_offset >= 0
                ? (", read on from byte " + std::to_string(p.resync_offset)).c_str()
                : "");
  }
  return reader.problems().empty() ? 0 : 3;
}

int EchoLive(Echo* echo, const EchoOptions& options) {
  std::string url = options.lcm_url.empty() ? sarmap::common::DefaultLcmUrl() : options.lcm_url;
  sarmap::common::SetSignalHandler({SIGINT, SIGTERM}, OnStop);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    throw std::runtime_error("cannot initialise LCM on '" + url +
                             "' (is there a multicast route? see README, 'Networking')");
  }
  struct Context {
    Echo* echo;
    bool more;
  } context{echo, true};
  // Every channel, filtered here with the same regular expression as for a log.
  lcm.subscribeFunction(
      ".*",
      +[](const lcm::ReceiveBuffer* rbuf, const std::string& channel, Context* ctx) {
        if (!ctx->more) return;
        ctx->more = ctx->echo->OnMessage(rbuf->recv_utime, channel,
                                         static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
      },
      &context);
  // Subscribed to every channel: guarded against the LCM fragments liblcm cannot survive.
  std::string guard_error;
  if (sarmap::common::GuardLcmReceiveSocket(&lcm, url, &guard_error) < 0) {
    fprintf(stderr, "sarmap-log echo: warning: no filter for hostile LCM fragments: %s\n",
            guard_error.c_str());
  }
  while (!g_stop && context.more) {
    if (lcm.handleTimeout(100) < 0 && !g_stop && errno != EINTR) {
      // LCM's file:// provider (a log played as the bus) ends this way.
      if (url.rfind("file://", 0) == 0) break;
      throw std::runtime_error(std::string("LCM receive failed") +
                               (errno ? std::string(": ") + std::strerror(errno) : ""));
    }
  }
  return 0;
}

int Main(int argc, char** argv) {
  sarmap::common::ArgParser parser(
      "sarmap-log echo",
      "Prints the messages of an LCM log (or of the live bus) as JSON lines, one per message,\n"
      "decoded from the .lcm type definitions by each message's fingerprint: any sarmap\n"
      "channel, no generated code needed.");
  EchoOptions options;
  parser.AddPositional("LOG", &options.log, "LCM log (or --live)", false);
  parser.AddSwitch("--live", &options.live, "print what arrives on the bus until Ctrl-C");
  parser.AddFlag("--lcm-url", &options.lcm_url,
                 "LCM URL with --live (default: the sarmap default)");
  parser.AddFlag("--channel", &options.channels,
                 "regular expression a channel must match in full (also --channels)");
  parser.AddFlag("--channels", &options.channels, "same as --channel");
  parser.AddFlag("--limit", &options.limit, "stop after this many messages (0: no limit)");
  parser.AddFlag("--from", &options.from_s, "start this many seconds after the log's first event");
  parser.AddFlag("--to", &options.to_s, "stop this many seconds after the log's first event");
  parser.AddFlag("--max-array", &options.json.max_array,
                 "print an array longer than this as {length, min, max, head} (0: in full)");
  parser.AddFlag("--head", &options.json.head, "elements shown in \"head\" of such an array");
  parser.AddSwitch("--full", &options.full, "print every array in full (--max-array 0)");
  parser.AddSwitch("--pretty", &options.pretty, "indented JSON, one object over several lines");
  parser.AddSwitch("--no-constant-names", &options.no_constant_names,
                   "no \"<member>_name\" beside members that hold one of their type's constants");
  parser.AddSwitch("--no-check", &options.no_check,
                   "do not say which messages a sarmap node would refuse (\"refused\")");
  parser.AddRepeated("--types", &options.type_dirs,
                     "directory of .lcm files (repeatable; default: " SARMAP_LCMTYPES_DIR ")");
  parser.SetEpilog(
      "Each line: {\"recv_utime\": logger receive time (us), \"t_s\": seconds since the first\n"
      "event, \"channel\", \"type\", \"msg\": {fields}}; a message that cannot be decoded gives\n"
      "{..., \"size\", \"error\"} and the next one is read. A message a sarmap node would drop\n"
      "(its checks of values and sizes) carries \"refused\": why.\n\n"
      "Examples:\n"
      "  sarmap-log echo mission.lcmlog --channel PEOPLE_VISUAL\n"
      "  sarmap-log echo mission.lcmlog --channel 'PEOPLE_.*' --from 10 --to 20 --pretty\n"
      "  sarmap-log echo --live --channel POSE --limit 5\n"
      "  sarmap-log echo mission.lcmlog --channel PEOPLE_VISUAL | jq "
      "'.msg.detections[].position_m'\n");
  if (!parser.Parse(argc, argv)) return 0;
  if (options.full) options.json.max_array = 0;
  options.json.constant_names = !options.no_constant_names;
  options.Validate();
  if (options.type_dirs.empty()) options.type_dirs.push_back(SARMAP_LCMTYPES_DIR);

  LcmTypeSet types;
  std::vector<std::string> errors;
  for (const auto& dir : options.type_dirs) types.AddDirectory(dir, &errors);
  if (errors.empty()) types.Resolve(&errors);
  if (!errors.empty()) {
    for (const auto& e : errors) fprintf(stderr, "sarmap-log echo: %s\n", e.c_str());
    throw ArgError("cannot read the LCM types (give the lcmtypes directory with --types DIR)");
  }
  for (const auto& a : types.ambiguities())
    fprintf(stderr, "sarmap-log echo: warning: %s\n", a.c_str());
  try {
    std::regex check(options.channels);
  } catch (const std::regex_error& e) {
    throw ArgError("--channel: invalid regular expression '" + options.channels + "'");
  }

  Echo echo(types, options);
  const int code = options.live ? EchoLive(&echo, options) : EchoLog(&echo, options);
  fflush(stdout);
  if (echo.errors() > 0) {
    fprintf(stderr, "sarmap-log echo: %lld messages could not be decoded (\"error\" lines)\n",
            static_cast<long long>(echo.errors()));
  }
  if (echo.refused() > 0) {
    fprintf(stderr, "sarmap-log echo: %lld messages a sarmap node would refuse (\"refused\")\n",
            static_cast<long long>(echo.refused()));
  }
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log echo", [&] { return Main(argc, argv); });
}
