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
// --raw-lcm attacks LCM's UDP protocol itself instead (hostile fragment headers).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
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
#include "log-tools/lcm_log_writer.h"
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

// --raw-lcm: datagrams of LCM's own UDP protocol with hostile headers, sent from a plain
// socket, for the receive thread of liblcm in every process (sarmap's decoding never sees
// them). LCM 1.3.1 udpm: a short message is "LC02" | seqno | channel NUL | payload; a fragment
// is "LC03" | seqno | message size | fragment offset | fragment number (16 bit) | fragments
// (16 bit) | (first fragment: channel NUL) | data; all big-endian.
class RawLcmSender {
 public:
  // url: udpm://GROUP:PORT?ttl=N...
  explicit RawLcmSender(const std::string& url) {
    static const std::regex re(R"(udpm://([0-9.]+)(?::([0-9]+))?(?:\?(.*))?)");
    std::smatch m;
    if (!std::regex_match(url, m, re)) {
      throw common::ArgError("--raw-lcm needs a udpm:// URL, not " + url);
    }
    std::memset(&dest_, 0, sizeof dest_);
    dest_.sin_family = AF_INET;
    dest_.sin_port = htons(static_cast<uint16_t>(m[2].matched ? std::stoi(m[2]) : 7667));
    if (inet_aton(m[1].str().c_str(), &dest_.sin_addr) == 0) {
      throw common::ArgError("bad multicast address in " + url);
    }
    int ttl = 0;
    std::smatch t;
    const std::string query = m[3];
    if (std::regex_search(query, t, std::regex(R"((?:^|&)ttl=([0-9]+))"))) ttl = std::stoi(t[1]);
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    if (fd_ < 0) throw std::runtime_error("cannot open a UDP socket");
    const unsigned char ttl_byte = static_cast<unsigned char>(ttl);
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl_byte, sizeof ttl_byte);
  }
  ~RawLcmSender() { close(fd_); }
  RawLcmSender(const RawLcmSender&) = delete;
  RawLcmSender& operator=(const RawLcmSender&) = delete;

  bool Send(const Bytes& datagram) {
    return sendto(fd_, datagram.data(), datagram.size(), 0,
                  reinterpret_cast<const sockaddr*>(&dest_),
                  sizeof dest_) == static_cast<ssize_t>(datagram.size());
  }

 private:
  int fd_ = -1;
  sockaddr_in dest_{};
};

const std::vector<std::string>& RawLcmKinds() {
  static const std::vector<std::string> kinds = {
      "lcm-fragment-offset-wrap", "lcm-fragment-past-end", "lcm-fragment-short",
      "lcm-fragment-huge",        "lcm-fragment-no-count", "lcm-short-no-nul",
      "lcm-short-header-only",    "lcm-bad-magic"};
  return kinds;
}

void Put32(Bytes* b, uint32_t v) {
  for (int i = 3; i >= 0; --i) b->push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void Put16(Bytes* b, uint16_t v) {
  b->push_back(static_cast<uint8_t>(v >> 8));
  b->push_back(static_cast<uint8_t>(v));
}

// One raw datagram of `kind` for `channel` (which the victims subscribe to).
Bytes RawLcmDatagram(const std::string& kind, const std::string& channel, uint32_t seqno,
                     std::mt19937_64& rng, std::string* what) {
  constexpr uint32_t kShort = 0x4c433032, kLong = 0x4c433033;
  Bytes b;
  const auto fragment = [&](uint32_t size, uint32_t offset, uint16_t number, uint16_t count) {
    Put32(&b, kLong);
    Put32(&b, seqno);
    Put32(&b, size);
    Put32(&b, offset);
    Put16(&b, number);
    Put16(&b, count);
    if (number == 0) b.insert(b.end(), channel.c_str(), channel.c_str() + channel.size() + 1);
  };
  if (kind == "lcm-fragment-offset-wrap") {
    // offset + length wraps past 2^32 to below the message size.
    const uint32_t length = 32;
    const uint32_t offset = 0u - (length - 16);
    fragment(100, offset, 0, 2);
    b.resize(b.size() + length, 'A');
    *what = "fragment 0 of 2, message 100 bytes, offset " + std::to_string(offset) + ", " +
            std::to_string(length) + " bytes";
  } else if (kind == "lcm-fragment-past-end") {
    fragment(100, 90, 0, 2);
    b.resize(b.size() + 32, 'B');
    *what = "fragment 0 of 2, message 100 bytes, offset 90, 32 bytes";
  } else if (kind == "lcm-fragment-short") {
    Put32(&b, kLong);
    Put32(&b, seqno);
    const size_t extra = rng() % 12;  // 8..19 bytes: shorter than a fragment header
    for (size_t i = 0; i < extra; ++i) b.push_back(static_cast<uint8_t>(rng()));
    *what = std::to_string(b.size()) + "-byte fragment (the header alone is 20)";
  } else if (kind == "lcm-fragment-huge") {
    const uint32_t size = rng() % 2 ? 0xffffffffu : 300u << 20;
    fragment(size, 0, 0, 65535);
    b.resize(b.size() + 64, 'C');
    *what = "fragment 0 of 65535, message " + std::to_string(size) + " bytes";
  } else if (kind == "lcm-fragment-no-count") {
    fragment(100, 0, 0, 0);
    b.resize(b.size() + 32, 'D');
    *what = "fragment 0 of 0";
  } else if (kind == "lcm-short-no-nul") {
    Put32(&b, kShort);
    Put32(&b, seqno);
    const size_t n = 1 + rng() % 1400;
    for (size_t i = 0; i < n; ++i) b.push_back(static_cast<uint8_t>('a' + rng() % 26));
    *what = "short message, " + std::to_string(n) + "-byte channel without NUL";
  } else if (kind == "lcm-short-header-only") {
    Put32(&b, kShort);
    b.resize(rng() % 5 + 4, 0);
    *what = std::to_string(b.size()) + "-byte short message";
  } else {
    Put32(&b, 0x4c433034 + static_cast<uint32_t>(rng() % 16));
    Put32(&b, seqno);
    b.insert(b.end(), channel.c_str(), channel.c_str() + channel.size() + 1);
    *what = "unknown magic";
  }
  return b;
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
  bool raw_lcm = false;
  parser.AddSwitch("--raw-lcm", &raw_lcm,
                   "instead: LCM protocol datagrams with hostile headers (kinds lcm-*), from a "
                   "plain UDP socket to the URL's group and port");
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

  if (raw_lcm && !record_path.empty()) {
    throw common::ArgError("--record: not with --raw-lcm (its datagrams are not LCM events)");
  }
  if (url.empty()) url = common::DefaultLcmUrl();
  lcm::LCM lcm(url);
  if (!lcm.good()) throw std::runtime_error("cannot open LCM on " + url);
  std::unique_ptr<RawLcmSender> raw;
  std::vector<std::string> raw_kinds;
  if (raw_lcm) raw = std::make_unique<RawLcmSender>(url);
  std::unique_ptr<logtools::LcmLogWriter> record;
  if (!record_path.empty()) {
    record = std::make_unique<logtools::LcmLogWriter>(record_path);
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
  const auto wanted = [&](const std::string& k) { return std::regex_match(k, kinds_re); };
  if (raw) {
    for (const std::string& k : RawLcmKinds()) {
      if (wanted(k)) raw_kinds.push_back(k);
    }
    if (raw_kinds.empty()) throw common::ArgError("--kinds " + kinds + " matches no lcm-* kind");
  } else if (!hostile.SetKinds(wanted)) {
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
    Bytes wire;
    if (raw) {
      kind = raw_kinds[rng() % raw_kinds.size()];
      // Sequence numbers far from liblcm's own, so no real message is disturbed.
      wire = RawLcmDatagram(kind, t.channel, 0x80000000u + static_cast<uint32_t>(sent), rng, &what);
      if (!raw->Send(wire)) ++failed;
    } else {
      wire = hostile.Next(t.type, &kind, &what);
      if (lcm.publish(t.channel, wire.data(), static_cast<unsigned>(wire.size())) != 0) ++failed;
    }
    if (record) record->WriteBytes(t.channel, wire.data(), wire.size(), common::WallClockUtime());
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
