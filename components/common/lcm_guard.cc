#include "common/lcm_guard.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <linux/filter.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <regex>

namespace sarmap {
namespace common {
namespace {

// The UDP port of a udpm:// URL; 0 for other providers.
int UdpmPort(const std::string& url) {
  static const std::regex re(R"(udpm://[^:/?]*(?::([0-9]+))?(?:[/?].*)?)");
  std::smatch m;
  if (!std::regex_match(url, m, re)) return 0;
  return m[1].matched ? std::atoi(m[1].str().c_str()) : 7667;
}

// A UDP socket filter sees the datagram from its UDP header on: the LCM payload is at 8.
constexpr uint32_t kPayload = 8;
constexpr uint32_t kMagicLong = 0x4c433033;     // "LC03": a fragment
constexpr uint32_t kFragmentHeader = 20;        // magic, seqno, size, offset, number, count
constexpr uint32_t kMaxMessageSize = 1u << 28;  // LCM_MAX_MESSAGE_SIZE of liblcm 1.3.1

}  // namespace

int GuardLcmReceiveSocket(lcm::LCM* lcm, const std::string& url, std::string* error) {
  const int port = UdpmPort(url);
  if (port <= 0) return 0;
  if (lcm != nullptr) lcm->getFileno();  // makes liblcm open its receive socket if not yet

  // Accept everything but an "LC03" fragment that is shorter than its header, claims more
  // than kMaxMessageSize, starts past its message's end, or is a first fragment (the one
  // carrying the channel) that does not start at 0.
  static sock_filter code[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, kPayload),                            // 0: A = magic
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kMagicLong, 0, 12),                  // 1: not LC03
      BPF_STMT(BPF_LD | BPF_W | BPF_LEN, 0),                                   // 2: A = length
      BPF_JUMP(BPF_JMP | BPF_JGE | BPF_K, kPayload + kFragmentHeader, 0, 11),  // 3: too short
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, kPayload + 8),                        // 4: A = size
      BPF_JUMP(BPF_JMP | BPF_JGT | BPF_K, kMaxMessageSize, 9, 0),              // 5: too large
      BPF_STMT(BPF_MISC | BPF_TAX, 0),                                         // 6: X = size
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, kPayload + 12),                       // 7: A = offset
      BPF_JUMP(BPF_JMP | BPF_JGT | BPF_X, 0, 6, 0),                            // 8: past end
      BPF_STMT(BPF_MISC | BPF_TAX, 0),                                         // 9: X = offset
      BPF_STMT(BPF_LD | BPF_H | BPF_ABS, kPayload + 16),                       // 10: A = number
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0, 0, 2),                            // 11: not first
      BPF_STMT(BPF_MISC | BPF_TXA, 0),                                         // 12: A = offset
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0, 0, 1),                            // 13: first, not 0
      BPF_STMT(BPF_RET | BPF_K, 0xffffffff),                                   // 14: accept
      BPF_STMT(BPF_RET | BPF_K, 0),                                            // 15: drop
  };
  sock_fprog program{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};

  int guarded = 0;
  DIR* dir = opendir("/proc/self/fd");
  if (dir == nullptr) {
    if (error) *error = std::string("cannot list /proc/self/fd: ") + std::strerror(errno);
    return -1;
  }
  while (const dirent* entry = readdir(dir)) {
    char* end = nullptr;
    const long fd = std::strtol(entry->d_name, &end, 10);
    if (end == entry->d_name || *end != '\0' || fd == dirfd(dir)) continue;
    int type = 0;
    socklen_t type_size = sizeof type;
    if (getsockopt(static_cast<int>(fd), SOL_SOCKET, SO_TYPE, &type, &type_size) != 0 ||
        type != SOCK_DGRAM) {
      continue;
    }
    sockaddr_in addr{};
    socklen_t addr_size = sizeof addr;
    if (getsockname(static_cast<int>(fd), reinterpret_cast<sockaddr*>(&addr), &addr_size) != 0 ||
        addr.sin_family != AF_INET || ntohs(addr.sin_port) != port) {
      continue;
    }
    if (setsockopt(static_cast<int>(fd), SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program) !=
        0) {
      if (error) *error = std::string("SO_ATTACH_FILTER: ") + std::strerror(errno);
      closedir(dir);
      return -1;
    }
    ++guarded;
  }
  closedir(dir);
  return guarded;
}

}  // namespace common
}  // namespace sarmap
