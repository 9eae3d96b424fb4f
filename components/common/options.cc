#include "common/options.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace sarmap {
namespace {

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::string OptionRule::Describe() const {
  switch (kind_) {
    case Kind::kNone:
      return "";
    case Kind::kPositive:
      return "> 0";
    case Kind::kNonNegative:
      return ">= 0";
    case Kind::kAtLeast:
      return ">= " + Number(lo_);
    case Kind::kInRange:
      return "in [" + Number(lo_) + ", " + Number(hi_) + "]";
    case Kind::kOneOf: {
      std::string list;
      for (const auto& c : choices_) list += (list.empty() ? "" : ", ") + c;
      return "one of {" + list + "}";
    }
  }
  return "";
}

namespace common {

void Validator::Obeys(const std::string& key, double value, const OptionRule& rule) {
  using Kind = OptionRule::Kind;
  bool ok = std::isfinite(value);
  switch (rule.kind()) {
    case Kind::kNone:
      return;
    case Kind::kPositive:
      ok = ok && value > 0;
      break;
    case Kind::kNonNegative:
      ok = ok && value >= 0;
      break;
    case Kind::kAtLeast:
      ok = ok && value >= rule.lo();
      break;
    case Kind::kInRange:
      ok = ok && value >= rule.lo() && value <= rule.hi();
      break;
    case Kind::kOneOf:
      return That(false, key, "a number cannot be " + rule.Describe());
  }
  That(ok, key, "must be " + rule.Describe() + ", is " + Number(value));
}

void Validator::Obeys(const std::string& key, const std::string& value, const OptionRule& rule) {
  if (rule.kind() == OptionRule::Kind::kNone) return;
  if (rule.kind() != OptionRule::Kind::kOneOf) {
    return That(false, key, "a text cannot be " + rule.Describe());
  }
  const auto& choices = rule.choices();
  That(std::find(choices.begin(), choices.end(), value) != choices.end(), key,
       "must be " + rule.Describe() + ", is '" + value + "'");
}

namespace options_internal {
namespace {

std::string Location(const YAML::Mark& mark, const std::string& source) {
  if (mark.is_null()) return source;
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

template <class T>
T Scalar(const YAML::Node& node, const std::string& key, const std::string& where) {
  if (!node.IsScalar()) {
    throw OptionsError(where + ": key '" + key + "': expected " + TypeName(static_cast<T*>(nullptr)) +
                       ", got a " + (node.IsSequence() ? "list" : node.IsMap() ? "mapping" : "null"));
  }
  try {
    T value = node.as<T>();
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) throw YAML::Exception(YAML::Mark::null_mark(), "not finite");
    }
    return value;
  } catch (const YAML::Exception&) {
    throw OptionsError(where + ": key '" + key + "': expected " +
                       TypeName(static_cast<T*>(nullptr)) + ", got '" + node.Scalar() + "'");
  }
}

template <class T>
void ReadList(const YAML::Node& node, const std::string& key, const std::string& where,
              std::vector<T>* out) {
  if (!node.IsSequence()) {
    throw OptionsError(where + ": key '" + key + "': expected a list");
  }
  std::vector<T> values;
  for (size_t i = 0; i < node.size(); ++i) {
    values.push_back(Scalar<T>(node[i], key + "[" + std::to_string(i) + "]", where));
  }
  *out = std::move(values);
}

template <class T>
void ReadNode(const YAML::Node& node, const std::string& key, const std::string& where, T* out) {
  if constexpr (std::is_same_v<T, std::vector<double>> || std::is_same_v<T, std::vector<int>> ||
                std::is_same_v<T, std::vector<std::string>>) {
    ReadList(node, key, where, out);
  } else {
    *out = Scalar<T>(node, key, where);
  }
}

}  // namespace

void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, bool* out) {
  *out = Scalar<bool>(map.Get(key), full_key, map.Where(key));
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, int* out) {
  *out = Scalar<int>(map.Get(key), full_key, map.Where(key));
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, int64_t* out) {
  *out = Scalar<int64_t>(map.Get(key), full_key, map.Where(key));
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, double* out) {
  *out = Scalar<double>(map.Get(key), full_key, map.Where(key));
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::string* out) {
  *out = Scalar<std::string>(map.Get(key), full_key, map.Where(key));
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<double>* out) {
  ReadList(map.Get(key), full_key, map.Where(key), out);
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<int>* out) {
  ReadList(map.Get(key), full_key, map.Where(key), out);
}
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<std::string>* out) {
  ReadList(map.Get(key), full_key, map.Where(key), out);
}

template <class T>
void ParseOverride(const std::string& text, const std::string& key, T* out) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw OptionsError("--set " + key + "=" + text + ": not valid YAML: " + e.msg);
  }
  if constexpr (std::is_same_v<T, std::string>) {
    *out = text;  // a string override is taken literally
  } else {
    ReadNode(node, key, "--set " + key, out);
  }
}
template void ParseOverride(const std::string&, const std::string&, bool*);
template void ParseOverride(const std::string&, const std::string&, int*);
template void ParseOverride(const std::string&, const std::string&, int64_t*);
template void ParseOverride(const std::string&, const std::string&, double*);
template void ParseOverride(const std::string&, const std::string&, std::string*);
template void ParseOverride(const std::string&, const std::string&, std::vector<double>*);
template void ParseOverride(const std::string&, const std::string&, std::vector<int>*);
template void ParseOverride(const std::string&, const std::string&, std::vector<std::string>*);

namespace {

// The shortest decimal that reads back as exactly `value` (0.05, not 0.050000000000000003).
std::string ShortestDecimal(double value) {
  char text[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

}  // namespace

template <class T>
std::string Format(const T& value) {
  YAML::Emitter out;
  out << YAML::Flow << value;
  return out.c_str();
}
template <>
std::string Format(const double& value) {
  if (std::isfinite(value)) return ShortestDecimal(value);
  YAML::Emitter out;
  out << value;  // .inf, -.inf, .nan
  return out.c_str();
}
template <>
std::string Format(const std::vector<double>& values) {
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + Format(values[i]);
  return out + "]";
}
template std::string Format(const bool&);
template std::string Format(const int&);
template std::string Format(const int64_t&);
template std::string Format(const std::string&);
template std::string Format(const std::vector<int>&);
template std::string Format(const std::vector<std::string>&);

std::string MarkdownCell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') {
      out += "\\|";
    } else if (c == '\n') {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out;
}

std::string TypeName(const bool*) { return "a boolean"; }
std::string TypeName(const int*) { return "an integer"; }
std::string TypeName(const int64_t*) { return "an integer"; }
std::string TypeName(const double*) { return "a number"; }
std::string TypeName(const std::string*) { return "a string"; }
std::string TypeName(const std::vector<double>*) { return "a list of numbers"; }
std::string TypeName(const std::vector<int>*) { return "a list of integers"; }
std::string TypeName(const std::vector<std::string>*) { return "a list of strings"; }

YamlMap::YamlMap() : node_(std::make_unique<YAML::Node>(YAML::NodeType::Map)) {}
YamlMap::YamlMap(const YamlMap& other)
    : node_(std::make_unique<YAML::Node>(*other.node_)), source_(other.source_) {}
YamlMap& YamlMap::operator=(const YamlMap& other) {
  node_ = std::make_unique<YAML::Node>(*other.node_);
  source_ = other.source_;
  return *this;
}
YamlMap::~YamlMap() = default;

namespace {

// base with every key of `over` laid on top: mappings merge key by key, anything else
// (numbers, strings, lists) is replaced whole.
YAML::Node Merged(const YAML::Node& base, const YAML::Node& over) {
  if (!base.IsMap() || !over.IsMap()) return YAML::Clone(over);
  YAML::Node out = YAML::Clone(base);
  for (auto it = over.begin(); it != over.end(); ++it) {
    const std::string key = it->first.Scalar();
    const YAML::Node existing = static_cast<const YAML::Node&>(out)[key];
    out[key] = existing.IsDefined() ? Merged(existing, it->second) : YAML::Clone(it->second);
  }
  return out;
}

// A file may start with `extends: other.yaml` (relative to the file): the base is read first and
// this file's keys are laid over it, so a robot's configuration names only what differs.
constexpr const char* kExtendsKey = "extends";
constexpr int kMaxExtendsDepth = 8;

YamlMap FromFileExtending(const std::string& path, int depth) {
  std::ifstream in(path);
  if (!in) throw OptionsError(path + ": cannot open the configuration file");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  YamlMap map = YamlMap::FromString(text, path);
  if (!map.Has(kExtendsKey)) return map;
  const YAML::Node extends = map.Get(kExtendsKey);
  if (!extends.IsScalar() || extends.Scalar().empty()) {
    throw OptionsError(map.Where(kExtendsKey) + ": '" + kExtendsKey +
                       "' must name the configuration file this one builds on");
  }
  if (depth >= kMaxExtendsDepth) {
    throw OptionsError(map.Where(kExtendsKey) + ": '" + kExtendsKey +
                       "' nests deeper than " + std::to_string(kMaxExtendsDepth) +
                       " files (a cycle?)");
  }
  // A relative base is found beside the file that names it, wherever the program runs.
  std::string base_path = extends.Scalar();
  const auto slash = path.find_last_of('/');
  if (base_path[0] != '/' && slash != std::string::npos) {
    base_path = path.substr(0, slash + 1) + base_path;
  }
  const YamlMap base = FromFileExtending(base_path, depth + 1);
  return map.LaidOver(base, kExtendsKey);
}

}  // namespace

YamlMap YamlMap::FromFile(const std::string& path) { return FromFileExtending(path, 0); }

YamlMap YamlMap::LaidOver(const YamlMap& base, const std::string& drop_key) const {
  YAML::Node own = YAML::Clone(*node_);
  own.remove(drop_key);
  YamlMap merged;
  // Locations in errors keep the line numbers of whichever file a key came from; the name
  // given says both files.
  merged.source_ = source_ + " (extends " + base.source_ + ")";
  *merged.node_ = Merged(*base.node_, own);
  return merged;
}

YamlMap YamlMap::FromString(const std::string& text, const std::string& name) {
  YamlMap map;
  map.source_ = name;
  try {
    *map.node_ = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw OptionsError(Location(e.mark, name) + ": YAML syntax error: " + e.msg);
  }
  if (map.node_->IsNull()) {
    *map.node_ = YAML::Node(YAML::NodeType::Map);
  } else if (!map.node_->IsMap()) {
    throw OptionsError(name + ": the top level must be a mapping of keys to values");
  }
  return map;
}

bool YamlMap::Has(const std::string& key) const { return (*node_)[key].IsDefined(); }

YamlMap YamlMap::Child(const std::string& key, const std::string& full_key) const {
  const YAML::Node child = Get(key);
  YamlMap map;
  map.source_ = source_;
  if (child.IsNull()) return map;
  if (!child.IsMap()) {
    throw OptionsError(Location(child.Mark(), source_) + ": key '" + full_key +
                       "': expected a mapping of keys to values");
  }
  *map.node_ = child;
  return map;
}

YAML::Node YamlMap::Get(const std::string& key) const {
  for (auto it = node_->begin(); it != node_->end(); ++it) {
    if (it->first.Scalar() == key) return it->second;
  }
  throw OptionsError(source_ + ": no key '" + key + "'");
}

std::string YamlMap::Where(const std::string& key) const {
  for (auto it = node_->begin(); it != node_->end(); ++it) {
    if (it->first.Scalar() == key) return Location(it->first.Mark(), source_);
  }
  return source_;
}

std::vector<std::string> YamlMap::Keys() const {
  std::vector<std::string> keys;
  for (auto it = node_->begin(); it != node_->end(); ++it) keys.push_back(it->first.Scalar());
  return keys;
}

void Reader::CheckUnknown() const {
  std::vector<std::string> errors;
  for (const auto& key : map_.Keys()) {
    if (std::find(seen_.begin(), seen_.end(), key) == seen_.end()) {
      std::string known;
      for (const auto& s : seen_) known += (known.empty() ? "" : ", ") + s;
      errors.push_back(map_.Where(key) + ": unknown key '" + prefix_ + key + "' (known here: " +
                       known + ")");
    }
  }
  if (!errors.empty()) ThrowErrors("bad configuration", errors);
}

std::vector<std::pair<std::string, std::string>> SplitOverrides(
    const std::vector<std::string>& overrides) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& o : overrides) {
    const auto eq = o.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw OptionsError("--set '" + o + "': expected key=value (e.g. --set max_range_m=4.0)");
    }
    out.emplace_back(o.substr(0, eq), o.substr(eq + 1));
  }
  return out;
}

void ThrowErrors(const std::string& what, const std::vector<std::string>& errors) {
  std::string text = what + ":";
  for (const auto& e : errors) text += "\n  " + e;
  throw OptionsError(text);
}

}  // namespace options_internal
}  // namespace common
}  // namespace sarmap
