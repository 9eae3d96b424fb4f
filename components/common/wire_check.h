#pragma once
// CheckWire<T>(data, size, &why): is this an acceptable LCM encoding of T? It walks the
// encoding field by field (sarmap/message_wire_layout.h, generated from lcmtypes/*.lcm) and
// neither allocates nor reads outside [data, data + size).
//
// The decoder lcm-gen 1.3.1 generates trusts what it reads: a string length of 0 or below
// wraps to a 2 GB copy (SIGSEGV), and an array count is resized to before the bytes behind it
// are checked (a 36-byte message can ask for gigabytes). So every decode in sarmap runs this
// first (common/decode.h). An encoding is accepted when:
//   - it starts with T's 8-byte fingerprint and ends exactly where T ends;
//   - every string length (int32, trailing NUL included) is in 1..bytes left, the string
//     ends with its NUL and holds no other (LCM's encoders never write one: a string that
//     does cannot be re-encoded, e.g. for an order's HMAC);
//   - every array count is >= 0, and count x the fewest bytes of one element fits in the
//     bytes left (each dimension on its own too, since the decoder sizes outer vectors
//     before it reads inner ones).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>

#include "sarmap/message_wire_layout.h"

namespace sarmap {
namespace common {

class WireWalker {
 public:
  WireWalker(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  size_t position() const { return pos_; }
  size_t left() const { return size_ - pos_; }
  // One line: the field path (e.g. "header.frame", "sources[3].id"), what is wrong, and
  // the byte offset.
  const std::string& why() const { return why_; }

  bool Skip(const char* name, uint64_t bytes) {
    if (bytes > left()) return Fail(name, -1, Needs(bytes));
    pos_ += static_cast<size_t>(bytes);
    return true;
  }

  bool Integer(const char* name, int bytes, int64_t* value) {
    if (static_cast<size_t>(bytes) > left()) return Fail(name, -1, Needs(bytes));
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | data_[pos_ + i];
    // Sign-extend from `bytes` bytes.
    const int shift = 64 - 8 * bytes;
    *value = static_cast<int64_t>(v << shift) >> shift;
    pos_ += static_cast<size_t>(bytes);
    return true;
  }

  bool String(const char* name, int64_t index) {
    const size_t start = pos_;
    int64_t length = 0;
    if (!Integer(name, 4, &length)) return false;
    const size_t after_length = left();
    if (length < 1 || static_cast<uint64_t>(length) > after_length) {
      pos_ = start;  // the offset in the reason points at the length
      return Fail(name, index,
                  "string length " + std::to_string(length) + " (must be 1.." +
                      std::to_string(after_length) + ", the bytes left, NUL included)");
    }
    const uint8_t* bytes = data_ + pos_;
    const size_t n = static_cast<size_t>(length);
    if (bytes[n - 1] != 0) return Fail(name, index, "string does not end with NUL");
    if (std::memchr(bytes, 0, n - 1) != nullptr) {
      return Fail(name, index, "string holds a NUL byte before its end");
    }
    pos_ += n;
    return true;
  }

  template <class S>
  bool Struct(const char* name, int64_t index, const S* tag) {
    if (WalkWire(*this, tag)) return true;
    why_ = Path(name, index) + "." + why_;
    return false;
  }

  // dims: the array's dimensions, outermost first; min_elem: fewest bytes of one element.
  bool Count(const char* name, std::initializer_list<int64_t> dims, size_t min_elem,
             uint64_t* count) {
    uint64_t total = 1;
    for (int64_t d : dims) {
      if (d < 0) return Fail(name, -1, "negative array count " + std::to_string(d));
      // Each element (and each outer row) costs the decoder memory before it reads a byte.
      if (static_cast<uint64_t>(d) > left()) {
        return Fail(name, -1,
                    "array count " + std::to_string(d) + " exceeds the " + std::to_string(left()) +
                        " bytes left");
      }
      // Clamped after each factor so that no number of dimensions overflows: both factors
      // are below 2^31 here.
      total *= static_cast<uint64_t>(d);
      if (total > left()) total = left() + 1;
    }
    const uint64_t elem = min_elem > 0 ? min_elem : 1;
    if (total > left() / elem) {
      std::string shape;
      for (int64_t d : dims) shape += (shape.empty() ? "" : " x ") + std::to_string(d);
      return Fail(name, -1,
                  "array of " + shape + " elements of at least " + std::to_string(elem) +
                      " bytes does not fit in the " + std::to_string(left()) + " bytes left");
    }
    *count = total;
    return true;
  }

 private:
  static std::string Needs(uint64_t bytes) { return "needs " + std::to_string(bytes) + " bytes"; }
  static std::string Path(const char* name, int64_t index) {
    return index < 0 ? std::string(name) : std::string(name) + "[" + std::to_string(index) + "]";
  }
  bool Fail(const char* name, int64_t index, const std::string& what) {
    why_ = Path(name, index) + ": " + what + " at byte " + std::to_string(pos_) + " of " +
           std::to_string(size_);
    return false;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  std::string why_;
};

// True when `data` is an acceptable encoding of T (fingerprint first); else false with a
// one-line reason in *why (optional).
template <class T>
bool CheckWire(const void* data, size_t size, std::string* why) {
  auto fail = [why](std::string text) {
    if (why) *why = T::getTypeName() + std::string(": ") + std::move(text);
    return false;
  };
  // The generated decoder takes an int length.
  if (size > 0x7fffffff) return fail(std::to_string(size) + " bytes is too large");
  WireWalker w(static_cast<const uint8_t*>(data), size);
  int64_t fingerprint = 0;
  if (!w.Integer("fingerprint", 8, &fingerprint)) {
    return fail("truncated (" + std::to_string(size) + " bytes, no fingerprint)");
  }
  if (fingerprint != T::getHash()) return fail("wrong fingerprint (another type)");
  if (!WalkWire(w, static_cast<const T*>(nullptr))) return fail(w.why());
  if (w.left() != 0) return fail(std::to_string(w.left()) + " trailing bytes");
  return true;
}

}  // namespace common
}  // namespace sarmap
