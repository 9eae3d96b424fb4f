#include "log-tools/lcm_json.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <vector>

namespace sarmap {
namespace logtools {
namespace {

using Json = nlohmann::ordered_json;

// Struct nesting deeper than this is refused (only a type that contains itself through a
// variable array can nest without bound, and each level would take a stack frame).
constexpr int kMaxDepth = 64;
// Elements of a type that can encode to zero bytes are not bounded by the bytes left.
constexpr uint64_t kMaxEmptyElements = 1 << 20;

bool IsInteger(const std::string& type) {
  return type == "int8_t" || type == "int16_t" || type == "int32_t" || type == "int64_t";
}

uint64_t BigEndian(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// The constants a member's comment points at: "CUE_*" -> "CUE_", bit set when the comment
// speaks of OR-ing them.
struct ConstantRef {
  std::string prefix;
  bool bits = false;
};

std::optional<ConstantRef> ConstantsNamedIn(const std::string& comment) {
  for (size_t star = comment.find('*'); star != std::string::npos;
       star = comment.find('*', star + 1)) {
    size_t begin = star;
    while (begin > 0 && (std::isupper(static_cast<unsigned char>(comment[begin - 1])) ||
                         std::isdigit(static_cast<unsigned char>(comment[begin - 1])) ||
                         comment[begin - 1] == '_')) {
      --begin;
    }
    if (star - begin >= 2 && comment[star - 1] == '_') {
      ConstantRef ref;
      ref.prefix = comment.substr(begin, star - begin);
      ref.bits =
          comment.find(" OR ") != std::string::npos || comment.find("bitwise") != std::string::npos;
      return ref;
    }
  }
  return std::nullopt;
}

std::optional<std::string> ConstantName(const LcmStruct& s, const ConstantRef& ref, int64_t value) {
  std::vector<std::pair<std::string, int64_t>> candidates;
  for (const auto& c : s.constants) {
    if (c.name.rfind(ref.prefix, 0) == 0 && IsInteger(c.type)) {
      candidates.emplace_back(c.name, std::strtoll(c.value.c_str(), nullptr, 0));
    }
  }
  for (const auto& [name, v] : candidates) {
    if (v == value) return name;
  }
  if (!ref.bits || value <= 0) return std::nullopt;
  std::string names;
  int64_t rest = value;
  for (const auto& [name, v] : candidates) {
    if (v > 0 && (value & v) == v) {
      names += (names.empty() ? "" : "|") + name;
      rest &= ~v;
    }
  }
  if (names.empty()) return std::nullopt;
  if (rest != 0) names += "|" + std::to_string(rest);
  return names;
}

class Decoder {
 public:
  Decoder(const LcmTypeSet& types, const LcmJsonOptions& options, const uint8_t* data, size_t size)
      : types_(types), options_(options), data_(data), size_(size) {}

  bool Struct(const LcmStruct& s, Json* out, const std::string& path, int depth) {
    if (depth > kMaxDepth) {
      return Fail(path, "nested deeper than " + std::to_string(kMaxDepth) + " structs");
    }
    *out = Json::object();
    std::map<std::string, int64_t> counts;  // scalar integer members, for variable arrays
    for (const auto& m : s.members) {
      const std::string member_path = path.empty() ? m.name : path + "." + m.name;
      Json value;
      std::optional<std::string> constant;
      if (m.dims.empty()) {
        int64_t integer = 0;
        if (!Scalar(m.type, &value, member_path, depth, &integer)) return false;
        if (IsInteger(m.type)) {
          counts[m.name] = integer;
          if (options_.constant_names) constant = NameConstant(s, m, integer);
        }
      } else if (!Array(m, 0, counts, &value, member_path, depth)) {
        return false;
      }
      (*out)[m.name] = std::move(value);
      if (constant) (*out)[m.name + "_name"] = *constant;
    }
    return true;
  }

  size_t left() const { return size_ - pos_; }
  const std::string& error() const { return error_; }

 private:
  bool Fail(const std::string& path, const std::string& what) {
    error_ = path + ": " + what + " (at byte " + std::to_string(pos_ + 8) + " of " +
             std::to_string(size_ + 8) + ")";
    return false;
  }

  // The constant that `value` of member `m` is, when the member's comment names constants.
  static std::optional<std::string> NameConstant(const LcmStruct& s, const LcmMember& m,
                                                 int64_t value) {
    if (m.comment.empty()) return std::nullopt;
    const auto ref = ConstantsNamedIn(m.comment);
    if (!ref) return std::nullopt;
    for (const auto& other : s.members) {
      if (other.name == m.name + "_name") return std::nullopt;  // a real member has the key
    }
    return ConstantName(s, *ref, value);
  }

  // A fixed-size primitive at the cursor (the caller checked the bytes are there).
  Json Primitive(const std::string& type, int64_t* integer) {
    const uint8_t* p = data_ + pos_;
    const int bytes = LcmPrimitiveBytes(type);
    pos_ += bytes;
    const uint64_t raw = BigEndian(p, bytes);
    if (type == "int8_t") return *integer = static_cast<int8_t>(raw);
    if (type == "int16_t") return *integer = static_cast<int16_t>(raw);
    if (type == "int32_t") return *integer = static_cast<int32_t>(raw);
    if (type == "int64_t") return *integer = static_cast<int64_t>(raw);
    if (type == "byte") return *integer = static_cast<int64_t>(raw);
    if (type == "boolean") return raw != 0;
    if (type == "float") {
      const uint32_t bits = static_cast<uint32_t>(raw);
      float f;
      std::memcpy(&f, &bits, sizeof(f));
      return JsonNumber(f);
    }
    double d;
    std::memcpy(&d, &raw, sizeof(d));
    return JsonNumber(d);
  }

  bool Scalar(const std::string& type, Json* out, const std::string& path, int depth,
              int64_t* integer) {
    if (type == "string") {
      if (left() < 4)
        return Fail(path, "string length needs 4 bytes, " + std::to_string(left()) + " left");
      const int32_t length = static_cast<int32_t>(BigEndian(data_ + pos_, 4));
      pos_ += 4;
      // The length counts the terminating NUL, so it is at least 1.
      if (length <= 0)
        return Fail(path, "string length " + std::to_string(length) + " is not positive");
      if (static_cast<uint64_t>(length) > left()) {
        return Fail(path, "string length " + std::to_string(length) + " > " +
                              std::to_string(left()) + " bytes left");
      }
      *out = std::string(reinterpret_cast<const char*>(data_ + pos_), length - 1);
      pos_ += length;
      return true;
    }
    if (IsLcmPrimitive(type)) {
      const int bytes = LcmPrimitiveBytes(type);
      if (left() < static_cast<size_t>(bytes)) {
        return Fail(path, type + " needs " + std::to_string(bytes) + " bytes, " +
                              std::to_string(left()) + " left");
      }
      *out = Primitive(type, integer);
      return true;
    }
    return Struct(*types_.Find(type), out, path, depth + 1);
  }

  // Fewest bytes of one element of dimension `dim` of `m`.
  uint64_t MinElementBytes(const LcmMember& m, size_t dim) const {
    uint64_t elem = m.type == "string"       ? 5
                    : IsLcmPrimitive(m.type) ? LcmPrimitiveBytes(m.type)
                                             : types_.MinWireSize(m.type);
    for (size_t d = dim + 1; d < m.dims.size(); ++d) {
      if (m.dims[d].variable) return 0;
      elem *= std::strtoull(m.dims[d].size.c_str(), nullptr, 0);
    }
    return elem;
  }

  bool Array(const LcmMember& m, size_t dim, const std::map<std::string, int64_t>& counts,
             Json* out, const std::string& path, int depth) {
    const LcmDimension& d = m.dims[dim];
    int64_t count = 0;
    if (d.variable) {
      count = counts.at(d.size);  // the schema checked it is an earlier integer member
      if (count < 0) {
        return Fail(path, "count " + std::to_string(count) + " (" + d.size + ") is negative");
      }
    } else {
      count = std::strtoll(d.size.c_str(), nullptr, 0);
    }
    const uint64_t elem_bytes = MinElementBytes(m, dim);
    const uint64_t n = static_cast<uint64_t>(count);
    if (elem_bytes > 0 ? n > left() / elem_bytes : n > kMaxEmptyElements) {
      return Fail(path, "count " + std::to_string(count) +
                            (d.variable ? " (" + d.size + ")" : std::string()) + " needs " +
                            (elem_bytes > 0 ? "at least " + std::to_string(elem_bytes) +
                                                  " bytes each, " + std::to_string(left()) + " left"
                                            : "too many empty elements"));
    }
    const bool summarise = options_.max_array > 0 && count > options_.max_array;
    const int64_t keep = summarise ? std::min<int64_t>(count, options_.head) : count;
    Json items = Json::array();
    const bool last = dim + 1 == m.dims.size();
    const bool numbers =
        last && IsLcmPrimitive(m.type) && m.type != "string" && m.type != "boolean";
    if (numbers && summarise) return SummariseNumbers(m.type, count, keep, out);
    for (int64_t i = 0; i < count; ++i) {
      Json item;
      int64_t integer = 0;
      if (numbers) {
        item = Primitive(m.type, &integer);  // bytes checked for the whole array above
      } else {
        const std::string item_path = path + "[" + std::to_string(i) + "]";
        if (last ? !Scalar(m.type, &item, item_path, depth, &integer)
                 : !Array(m, dim + 1, counts, &item, item_path, depth)) {
          return false;
        }
      }
      if (i < keep) items.push_back(std::move(item));
    }
    if (!summarise) {
      *out = std::move(items);
      return true;
    }
    *out = Json::object();
    (*out)["length"] = count;
    (*out)["head"] = std::move(items);
    return true;
  }

  // {length, min, max, head} of `count` numbers at the cursor (the caller checked the bytes
  // are there), without a JSON value per element: images and audio are millions of them.
  bool SummariseNumbers(const std::string& type, int64_t count, int64_t keep, Json* out) {
    const int bytes = LcmPrimitiveBytes(type);
    const uint8_t* start = data_ + pos_;
    const bool is_float = type == "float", is_double = type == "double";
    const bool is_signed = !is_float && !is_double && type != "byte";
    double min = 0, max = 0;
    int64_t min_at = -1, max_at = -1;
    for (int64_t i = 0; i < count; ++i) {
      const uint64_t raw = BigEndian(start + i * bytes, bytes);
      double v;
      if (is_float) {
        const uint32_t bits = static_cast<uint32_t>(raw);
        float f;
        std::memcpy(&f, &bits, sizeof(f));
        v = f;
      } else if (is_double) {
        std::memcpy(&v, &raw, sizeof(v));
      } else if (is_signed) {
        // Sign-extend from `bytes` bytes.
        const int shift = 64 - 8 * bytes;
        v = static_cast<double>(static_cast<int64_t>(raw << shift) >> shift);
      } else {
        v = static_cast<double>(raw);
      }
      if (!std::isfinite(v)) continue;  // the range of the finite values
      if (min_at < 0 || v < min) {
        min = v;
        min_at = i;
      }
      if (max_at < 0 || v > max) {
        max = v;
        max_at = i;
      }
    }
    auto element = [&](int64_t i) {
      pos_ = (start - data_) + i * bytes;
      int64_t integer = 0;
      return Primitive(type, &integer);
    };
    *out = Json::object();
    (*out)["length"] = count;
    if (min_at >= 0) {
      (*out)["min"] = element(min_at);
      (*out)["max"] = element(max_at);
    }
    Json head = Json::array();
    for (int64_t i = 0; i < keep; ++i) head.push_back(element(i));
    (*out)["head"] = std::move(head);
    pos_ = (start - data_) + count * bytes;
    return true;
  }

  const LcmTypeSet& types_;
  const LcmJsonOptions& options_;
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  std::string error_;
};

}  // namespace

Json JsonNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return value;
}

Json JsonNumber(float value) {
  if (!std::isfinite(value)) return JsonNumber(static_cast<double>(value));
  // The shortest decimal that reads back as this float, held as the double nearest to it,
  // which the JSON writer prints with the same digits.
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text) - 1, value);
  *result.ptr = '\0';
  return std::strtod(text, nullptr);
}

LcmJsonResult DecodeLcmToJson(const LcmTypeSet& types, const uint8_t* data, size_t size,
                              const LcmJsonOptions& options) {
  LcmJsonResult result;
  if (size < 8) {
    result.error = "message of " + std::to_string(size) + " bytes has no 8-byte fingerprint";
    return result;
  }
  const uint64_t fingerprint = BigEndian(data, 8);
  const LcmStruct* type = types.FindByFingerprint(fingerprint);
  if (type == nullptr) {
    char hex[24];
    std::snprintf(hex, sizeof(hex), "0x%016llx", static_cast<unsigned long long>(fingerprint));
    result.error = std::string("unknown type (fingerprint ") + hex + ")";
    return result;
  }
  result.type = type->full_name();
  Decoder decoder(types, options, data + 8, size - 8);
  Json msg;
  if (!decoder.Struct(*type, &msg, "", 0)) {
    result.error = decoder.error();
    return result;
  }
  result.ok = true;
  result.msg = std::move(msg);
  result.trailing_bytes = decoder.left();
  return result;
}

std::string EchoLine(int64_t recv_utime, int64_t first_utime, const std::string& channel,
                     const LcmJsonResult& result, size_t size, int indent,
                     const std::string& refused) {
  Json line = Json::object();
  line["recv_utime"] = recv_utime;
  line["t_s"] = static_cast<double>(recv_utime - first_utime) / 1e6;
  line["channel"] = channel;
  if (!result.type.empty()) line["type"] = result.type;
  if (result.ok) {
    line["msg"] = result.msg;
    if (result.trailing_bytes > 0) {
      line["warning"] = std::to_string(result.trailing_bytes) + " bytes after the message";
    }
    if (!refused.empty()) line["refused"] = refused;
  } else {
    line["size"] = size;
    line["error"] = result.error;
  }
  return line.dump(indent, ' ', false, Json::error_handler_t::replace);
}

}  // namespace logtools
}  // namespace sarmap
