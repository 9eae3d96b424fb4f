#pragma once
// Any LCM message as JSON, decoded by its fingerprint against the types of an LcmTypeSet
// (lcm_schema.h): no generated code, no LCM library.
//
// Every length read from the message (string lengths, array counts) is checked against the
// bytes that remain before anything is allocated or looped over, so truncated or hostile data
// gives an error naming the field, never a crash or an allocation the data cannot back.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "log-tools/lcm_schema.h"

namespace sarmap {
namespace logtools {

struct LcmJsonOptions {
  // An array (each dimension on its own) with more elements than this is printed as
  // {"length": n, "min": x, "max": y, "head": [first elements]} (min/max of the finite
  // values, for numbers);
  // 0 prints every array in full.
  int64_t max_array = 64;
  // Elements kept in "head" of a summarised array.
  int64_t head = 8;
  // Integer members whose comment names constants of their struct ("// CUE_*",
  // "// bitwise OR of CUE_*") get a sibling "<member>_name" with the constant's name
  // ("CUE_SEEN_RGBD", or "CUE_SEEN_RGBD|CUE_HEARD" for bit sets).
  bool constant_names = true;
};

struct LcmJsonResult {
  bool ok = false;
  std::string type;            // full type name when the fingerprint is known
  nlohmann::ordered_json msg;  // the decoded fields (ok)
  std::string error;           // why not (not ok)
  size_t trailing_bytes = 0;   // bytes after the message (ok; LCM ignores them)
};

// Decodes one encoded message (fingerprint first).
LcmJsonResult DecodeLcmToJson(const LcmTypeSet& types, const uint8_t* data, size_t size,
                              const LcmJsonOptions& options = {});

// One output line of `sarmap-log echo` (no newline): {"recv_utime", "t_s", "channel", "type",
// "msg"} for a decoded message, {"recv_utime", "t_s", "channel", ["type",] "size", "error"}
// for one that is not; "warning" when bytes follow the message; "refused" with `refused` when
// it is not empty (why a sarmap node would drop the message). recv_utime is the logger's
// (or this process's) receive time in us, t_s the seconds since `first_utime`. Strings that
// are not UTF-8 are printed with U+FFFD for the bad bytes. indent >= 0 pretty-prints.
std::string EchoLine(int64_t recv_utime, int64_t first_utime, const std::string& channel,
                     const LcmJsonResult& result, size_t size, int indent = -1,
                     const std::string& refused = "");

// A number for JSON: floats printed with the fewest digits that give the float back (0.1f
// prints 0.1); NaN and infinities, which JSON lacks, as the strings "nan", "inf", "-inf".
nlohmann::ordered_json JsonNumber(double value);
nlohmann::ordered_json JsonNumber(float value);

}  // namespace logtools
}  // namespace sarmap
