// The fuzz target of sarmap's decode-and-check path: one input is one datagram, handed to
// DecodeMessage<T> for every message type (the fingerprint picks at most one) and to
// CheckWire<T> for every LCM struct, nested ones included, as a node, a tool or a log reader
// would. Accepted depth images and occupancy grids are decompressed too.
//
// Besides not crashing (the sanitizers of the libFuzzer build watch memory), it asserts:
//   - a rejection comes with a one-line reason;
//   - what CheckWire accepts, the generated decoder reads to the last byte and re-encodes to
//     the same bytes (the checker and the decoder agree on the layout);
//   - what DecodeMessage accepts passes CheckMessage.
// Types come from the registry that cmake/lcm_registry.py generates, so a new .lcm file is
// fuzzed without a change here.
//
// Built twice: with clang -fsanitize=fuzzer,address,undefined as sarmap-decode-fuzz (make
// fuzz), and with the project's compiler behind tests/fuzz/standalone_driver.cc
// (sarmap-decode-fuzz-driver, run by make test).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "common/decode.h"
#include "common/image_messages.h"
#include "sarmap/message_registry.h"

// Defined by a driver that measures allocations (standalone_driver.cc), absent under libFuzzer
// (whose -malloc_limit_mb watches instead): brackets the decode of one message, whose
// allocations the bytes must justify. Payload decompression is outside: a valid compressed
// image may expand to what its checked width and height allow.
extern "C" void SarmapFuzzDecodeBegin() __attribute__((weak));
// message: DecodeMessage of a message type (else the decode of any struct after CheckWire
// passed); accepted: whether it was accepted.
extern "C" void SarmapFuzzDecodeEnd(const char* type, size_t size, bool message, bool accepted)
    __attribute__((weak));

namespace {

[[noreturn]] void Fail(const char* type, const std::string& what, size_t size) {
  std::fprintf(stderr, "decode fuzz: %s: %s (input of %zu bytes)\n", type, what.c_str(), size);
  std::fflush(stderr);
  std::abort();
}

void CheckReason(const char* type, const std::string& why, size_t size) {
  if (why.empty()) Fail(type, "rejected without a reason", size);
  if (why.find('\n') != std::string::npos) Fail(type, "reason spans lines: " + why, size);
}

// Depth images and grids carry compressed payloads that receivers decode next.
void DecodePayload(const sarmap::image_t& image) {
  if (image.pixel_format != sarmap::image_t::PIXEL_DEPTH_U16) return;
  std::vector<uint16_t> depth;
  std::string error;
  if (!sarmap::common::DecodeDepthImage(image, &depth, &error)) {
    CheckReason("image_t payload", error, image.data.size());
  } else if (depth.size() != static_cast<size_t>(image.width) * image.height) {
    Fail("image_t payload", "depth of the wrong size", image.data.size());
  }
}
void DecodePayload(const sarmap::occupancy_grid_t& grid) {
  std::vector<int8_t> cells;
  std::string error;
  if (!sarmap::common::DecodeOccupancyGrid(grid, &cells, &error)) {
    CheckReason("occupancy_grid_t payload", error, grid.data.size());
  } else if (cells.size() != static_cast<size_t>(grid.width) * grid.height) {
    Fail("occupancy_grid_t payload", "grid of the wrong size", grid.data.size());
  }
}
template <class T>
void DecodePayload(const T&) {}

template <class T>
void CheckWireAgreesWithTheDecoder(const uint8_t* data, size_t size) {
  std::string why;
  if (!sarmap::common::CheckWire<T>(data, size, &why)) {
    CheckReason(T::getTypeName(), why, size);
    return;
  }
  T msg;
  if (SarmapFuzzDecodeBegin) SarmapFuzzDecodeBegin();
  const int read = msg.decode(data, 0, static_cast<int>(size));
  if (read != static_cast<int>(size)) {
    Fail(T::getTypeName(), "accepted, but the decoder read " + std::to_string(read) + " bytes",
         size);
  }
  if (SarmapFuzzDecodeEnd) SarmapFuzzDecodeEnd(T::getTypeName(), size, false, true);
  std::vector<uint8_t> again(static_cast<size_t>(msg.getEncodedSize()));
  if (again.size() != size ||
      msg.encode(again.data(), 0, static_cast<int>(again.size())) != static_cast<int>(size) ||
      std::memcmp(again.data(), data, size) != 0) {
    Fail(T::getTypeName(), "accepted, but does not re-encode to the same bytes", size);
  }
}

template <class T>
void DecodeAndCheck(const uint8_t* data, size_t size) {
  T msg;
  std::string why;
  if (SarmapFuzzDecodeBegin) SarmapFuzzDecodeBegin();
  const bool accepted = sarmap::common::DecodeMessage(data, size, &msg, &why);
  if (SarmapFuzzDecodeEnd) SarmapFuzzDecodeEnd(T::getTypeName(), size, true, accepted);
  if (!accepted) {
    CheckReason(T::getTypeName(), why, size);
    return;
  }
  const std::string problem = sarmap::common::CheckMessage(msg);
  if (!problem.empty()) Fail(T::getTypeName(), "accepted, but CheckMessage says " + problem, size);
  DecodePayload(msg);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // LCM hands a subscriber a non-null pointer even for an empty datagram.
  static const uint8_t kEmpty[1] = {0};
  if (data == nullptr) data = kEmpty;
#define SARMAP_FUZZ_WIRE(T) CheckWireAgreesWithTheDecoder<sarmap::T>(data, size);
  SARMAP_FOR_EACH_LCM_TYPE(SARMAP_FUZZ_WIRE)
#undef SARMAP_FUZZ_WIRE
#define SARMAP_FUZZ_DECODE(T) DecodeAndCheck<sarmap::T>(data, size);
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_FUZZ_DECODE)
#undef SARMAP_FUZZ_DECODE
  return 0;
}
