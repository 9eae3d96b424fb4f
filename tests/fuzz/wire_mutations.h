#pragma once
// Hostile datagrams made from valid encodings, for the decode fuzzer and the network fuzzer.
//
// WireFields walks one valid encoding of a type with the generated layout
// (sarmap/message_wire_layout.h) and records where its string lengths, array counts and
// fixed-size primitives sit. Mutate() then crafts one datagram of a kind: a valid fingerprint
// with a hostile string length or array count, a far-future or negative stamp, NaN or
// infinity in a number, a string holding NUL, markup or 60 kB, a truncation, trailing bytes,
// flipped bytes or random bytes. HostileDatagrams draws such datagrams for any message type,
// by type name.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "common/wire_check.h"
#include "sarmap/message_registry.h"
#include "sarmap/message_wire_layout.h"
#include "tests/fuzz/samples.h"

namespace sarmap {
namespace testing {

struct WireSlot {
  size_t offset = 0;  // strings: the int32 length; others: the first byte
  size_t bytes = 0;   // strings: the string's bytes, NUL included
  std::string path;   // e.g. "header.utime", "sources[2].id"
};

// Where the fields of one valid encoding sit (offsets count the 8-byte fingerprint).
class WireFields {
 public:
  WireFields() = default;
  // False when `wire` is not an acceptable encoding of T.
  template <class T>
  static bool Find(const Bytes& wire, WireFields* out) {
    if (!common::CheckWire<T>(wire.data(), wire.size(), nullptr)) return false;
    *out = WireFields(wire.data(), wire.size());
    return WalkWire(*out, static_cast<const T*>(nullptr));
  }

  std::vector<WireSlot> strings;
  std::vector<WireSlot> counts;      // integers that size arrays
  std::vector<WireSlot> primitives;  // one primitive field, or all elements of a primitive array

  // The walker interface of WalkWire (see message_wire_layout.h).
  bool Skip(const char* name, uint64_t bytes) {
    if (bytes > size_ - pos_) return false;
    if (bytes > 0) primitives.push_back({pos_, static_cast<size_t>(bytes), Path(name, -1)});
    pos_ += static_cast<size_t>(bytes);
    return true;
  }
  bool Integer(const char* name, int bytes, int64_t* value) {
    if (static_cast<size_t>(bytes) > size_ - pos_) return false;
    counts.push_back({pos_, static_cast<size_t>(bytes), Path(name, -1)});
    *value = Read(bytes);
    return true;
  }
  bool String(const char* name, int64_t index) {
    if (4 > size_ - pos_) return false;
    const size_t at = pos_;
    const int64_t length = Read(4);
    if (length < 1 || static_cast<uint64_t>(length) > size_ - pos_) return false;
    strings.push_back({at, static_cast<size_t>(length), Path(name, index)});
    pos_ += static_cast<size_t>(length);
    return true;
  }
  template <class S>
  bool Struct(const char* name, int64_t index, const S* tag) {
    const std::string saved = prefix_;
    prefix_ = Path(name, index) + ".";
    const bool ok = WalkWire(*this, tag);
    prefix_ = saved;
    return ok;
  }
  bool Count(const char*, std::initializer_list<int64_t> dims, size_t, uint64_t* n) {
    *n = 1;
    for (int64_t d : dims) *n *= static_cast<uint64_t>(d);
    return true;
  }

 private:
  WireFields(const uint8_t* data, size_t size) : data_(data), size_(size), pos_(8) {}
  std::string Path(const char* name, int64_t index) const {
    return prefix_ + name + (index < 0 ? "" : "[" + std::to_string(index) + "]");
  }
  int64_t Read(int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | data_[pos_ + i];
    pos_ += static_cast<size_t>(bytes);
    const int shift = 64 - 8 * bytes;
    return static_cast<int64_t>(v << shift) >> shift;
  }

  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 0;
  std::string prefix_;
};

// Writes `value` big-endian into `bytes` bytes at `offset`.
inline void PutBigEndian(Bytes* wire, size_t offset, size_t bytes, uint64_t value) {
  for (size_t i = 0; i < bytes; ++i) {
    (*wire)[offset + i] = static_cast<uint8_t>(value >> (8 * (bytes - 1 - i)));
  }
}

enum class Mutation {
  kStringLength,   // INT32_MIN, -1, 0, huge, one past the end
  kArrayCount,     // negative, INT32_MIN/MAX, ten million, one past the end
  kStamp,          // header.utime (and every *utime) far future / past, zero, negative
  kNonFinite,      // NaN, +-Inf, DBL_MAX in a double or float slot
  kStringContent,  // NUL inside, markup and script, invalid UTF-8, 60 kB
  kTruncated,
  kTrailing,
  kByteFlips,
  kRandomBytes,  // random length, half of them behind the right fingerprint
  kCount
};

inline const char* MutationName(Mutation m) {
  switch (m) {
    case Mutation::kStringLength:
      return "string-length";
    case Mutation::kArrayCount:
      return "array-count";
    case Mutation::kStamp:
      return "stamp";
    case Mutation::kNonFinite:
      return "non-finite";
    case Mutation::kStringContent:
      return "string-content";
    case Mutation::kTruncated:
      return "truncated";
    case Mutation::kTrailing:
      return "trailing";
    case Mutation::kByteFlips:
      return "byte-flips";
    case Mutation::kRandomBytes:
      return "random-bytes";
    case Mutation::kCount:
      break;
  }
  return "?";
}

// Values a hostile sender puts in a string length field; `left` is the bytes after it.
inline std::vector<int64_t> HostileStringLengths(size_t left) {
  return {std::numeric_limits<int32_t>::min(), -1,         0,
          std::numeric_limits<int32_t>::max(), 0x40000000, static_cast<int64_t>(left) + 1};
}
// ... in an array count (`left` bytes after it).
inline std::vector<int64_t> HostileCounts(size_t left) {
  return {-1,    std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::max(), 10000000,
          65536, static_cast<int64_t>(left) + 1};
}
// ... in a stamp, around `now_utime` (microseconds since the epoch).
inline std::vector<int64_t> HostileStamps(int64_t now_utime) {
  constexpr int64_t kYear = 365LL * 24 * 3600 * 1000000;
  return {std::numeric_limits<int64_t>::max(),
          std::numeric_limits<int64_t>::min(),
          0,
          -1,
          1,
          now_utime + kYear,
          now_utime + 100 * kYear,
          253402300799000000LL,  // 9999-12-31
          now_utime - kYear,
          now_utime - 50 * kYear};
}
// Bit patterns of hostile doubles and floats.
inline std::vector<uint64_t> HostileDoubleBits() {
  return {0x7ff8000000000000ULL,   // quiet NaN
          0x7ff0000000000001ULL,   // signalling NaN
          0xfff8000000000000ULL,   // negative NaN
          0x7ff0000000000000ULL,   // +Inf
          0xfff0000000000000ULL,   // -Inf
          0x7fefffffffffffffULL,   // DBL_MAX
          0x0000000000000001ULL,   // smallest denormal
          0x8000000000000000ULL};  // -0
}
inline std::vector<uint32_t> HostileFloatBits() {
  return {0x7fc00000u, 0x7f800001u, 0x7f800000u, 0xff800000u, 0x7f7fffffu, 0x00000001u};
}
// String contents (without the terminating NUL, which the splice adds).
inline std::vector<std::string> HostileStrings() {
  return {std::string("map\0evil", 8),
          std::string(1, '\0'),
          "",
          "<script>fetch('/x?'+document.cookie+location)</script>",
          "\"><img src=x onerror=alert(1)>",
          "</textarea><svg onload=alert(document.domain)>",
          "javascript:alert(1)",
          "'; DROP TABLE people; --",
          "../../../../../etc/passwd",
          "\x1b[2J\x1b[31mred\x07",
          "\xff\xfe\xc0\x80\xed\xa0\x80 not utf-8",
          "%s%s%s%n%n",
          "line\nbreak\r\n\ttab",
          std::string(256, 'A'),
          std::string(4096, 'B'),
          std::string(60000, 'C')};
}

// Replaces the contents of the string whose length sits at `slot.offset`.
inline Bytes SpliceString(const Bytes& valid, const WireSlot& slot, const std::string& content) {
  Bytes out(valid.begin(), valid.begin() + static_cast<std::ptrdiff_t>(slot.offset));
  const uint64_t length = content.size() + 1;
  out.resize(out.size() + 4);
  PutBigEndian(&out, slot.offset, 4, length);
  out.insert(out.end(), content.begin(), content.end());
  out.push_back(0);
  out.insert(out.end(), valid.begin() + static_cast<std::ptrdiff_t>(slot.offset + 4 + slot.bytes),
             valid.end());
  return out;
}

// One datagram of kind `kind` made from `valid` (whose fields are `fields`). False when the
// encoding has nothing to mutate of that kind (e.g. no array). *what: one line saying what
// was done, e.g. "header.frame length -2147483648".
template <class Rng>
bool Mutate(Mutation kind, const Bytes& valid, const WireFields& fields, int64_t now_utime,
            Rng& rng, Bytes* out, std::string* what) {
  const auto pick = [&rng](size_t n) { return static_cast<size_t>(rng() % n); };
  *out = valid;
  switch (kind) {
    case Mutation::kStringLength: {
      if (fields.strings.empty()) return false;
      const WireSlot& s = fields.strings[pick(fields.strings.size())];
      const auto values = HostileStringLengths(valid.size() - s.offset - 4);
      const int64_t v = values[pick(values.size())];
      PutBigEndian(out, s.offset, 4, static_cast<uint64_t>(v));
      *what = s.path + " length " + std::to_string(v);
      return true;
    }
    case Mutation::kArrayCount: {
      if (fields.counts.empty()) return false;
      const WireSlot& c = fields.counts[pick(fields.counts.size())];
      const auto values = HostileCounts(valid.size() - c.offset - c.bytes);
      const int64_t v = values[pick(values.size())];
      PutBigEndian(out, c.offset, c.bytes, static_cast<uint64_t>(v));
      *what = c.path + " count " + std::to_string(v);
      return true;
    }
    case Mutation::kStamp: {
      std::vector<const WireSlot*> stamps;
      for (const WireSlot& p : fields.primitives) {
        const std::string& n = p.path;
        if (p.bytes == 8 && n.size() >= 5 && n.compare(n.size() - 5, 5, "utime") == 0) {
          stamps.push_back(&p);
        }
      }
      if (stamps.empty()) return false;
      // Mostly header.utime, the stamp every node orders its inputs by.
      const WireSlot& s = (rng() % 4 != 0) ? *stamps[0] : *stamps[pick(stamps.size())];
      const auto values = HostileStamps(now_utime);
      const int64_t v = values[pick(values.size())];
      PutBigEndian(out, s.offset, 8, static_cast<uint64_t>(v));
      *what = s.path + " = " + std::to_string(v);
      return true;
    }
    case Mutation::kNonFinite: {
      std::vector<const WireSlot*> slots;
      for (const WireSlot& p : fields.primitives) {
        if (p.bytes % 4 == 0) slots.push_back(&p);
      }
      if (slots.empty()) return false;
      const WireSlot& s = *slots[pick(slots.size())];
      // Every element of the slot, or one.
      const bool all = rng() % 4 == 0;
      if (s.bytes % 8 == 0 && rng() % 3 != 0) {
        const auto values = HostileDoubleBits();
        const uint64_t v = values[pick(values.size())];
        const size_t n = s.bytes / 8, first = all ? 0 : pick(n), last = all ? n : first + 1;
        for (size_t i = first; i < last; ++i) PutBigEndian(out, s.offset + 8 * i, 8, v);
        char text[40];
        double d;
        std::memcpy(&d, &v, sizeof d);
        std::snprintf(text, sizeof text, "%g", d);
        *what = s.path + (all ? "[*]" : "[" + std::to_string(first) + "]") + " = double " + text;
      } else {
        const auto values = HostileFloatBits();
        const uint32_t v = values[pick(values.size())];
        const size_t n = s.bytes / 4, first = all ? 0 : pick(n), last = all ? n : first + 1;
        for (size_t i = first; i < last; ++i) PutBigEndian(out, s.offset + 4 * i, 4, v);
        char text[40];
        float f;
        std::memcpy(&f, &v, sizeof f);
        std::snprintf(text, sizeof text, "%g", static_cast<double>(f));
        *what = s.path + (all ? "[*]" : "[" + std::to_string(first) + "]") + " = float " + text;
      }
      return true;
    }
    case Mutation::kStringContent: {
      if (fields.strings.empty()) return false;
      const WireSlot& s = fields.strings[pick(fields.strings.size())];
      const auto values = HostileStrings();
      const std::string& v = values[pick(values.size())];
      *out = SpliceString(valid, s, v);
      std::string shown;
      for (char c : v.substr(0, 24)) {
        const auto u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f) {
          shown += c;
        } else {
          char hex[8];
          std::snprintf(hex, sizeof hex, "\\x%02x", u);
          shown += hex;
        }
      }
      *what = s.path + " = \"" + shown + (v.size() > 24 ? "...\" (" : "\" (") +
              std::to_string(v.size()) + " bytes)";
      return true;
    }
    case Mutation::kTruncated: {
      const size_t size = pick(valid.size());
      out->resize(size);
      *what = "truncated to " + std::to_string(size) + " of " + std::to_string(valid.size());
      return true;
    }
    case Mutation::kTrailing: {
      const size_t extra = 1 + pick(64);
      for (size_t i = 0; i < extra; ++i) out->push_back(static_cast<uint8_t>(rng()));
      *what = std::to_string(extra) + " trailing bytes";
      return true;
    }
    case Mutation::kByteFlips: {
      if (valid.size() <= 8) return false;
      const int flips = 1 + static_cast<int>(pick(4));
      for (int i = 0; i < flips; ++i) {
        (*out)[8 + pick(valid.size() - 8)] ^= static_cast<uint8_t>(1 + rng() % 255);
      }
      *what = std::to_string(flips) + " bytes flipped";
      return true;
    }
    case Mutation::kRandomBytes: {
      const bool fingerprint = rng() % 2 == 0;
      out->assign(pick(600), 0);
      for (auto& b : *out) b = static_cast<uint8_t>(rng());
      if (fingerprint) out->insert(out->begin(), valid.begin(), valid.begin() + 8);
      *what = std::to_string(out->size()) + " random bytes" +
              (fingerprint ? " behind the fingerprint" : "");
      return true;
    }
    case Mutation::kCount:
      break;
  }
  return false;
}

// Valid encodings of one message type and where their fields sit.
struct TypeCorpus {
  std::string type_name;
  std::vector<Bytes> valid;
  std::vector<WireFields> fields;
  bool last_is_sane = false;  // valid.back() passes CheckMessage()
};

// `random` random samples of T and one sane sample (which passes CheckMessage()).
template <class T>
TypeCorpus MakeTypeCorpus(int random) {
  TypeCorpus c;
  c.type_name = T::getTypeName();
  std::vector<Bytes> encodings = RandomEncodings<T>(random);
  std::mt19937_64 rng(7);
  T sane;
  const bool have_sane = SaneSample(rng, &sane);
  if (have_sane) encodings.push_back(Encode(sane));
  // Only encodings whose fields were found (all of them, unless the layout is broken).
  for (Bytes& wire : encodings) {
    WireFields f;
    if (!WireFields::Find<T>(wire, &f)) continue;
    c.valid.push_back(std::move(wire));
    c.fields.push_back(std::move(f));
  }
  c.last_is_sane = have_sane && c.valid.size() == encodings.size();
  return c;
}

// TypeCorpus of every message type (SARMAP_FOR_EACH_MESSAGE_TYPE), by type name.
inline std::map<std::string, TypeCorpus> MessageTypeCorpora(int random) {
  std::map<std::string, TypeCorpus> out;
#define SARMAP_CORPUS(T) out[#T] = MakeTypeCorpus<sarmap::T>(random);
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_CORPUS)
#undef SARMAP_CORPUS
  return out;
}

// Draws hostile datagrams for message types by name: a random mutation of a valid sample
// (the sane one half of the time), or (1 in 12) a valid sample of another type.
class HostileDatagrams {
 public:
  HostileDatagrams(uint64_t seed, int64_t now_utime, int random_samples = 4)
      : rng_(seed), now_utime_(now_utime), corpora_(MessageTypeCorpora(random_samples)) {}

  bool Knows(const std::string& type_name) const { return corpora_.count(type_name) > 0; }

  // Only these kinds from now on: MutationName()s and "wrong-type". False (and no change)
  // when none is known.
  bool SetKinds(const std::function<bool(const std::string&)>& wanted) {
    std::vector<Mutation> kinds;
    for (int k = 0; k < static_cast<int>(Mutation::kCount); ++k) {
      if (wanted(MutationName(static_cast<Mutation>(k)))) kinds.push_back(static_cast<Mutation>(k));
    }
    const bool wrong_type = wanted("wrong-type");
    if (kinds.empty() && !wrong_type) return false;
    kinds_ = std::move(kinds);
    wrong_type_ = wrong_type;
    return true;
  }
  const std::map<std::string, TypeCorpus>& corpora() const { return corpora_; }

  // *kind: the mutation's name ("wrong-type" for another type's message).
  Bytes Next(const std::string& type_name, std::string* kind, std::string* what) {
    const TypeCorpus& c = corpora_.at(type_name);
    if (c.valid.empty()) {  // never for a type lcm_registry.py generated
      *kind = "empty";
      *what = "no bytes";
      return {};
    }
    if (wrong_type_ && (kinds_.empty() || rng_() % 12 == 0)) {
      auto it = corpora_.begin();
      std::advance(it, static_cast<std::ptrdiff_t>(rng_() % corpora_.size()));
      if (it->first != type_name && !it->second.valid.empty()) {
        *kind = "wrong-type";
        *what = "a valid " + it->first;
        return it->second.valid[rng_() % it->second.valid.size()];
      }
    }
    Bytes out;
    for (int attempt = 0; attempt < 32 && !kinds_.empty(); ++attempt) {
      // Half of them from the sane sample: a hostile value in an otherwise acceptable message
      // gets past the receiver's checks into its handler.
      const size_t i =
          c.last_is_sane && rng_() % 2 == 0 ? c.valid.size() - 1 : rng_() % c.valid.size();
      const Mutation m = kinds_[rng_() % kinds_.size()];
      if (Mutate(m, c.valid[i], c.fields[i], now_utime_, rng_, &out, what)) {
        *kind = MutationName(m);
        return out;
      }
    }
    *kind = "valid";
    *what = "a valid " + type_name;
    return c.valid[0];
  }

 private:
  static std::vector<Mutation> AllKinds() {
    std::vector<Mutation> out;
    for (int k = 0; k < static_cast<int>(Mutation::kCount); ++k) {
      out.push_back(static_cast<Mutation>(k));
    }
    return out;
  }

  std::mt19937_64 rng_;
  int64_t now_utime_;
  std::vector<Mutation> kinds_ = AllKinds();
  bool wrong_type_ = true;
  std::map<std::string, TypeCorpus> corpora_;
};

}  // namespace testing
}  // namespace sarmap
