#pragma once
// Options structs: one per component, loaded from YAML with `--set key=value` overrides and
// validated once, with errors that name the bad key (and file:line:col when it came from a
// file).
//
// An options struct lists its fields in Visit(), each with its help and, where a value has
// limits, the rule it obeys; Validate() is only for what involves several fields:
//
//   struct ScanOptions {
//     double min_range_m = 0.3;
//     double max_range_m = 4.5;
//     GridOptions grid;                                  // nested options struct
//     template <class V> void Visit(V& v) {
//       v("min_range_m", min_range_m, "Ranges below this are no return", NonNegative());
//       v("max_range_m", max_range_m, "Ranges beyond this are no return", Positive());
//       v("grid", grid, "Grid settings");
//     }
//     void Validate(Validator& check) const {
//       check.That(max_range_m > min_range_m, "max_range_m", "must exceed min_range_m");
//     }
//   };
//   ScanOptions opt = LoadOptions<ScanOptions>("config/scan.yaml", {"max_range_m=3"});
//
// Supported field types: bool, int, int64_t, double, std::string, std::vector of
// double/int/std::string, and nested structs with Visit() (and optionally Validate()).
// Rules: Positive(), NonNegative(), AtLeast(x), InRange(lo, hi) for numbers (a list's every
// element), OneOf({...}) for strings. The loader checks them beside Validate(), and
// --print-config and the README tables show them.

#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace YAML {
class Node;
}

namespace sarmap {

// The limits of one option's value, declared beside its key in Visit().
class OptionRule {
 public:
  enum class Kind { kNone, kPositive, kNonNegative, kAtLeast, kInRange, kOneOf };
  OptionRule() = default;
  OptionRule(Kind kind, double lo, double hi, std::vector<std::string> choices = {})
      : kind_(kind), lo_(lo), hi_(hi), choices_(std::move(choices)) {}
  Kind kind() const { return kind_; }
  double lo() const { return lo_; }
  double hi() const { return hi_; }
  const std::vector<std::string>& choices() const { return choices_; }
  // "> 0", ">= 0", ">= 1", "in [0, 1]", "one of {a, b}"; "" without a rule.
  std::string Describe() const;

 private:
  Kind kind_ = Kind::kNone;
  double lo_ = 0, hi_ = 0;
  std::vector<std::string> choices_;
};
inline OptionRule Positive() { return {OptionRule::Kind::kPositive, 0, 0}; }
inline OptionRule NonNegative() { return {OptionRule::Kind::kNonNegative, 0, 0}; }
inline OptionRule AtLeast(double lo) { return {OptionRule::Kind::kAtLeast, lo, 0}; }
inline OptionRule InRange(double lo, double hi) { return {OptionRule::Kind::kInRange, lo, hi}; }
inline OptionRule OneOf(std::vector<std::string> choices) {
  return {OptionRule::Kind::kOneOf, 0, 0, std::move(choices)};
}

namespace common {

class OptionsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Collects validation failures; each names its key.
class Validator {
 public:
  explicit Validator(std::string prefix = "") : prefix_(std::move(prefix)) {}
  void That(bool ok, const std::string& key, const std::string& what) {
    if (!ok) errors_.push_back(prefix_ + key + ": " + what);
  }
  void Positive(const std::string& key, double value) { Obeys(key, value, sarmap::Positive()); }
  void NonNegative(const std::string& key, double value) {
    Obeys(key, value, sarmap::NonNegative());
  }
  void InRange(const std::string& key, double value, double lo, double hi) {
    Obeys(key, value, sarmap::InRange(lo, hi));
  }
  void OneOf(const std::string& key, const std::string& value,
             const std::vector<std::string>& allowed) {
    Obeys(key, value, sarmap::OneOf(allowed));
  }
  // The value against a rule: "must be <rule>, is <value>" when it breaks it (numbers and lists
  // of numbers; OneOf: strings).
  void Obeys(const std::string& key, double value, const OptionRule& rule);
  void Obeys(const std::string& key, const std::string& value, const OptionRule& rule);
  template <class T>
  void Obeys(const std::string& key, const std::vector<T>& values, const OptionRule& rule) {
    for (const auto& value : values) Obeys(key, value, rule);
  }
  const std::vector<std::string>& errors() const { return errors_; }
  std::vector<std::string>& mutable_errors() { return errors_; }
  const std::string& prefix() const { return prefix_; }

 private:
  std::string prefix_;
  std::vector<std::string> errors_;
};

namespace options_internal {

template <class T, class = void>
struct IsOptionsStruct : std::false_type {};
template <class T>
struct IsOptionsStruct<T, std::void_t<decltype(&T::template Visit<int>)>> : std::true_type {};

template <class T, class = void>
struct HasValidate : std::false_type {};
template <class T>
struct HasValidate<T, std::void_t<decltype(std::declval<const T&>().Validate(
                          std::declval<Validator&>()))>> : std::true_type {};

class YamlMap;
// Reads map[key] into *out (implemented in options.cc for the supported types).
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, bool* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, int* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, int64_t* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, double* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::string* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<double>* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<int>* out);
void ReadKey(const YamlMap& map, const std::string& key, const std::string& full_key, std::vector<std::string>* out);
template <class T>
void ParseOverride(const std::string& text, const std::string& key, T* out);
template <class T>
std::string Format(const T& value);
// Doubles as the shortest decimal that reads back exactly.
template <>
std::string Format(const double& value);
template <>
std::string Format(const std::vector<double>& values);
// `text` safe inside a Markdown table cell (| escaped, newlines folded).
std::string MarkdownCell(const std::string& text);
std::string TypeName(const bool*);
std::string TypeName(const int*);
std::string TypeName(const int64_t*);
std::string TypeName(const double*);
std::string TypeName(const std::string*);
std::string TypeName(const std::vector<double>*);
std::string TypeName(const std::vector<int>*);
std::string TypeName(const std::vector<std::string>*);

// A YAML mapping with the location it came from; wraps yaml-cpp so this header stays light.
class YamlMap {
 public:
  YamlMap();  // empty mapping
  YamlMap(const YamlMap&);
  YamlMap& operator=(const YamlMap&);
  ~YamlMap();
  // A file may start with `extends: other.yaml` (relative to the file): that file is read first
  // and this one's keys are laid over it, so a robot's configuration names only what differs.
  static YamlMap FromFile(const std::string& path);
  // *this laid over base (mappings merge key by key, other values replace), without drop_key.
  YamlMap LaidOver(const YamlMap& base, const std::string& drop_key) const;
  static YamlMap FromString(const std::string& text, const std::string& name);
  bool Has(const std::string& key) const;
  YamlMap Child(const std::string& key, const std::string& full_key) const;
  YAML::Node Get(const std::string& key) const;
  std::string Where(const std::string& key) const;  // "file:line:col"
  std::vector<std::string> Keys() const;
  const std::string& source() const { return source_; }

 private:
  std::unique_ptr<YAML::Node> node_;
  std::string source_;
};

class Reader {
 public:
  Reader(YamlMap map, std::vector<std::pair<std::string, std::string>>* overrides,
         std::string prefix)
      : map_(std::move(map)), overrides_(overrides), prefix_(std::move(prefix)) {}

  template <class T>
  void operator()(const char* key, T& value, const char* /*help*/, const OptionRule& = {}) {
    seen_.emplace_back(key);
    const std::string full = prefix_ + key;
    if constexpr (IsOptionsStruct<T>::value) {
      Reader child(map_.Has(key) ? map_.Child(key, full) : YamlMap(), overrides_, full + ".");
      value.Visit(child);
      child.CheckUnknown();
    } else {
      if (map_.Has(key)) ReadKey(map_, key, full, &value);
      for (auto it = overrides_->begin(); it != overrides_->end();) {
        if (it->first == full) {
          ParseOverride(it->second, full, &value);
          it = overrides_->erase(it);
        } else {
          ++it;
        }
      }
    }
  }
  void CheckUnknown() const;

 private:
  YamlMap map_;
  std::vector<std::pair<std::string, std::string>>* overrides_;
  std::string prefix_;
  std::vector<std::string> seen_;
};

class Writer {
 public:
  Writer(std::ostream* out, int indent, bool with_help)
      : out_(out), indent_(indent), with_help_(with_help) {}
  template <class T>
  void operator()(const char* key, const T& value, const char* help, const OptionRule& rule = {}) {
    const std::string pad(indent_, ' ');
    if (with_help_ && help && *help) *out_ << pad << "# " << help << "\n";
    if constexpr (IsOptionsStruct<T>::value) {
      *out_ << pad << key << ":\n";
      Writer child(out_, indent_ + 2, with_help_);
      const_cast<T&>(value).Visit(child);
    } else {
      *out_ << pad << key << ": " << Format(value);
      if (with_help_) {
        *out_ << "  # " << TypeName(&value);
        if (rule.kind() != OptionRule::Kind::kNone) *out_ << ", " << rule.Describe();
      }
      *out_ << "\n";
    }
  }

 private:
  std::ostream* out_;
  int indent_;
  bool with_help_;
};

// One Markdown table row per leaf key ("a.b.c"): its value, its rule and its help.
class MarkdownWriter {
 public:
  MarkdownWriter(std::ostream* out, std::string prefix) : out_(out), prefix_(std::move(prefix)) {}
  template <class T>
  void operator()(const char* key, const T& value, const char* help, const OptionRule& rule = {}) {
    const std::string full = prefix_ + key;
    if constexpr (IsOptionsStruct<T>::value) {
      MarkdownWriter child(out_, full + ".");
      const_cast<T&>(value).Visit(child);
    } else {
      *out_ << "| `" << full << "` | `" << MarkdownCell(Format(value)) << "` | "
            << MarkdownCell(rule.Describe()) << " | " << MarkdownCell(help ? help : "") << " |\n";
    }
  }

 private:
  std::ostream* out_;
  std::string prefix_;
};

// Each leaf against its rule; each nested struct's Validate() and leaves, under its prefix.
struct ValidateVisitor {
  Validator* check;
  template <class T>
  void operator()(const char* key, const T& value, const char*, const OptionRule& rule = {}) {
    if constexpr (IsOptionsStruct<T>::value) {
      Validator child(check->prefix() + key + ".");
      if constexpr (HasValidate<T>::value) value.Validate(child);
      ValidateVisitor nested{&child};
      const_cast<T&>(value).Visit(nested);
      for (auto& e : child.errors()) check->mutable_errors().push_back(e);
    } else if (rule.kind() != OptionRule::Kind::kNone) {
      if constexpr (std::is_same_v<T, bool>) {
        check->That(false, key, "a yes/no option has no rule");
      } else {
        check->Obeys(key, value, rule);
      }
    }
  }
};

std::vector<std::pair<std::string, std::string>> SplitOverrides(
    const std::vector<std::string>& overrides);
[[noreturn]] void ThrowErrors(const std::string& what, const std::vector<std::string>& errors);

}  // namespace options_internal

// Checks `options` (every key against its rule, Validate(), and every nested options struct
// the same way) into `check`, which collects an error per bad key.
template <class Options>
void CheckOptions(const Options& options, Validator* check) {
  if constexpr (options_internal::HasValidate<Options>::value) options.Validate(*check);
  options_internal::ValidateVisitor nested{check};
  const_cast<Options&>(options).Visit(nested);
}

// CheckOptions; throws OptionsError naming every bad key.
template <class Options>
void ValidateOptions(const Options& options) {
  Validator check;
  CheckOptions(options, &check);
  if (!check.errors().empty()) options_internal::ThrowErrors("invalid options", check.errors());
}

// Reads options: defaults from the struct, then `yaml_path` (if not empty; `section` selects
// a top-level key of the file, "" for the whole file), then `overrides` ("a.b=value").
// Unknown keys and type errors throw OptionsError; values are not validated (LoadOptions is).
template <class Options>
Options ReadOptions(const std::string& yaml_path, const std::vector<std::string>& overrides,
                    const std::string& section = "") {
  using namespace options_internal;
  Options options;
  YamlMap map = yaml_path.empty() ? YamlMap() : YamlMap::FromFile(yaml_path);
  if (!section.empty()) {
    if (!map.Has(section)) {
      throw OptionsError(yaml_path + ": no top-level key '" + section + "'");
    }
    map = map.Child(section, section);
  }
  auto pending = SplitOverrides(overrides);
  Reader reader(map, &pending, "");
  options.Visit(reader);
  reader.CheckUnknown();
  if (!pending.empty()) {
    std::vector<std::string> errors;
    for (auto& p : pending) errors.push_back("--set " + p.first + ": unknown key");
    ThrowErrors("bad overrides", errors);
  }
  return options;
}

// ReadOptions, then validation: unknown keys, type errors and invalid values throw
// OptionsError naming every bad key.
template <class Options>
Options LoadOptions(const std::string& yaml_path, const std::vector<std::string>& overrides,
                    const std::string& section = "") {
  Options options = ReadOptions<Options>(yaml_path, overrides, section);
  ValidateOptions(options);
  return options;
}

// Options as YAML, e.g. for --print-config; with_help adds each field's help and type.
template <class Options>
std::string OptionsToYaml(const Options& options, bool with_help) {
  std::ostringstream out;
  options_internal::Writer writer(&out, 0, with_help);
  const_cast<Options&>(options).Visit(writer);
  return out.str();
}

// Options as a Markdown table (key | value | valid | meaning), for the configuration section of a
// component's README.
template <class Options>
std::string OptionsToMarkdown(const Options& options) {
  std::ostringstream out;
  out << "| key | value | valid | meaning |\n|---|---|---|---|\n";
  options_internal::MarkdownWriter writer(&out, "");
  const_cast<Options&>(options).Visit(writer);
  return out.str();
}

}  // namespace common
}  // namespace sarmap
