// sarmap-net-fuzz: a hostile publisher on the bus. Sends crafted datagrams over real LCM to
// every default channel (common/channels.h) and NODE_STATUS, at a set rate for a set time:
// each is a valid encoding of the channel's type with one hostile change (string lengths of
// INT32_MIN, -1, 0 or past the end; negative or huge array counts; stamps far in the future
// or past, zero or negative; NaN and infinities; strings with NUL, markup and script, invalid
// UTF-8 or 60 kB; truncations, trailing bytes, flipped bytes), random bytes, or another
// type's message (tests/fuzz/wire_mutations.h).
//
//   sarmap-net-fuzz --seconds 10 --rate 2000 [--channels REGEX] [--record sent.lcmlog]
//
// --record keeps every datagram sent in an LCM log, to replay one that took a node down
// (sarmap-log replay); --log writes one line per datagram: index, channel, kind, what.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "common/args.h"
#include "common/channels.h"
#include "common/node.h"
#include "common/time.h"
#include "tests/fuzz/wire_mutations.h"

namespace sarmap {
namespace testing {
namespace {

struct Target {
  std::string channel;
  std::string type;
};

std::vector<Target> Targets(const std::string& regex) {
  std::vector<Target> all;
  for (const auto& spec : common::DefaultChannels()) all.push_back({spec.channel, spec.type});
  // Not a data channel, but the viewer and the monitor read it.
  all.push_back({"NODE_STATUS", "node_status_t"});
  const std::regex re(regex);
  std::vector<Target> out;
  for (const Target& t : all) {
    if (std::regex_match(t.channel, re)) out.push_back(t);
  }
  return out;
}

int Main(int argc, char** argv) {
  common::ArgParser parser("sarmap-net-fuzz",
                           "Sends crafted hostile datagrams (valid fingerprints with hostile "
                           "lengths, counts, stamps and strings; NaN; random bytes) to every "
                           "default channel over LCM, at a set rate for a set time.");
  double seconds = 10, rate_hz = 2000;
  int64_t seed = 1;
  std::string channels = ".*", kinds = ".*", url, record_path, log_path;
  parser.AddFlag("--seconds", &seconds, "how long to send");
  parser.AddFlag("--rate", &rate_hz, "datagrams per second, over all channels");
  parser.AddFlag("--channels", &channels, "regular expression of the channels to target");
  parser.AddFlag("--kinds", &kinds,
                 "regular expression of the kinds of datagram: string-length, array-count, "
                 "stamp, non-finite, string-content, truncated, trailing, byte-flips, "
                 "random-bytes, wrong-type");
  parser.AddFlag("--seed", &seed, "seed of the random choices");
  parser.AddFlag("--lcm-url", &url, "LCM URL (default: $SARMAP_LCM_URL or sarmap's default)");
  parser.AddFlag("--record", &record_path, "write every datagram sent to this LCM log");
  parser.AddFlag("--log", &log_path, "write one line per datagram sent to this file");
  parser.SetEpilog(
      "Only for a private network (tests run it in a network namespace): it is an attack on\n"
      "every node listening on the LCM URL.");
  if (!parser.Parse(argc, argv)) return 0;
  if (!(seconds > 0)) throw common::ArgError("--seconds must be > 0");
  if (!(rate_hz > 0)) throw common::ArgError("--rate must be > 0");
  std::vector<Target> targets;
  try {
    targets = Targets(channels);
  } catch (const std::regex_error&) {
    throw common::ArgError("--channels: not a regular expression: " + channels);
  }
  if (targets.empty()) throw common::ArgError("--channels " + channels + " matches no channel");

  lcm::LCM lcm(url.empty() ? common::DefaultLcmUrl() : url);
  if (!lcm.good()) throw std::runtime_error("cannot open LCM on " + url);
  std::unique_ptr<lcm::LogFile> record;
  if (!record_path.empty()) {
    record = std::make_unique<lcm::LogFile>(record_path, "w");
    if (!record->good()) throw std::runtime_error("cannot write " + record_path);
  }
  std::ofstream log;
  if (!log_path.empty()) {
    log.open(log_path);
    if (!log) throw std::runtime_error("cannot write " + log_path);
  }

  HostileDatagrams hostile(static_cast<uint64_t>(seed), common::WallClockUtime());
  std::regex kinds_re;
  try {
    kinds_re = std::regex(kinds);
  } catch (const std::regex_error&) {
    throw common::ArgError("--kinds: not a regular expression: " + kinds);
  }
  if (!hostile.SetKinds([&](const std::string& k) { return std::regex_match(k, kinds_re); })) {
    throw common::ArgError("--kinds " + kinds + " matches no kind");
  }
  for (const Target& t : targets) {
    if (!hostile.Knows(t.type)) throw std::runtime_error("no samples of " + t.type);
  }
  std::mt19937_64 rng(static_cast<uint64_t>(seed) + 1);
  std::map<std::string, int64_t> by_kind;
  int64_t sent = 0, failed = 0, bytes = 0;
  std::string kind, what;
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  std::printf("sarmap-net-fuzz: %zu channels, %.0f datagrams/s for %.1f s\n", targets.size(),
              rate_hz, seconds);
  std::fflush(stdout);
  for (;;) {
    // The schedule is absolute, so a slow send does not lower the rate.
    const auto due = start + std::chrono::duration<double>(static_cast<double>(sent) / rate_hz);
    if (due >= end) break;
    std::this_thread::sleep_until(due);
    const Target& t = targets[rng() % targets.size()];
    const Bytes wire = hostile.Next(t.type, &kind, &what);
    if (lcm.publish(t.channel, wire.data(), static_cast<unsigned>(wire.size())) != 0) ++failed;
    if (record) {
      lcm::LogEvent event{};
      event.timestamp = common::WallClockUtime();
      event.channel = t.channel;
      event.datalen = static_cast<int32_t>(wire.size());
      event.data = const_cast<uint8_t*>(wire.data());
      record->writeEvent(&event);
    }
    if (log.is_open()) {
      log << sent << ' ' << t.channel << ' ' << kind << ' ' << wire.size() << " bytes: " << what
          << '\n';
    }
    ++sent;
    ++by_kind[kind];
    bytes += static_cast<int64_t>(wire.size());
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("sent %lld datagrams (%.1f MB) in %.1f s to %zu channels; %lld failed to send\n",
              static_cast<long long>(sent), static_cast<double>(bytes) / 1e6, elapsed,
              targets.size(), static_cast<long long>(failed));
  for (const auto& [name, count] : by_kind) {
    std::printf("  %-15s %lld\n", name.c_str(), static_cast<long long>(count));
  }
  return 0;
}

}  // namespace
}  // namespace testing
}  // namespace sarmap

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-net-fuzz",
                                 [&] { return sarmap::testing::Main(argc, argv); });
}
