#pragma once
// GuardLcmReceiveSocket(): a kernel filter on liblcm's multicast receive socket that drops the
// LCM fragments liblcm 1.3.1 cannot survive.
//
// liblcm's receive thread copies a fragment to `buffer + offset` after checking
// `offset + length > message size` in 32 bits: an offset near 2^32 wraps the sum below the
// message size and the copy lands 4 GB away (one 57-byte datagram on a subscribed channel,
// SIGSEGV), and a fragment shorter than its 20-byte header underflows its length. This all
// happens before any sarmap code sees the bytes, so the filter (classic BPF, attached with
// SO_ATTACH_FILTER) drops, before liblcm reads them, LCM fragments ("LC03") that are shorter
// than their header, claim a message above LCM_MAX_MESSAGE_SIZE, start past their message's
// end, or are first fragments (which carry the channel) not at offset 0. Then liblcm's own
// check is exact: offset <= size <= 2^28 and a fragment's data below 64 kB cannot wrap, and a
// first fragment whose channel runs past its data is refused at offset 0. LCM's senders never
// write such fragments; every other datagram passes unchanged.

#include <string>

namespace lcm {
class LCM;
}

namespace sarmap {
namespace common {

// Attaches the filter to every UDP socket of this process bound to the port of `url` (LCM's
// receive socket, created by the first subscribe). Call after subscribing. Returns the number
// of sockets guarded: 0 for a URL other than udpm://, or when there is no such socket yet;
// -1 with *error set when the kernel refuses the filter.
int GuardLcmReceiveSocket(lcm::LCM* lcm, const std::string& url, std::string* error = nullptr);

}  // namespace common
}  // namespace sarmap
