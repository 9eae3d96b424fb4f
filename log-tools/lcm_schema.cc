#include "log-tools/lcm_schema.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace sarmap {
namespace logtools {
namespace {

const char* const kPrimitives[] = {"int8_t", "int16_t", "int32_t", "int64_t", "byte",
                                   "float",  "double",  "string",  "boolean"};
const char* const kDimensionTypes[] = {"int8_t", "int16_t", "int32_t", "int64_t"};
const char* const kConstTypes[] = {"int8_t", "int16_t", "int32_t", "int64_t", "float", "double"};

template <size_t N>
bool In(const std::string& s, const char* const (&list)[N]) {
  return std::find_if(std::begin(list), std::end(list), [&](const char* x) { return s == x; }) !=
         std::end(list);
}

bool IsIdentifier(const std::string& s) {
  return !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_');
}

struct Token {
  std::string text;
  int line;
};

// Words (identifiers, dotted names, numbers with sign and exponent) and the punctuation
// { } [ ] ; , = ; comments are collected per line instead of becoming tokens.
bool Tokenize(const std::string& text, std::vector<Token>* tokens,
              std::map<int, std::string>* comments, int* bad_line) {
  int line = 1;
  size_t i = 0;
  auto word_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' ||
           c == '+';
  };
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      const size_t end = std::min(text.find('\n', i), text.size());
      std::string& comment = (*comments)[line];
      if (!comment.empty()) comment += ' ';
      comment += text.substr(i + 2, end - i - 2);
      i = end;
    } else if (text.compare(i, 2, "/*") == 0) {
      const size_t end = text.find("*/", i + 2);
      if (end == std::string::npos) {
        *bad_line = line;
        return false;
      }
      line += static_cast<int>(std::count(text.begin() + i, text.begin() + end, '\n'));
      i = end + 2;
    } else if (std::string("{}[];,=").find(c) != std::string::npos) {
      tokens->push_back({std::string(1, c), line});
      ++i;
    } else if (word_char(c)) {
      size_t j = i;
      while (j < text.size() && word_char(text[j])) ++j;
      tokens->push_back({text.substr(i, j - i), line});
      i = j;
    } else {
      *bad_line = line;
      return false;
    }
  }
  return true;
}

class Parser {
 public:
  Parser(const std::vector<Token>& tokens, const std::map<int, std::string>& comments,
         std::string file)
      : tokens_(tokens), comments_(comments), file_(std::move(file)) {}

  bool Parse(std::vector<LcmStruct>* out, std::string* error) {
    while (pos_ < tokens_.size()) {
      const Token& t = tokens_[pos_++];
      if (t.text == "package") {
        std::string name;
        if (!Word("package name", &name) || !Expect(";")) break;
        package_ = name;
      } else if (t.text == "struct") {
        LcmStruct s;
        if (!Struct(&s)) break;
        out->push_back(std::move(s));
      } else if (t.text == "enum") {
        Fail(t.line, "enum is not supported");
        break;
      } else {
        Fail(t.line, "expected 'package' or 'struct', found '" + t.text + "'");
        break;
      }
    }
    *error = error_;
    return error_.empty();
  }

 private:
  int Line() const {
    if (pos_ < tokens_.size()) return tokens_[pos_].line;
    return tokens_.empty() ? 1 : tokens_.back().line;
  }
  bool Fail(int line, const std::string& what) {
    if (error_.empty()) error_ = file_ + ":" + std::to_string(line) + ": " + what;
    return false;
  }
  bool Peek(const char* text) const { return pos_ < tokens_.size() && tokens_[pos_].text == text; }
  bool Expect(const char* text) {
    if (!Peek(text)) {
      return Fail(Line(), std::string("expected '") + text + "'" +
                              (pos_ < tokens_.size() ? ", found '" + tokens_[pos_].text + "'"
                                                     : " before the end of the file"));
    }
    ++pos_;
    return true;
  }
  bool Word(const char* what, std::string* out) {
    if (pos_ >= tokens_.size()) return Fail(Line(), std::string("expected ") + what);
    const Token& t = tokens_[pos_];
    if (t.text.size() == 1 && std::string("{}[];,=").find(t.text[0]) != std::string::npos) {
      return Fail(t.line, std::string("expected ") + what + ", found '" + t.text + "'");
    }
    *out = t.text;
    ++pos_;
    return true;
  }

  bool Struct(LcmStruct* s) {
    s->package = package_;
    s->file = file_;
    s->line = Line();
    if (!Word("struct name", &s->name)) return false;
    if (!IsIdentifier(s->name)) return Fail(s->line, "invalid struct name '" + s->name + "'");
    if (!Expect("{")) return false;
    while (!Peek("}")) {
      if (pos_ >= tokens_.size()) return Fail(Line(), "missing '}' of struct " + s->name);
      if (Peek("const")) {
        ++pos_;
        if (!Const(s)) return false;
      } else if (Peek("struct") || Peek("enum")) {
        return Fail(Line(), "nested type declarations are not supported");
      } else if (!Member(s)) {
        return false;
      }
    }
    ++pos_;
    s->base_hash = LcmBaseHash(*s);
    return true;
  }

  bool Taken(const LcmStruct& s, const std::string& name) const {
    for (const auto& m : s.members) {
      if (m.name == name) return true;
    }
    for (const auto& c : s.constants) {
      if (c.name == name) return true;
    }
    return false;
  }

  bool Const(LcmStruct* s) {
    const int line = Line();
    std::string type;
    if (!Word("constant type", &type)) return false;
    if (!In(type, kConstTypes)) return Fail(line, "invalid type for const: '" + type + "'");
    while (true) {
      LcmConstant c;
      c.type = type;
      const int name_line = Line();
      if (!Word("constant name", &c.name)) return false;
      if (!IsIdentifier(c.name)) return Fail(name_line, "invalid constant name '" + c.name + "'");
      if (Taken(*s, c.name)) return Fail(name_line, "duplicate member name '" + c.name + "'");
      if (!Expect("=") || !Word("constant value", &c.value)) return false;
      char* end = nullptr;
      if (type == "float" || type == "double") {
        std::strtod(c.value.c_str(), &end);
      } else {
        std::strtoll(c.value.c_str(), &end, 0);
      }
      if (end == c.value.c_str() || *end != '\0') {
        return Fail(name_line, "invalid value '" + c.value + "' for " + type + " " + c.name);
      }
      s->constants.push_back(std::move(c));
      if (Peek(",")) {
        ++pos_;
        continue;
      }
      return Expect(";");
    }
  }

  bool Member(LcmStruct* s) {
    const int line = Line();
    std::string type;
    if (!Word("type name", &type)) return false;
    if (!IsIdentifier(type)) return Fail(line, "invalid type name '" + type + "'");
    if (!IsLcmPrimitive(type) && type.find('.') == std::string::npos && !package_.empty()) {
      type = package_ + "." + type;
    }
    while (true) {
      LcmMember m;
      m.type = type;
      m.line = Line();
      if (!Word("member name", &m.name)) return false;
      if (!IsIdentifier(m.name) || m.name.find('.') != std::string::npos) {
        return Fail(m.line, "invalid member name '" + m.name + "'");
      }
      if (Taken(*s, m.name)) return Fail(m.line, "duplicate member name '" + m.name + "'");
      auto comment = comments_.find(m.line);
      if (comment != comments_.end()) m.comment = comment->second;
      while (Peek("[")) {
        ++pos_;
        LcmDimension d;
        const int dim_line = Line();
        if (!Word("array size", &d.size)) return false;
        if (std::isdigit(static_cast<unsigned char>(d.size[0]))) {
          char* end = nullptr;
          const long long n = std::strtoll(d.size.c_str(), &end, 0);
          if (*end != '\0' || n <= 0 || n > INT32_MAX) {
            return Fail(dim_line, "constant array size must be a number > 0: '" + d.size + "'");
          }
        } else {
          d.variable = true;
          auto it = std::find_if(s->members.begin(), s->members.end(),
                                 [&](const LcmMember& x) { return x.name == d.size; });
          if (it == s->members.end()) {
            return Fail(dim_line, "unknown array size '" + d.size +
                                      "' (must be a member declared before the array)");
          }
          if (!it->dims.empty() || !In(it->type, kDimensionTypes)) {
            return Fail(dim_line, "array size '" + d.size + "' must be a scalar integer member");
          }
        }
        if (!Expect("]")) return false;
        m.dims.push_back(std::move(d));
      }
      s->members.push_back(std::move(m));
      if (Peek(",")) {
        ++pos_;
        continue;
      }
      return Expect(";");
    }
  }

  const std::vector<Token>& tokens_;
  const std::map<int, std::string>& comments_;
  std::string file_;
  std::string package_;
  size_t pos_ = 0;
  std::string error_;
};

int64_t HashUpdate(int64_t v, char c) {
  // In unsigned arithmetic where lcm-gen's signed arithmetic wraps; v >> 55 stays arithmetic.
  const uint64_t shifted = (static_cast<uint64_t>(v) << 8) ^ static_cast<uint64_t>(v >> 55);
  return static_cast<int64_t>(shifted + static_cast<uint64_t>(static_cast<int64_t>(c)));
}

int64_t HashString(int64_t v, const std::string& s) {
  v = HashUpdate(v, static_cast<char>(s.size()));
  for (char c : s) v = HashUpdate(v, c);
  return v;
}

}  // namespace

bool IsLcmPrimitive(const std::string& type) { return In(type, kPrimitives); }

int LcmPrimitiveBytes(const std::string& type) {
  if (type == "int8_t" || type == "byte" || type == "boolean") return 1;
  if (type == "int16_t") return 2;
  if (type == "int32_t" || type == "float") return 4;
  if (type == "int64_t" || type == "double") return 8;
  return 0;
}

bool ParseLcm(const std::string& text, const std::string& file, std::vector<LcmStruct>* out,
              std::string* error) {
  std::vector<Token> tokens;
  std::map<int, std::string> comments;
  int bad_line = 0;
  if (!Tokenize(text, &tokens, &comments, &bad_line)) {
    *error = file + ":" + std::to_string(bad_line) + ": unexpected character or open comment";
    return false;
  }
  return Parser(tokens, comments, file).Parse(out, error);
}

int64_t LcmBaseHash(const LcmStruct& s) {
  int64_t v = 0x12345678;
  for (const auto& m : s.members) {
    v = HashString(v, m.name);
    if (IsLcmPrimitive(m.type)) v = HashString(v, m.type);
    v = HashUpdate(v, static_cast<char>(m.dims.size()));
    for (const auto& d : m.dims) {
      v = HashUpdate(v, d.variable ? 1 : 0);
      v = HashString(v, d.size);
    }
  }
  return v;
}

bool LcmTypeSet::AddText(const std::string& text, const std::string& file,
                         std::vector<std::string>* errors) {
  std::vector<LcmStruct> parsed;
  std::string error;
  if (!ParseLcm(text, file, &parsed, &error)) {
    errors->push_back(error);
    return false;
  }
  bool ok = true;
  for (auto& s : parsed) {
    const std::string name = s.full_name();
    auto it = structs_.find(name);
    if (it != structs_.end()) {
      errors->push_back(file + ":" + std::to_string(s.line) + ": " + name +
                        " already declared in " + it->second.file);
      ok = false;
      continue;
    }
    structs_.emplace(name, std::move(s));
  }
  return ok;
}

bool LcmTypeSet::AddDirectory(const std::string& dir, std::vector<std::string>* errors) {
  std::error_code ec;
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ".lcm") files.push_back(entry.path().string());
  }
  if (ec) {
    errors->push_back(dir + ": " + ec.message());
    return false;
  }
  if (files.empty()) {
    errors->push_back(dir + ": no .lcm files");
    return false;
  }
  std::sort(files.begin(), files.end());
  bool ok = true;
  for (const auto& f : files) {
    std::ifstream in(f);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) {
      errors->push_back(f + ": cannot read");
      ok = false;
      continue;
    }
    ok = AddText(text.str(), f, errors) && ok;
  }
  return ok;
}

bool LcmTypeSet::Resolve(std::vector<std::string>* errors) {
  bool ok = true;
  for (const auto& [name, s] : structs_) {
    for (const auto& m : s.members) {
      if (!IsLcmPrimitive(m.type) && !structs_.count(m.type)) {
        errors->push_back(s.file + ":" + std::to_string(m.line) + ": unknown type " + m.type +
                          " of " + name + "." + m.name);
        ok = false;
      }
    }
  }
  if (!ok) return false;
  by_fingerprint_.clear();
  min_wire_size_.clear();
  ambiguities_.clear();
  for (auto& [name, s] : structs_) {
    std::vector<std::string> stack;
    s.fingerprint = Fingerprint(name, &stack);
    auto [it, inserted] = by_fingerprint_.emplace(s.fingerprint, name);
    if (!inserted) {
      // LCM cannot tell such types apart on the wire either: the first (by name) decodes.
      ambiguities_.push_back(s.file + ":" + std::to_string(s.line) + ": " + name +
                             " has the same fingerprint as " + it->second + ", which is used");
    }
  }
  for (const auto& entry : structs_) {
    std::vector<std::string> stack;
    ComputeMinWireSize(entry.first, &stack);
  }
  return ok;
}

uint64_t LcmTypeSet::Fingerprint(const std::string& full_name,
                                 std::vector<std::string>* stack) const {
  if (std::find(stack->begin(), stack->end(), full_name) != stack->end()) return 0;
  const LcmStruct& s = structs_.at(full_name);
  stack->push_back(full_name);
  uint64_t hash = static_cast<uint64_t>(s.base_hash);
  for (const auto& m : s.members) {
    if (!IsLcmPrimitive(m.type)) hash += Fingerprint(m.type, stack);
  }
  stack->pop_back();
  return (hash << 1) + ((hash >> 63) & 1);
}

uint64_t LcmTypeSet::ComputeMinWireSize(const std::string& full_name,
                                        std::vector<std::string>* stack) {
  auto done = min_wire_size_.find(full_name);
  if (done != min_wire_size_.end()) return done->second;
  // A type that contains itself (only possible through a variable array) counts as empty.
  if (std::find(stack->begin(), stack->end(), full_name) != stack->end()) return 0;
  stack->push_back(full_name);
  uint64_t total = 0;
  for (const auto& m : structs_.at(full_name).members) {
    uint64_t count = 1;
    for (const auto& d : m.dims) {
      count = d.variable ? 0 : count * std::strtoull(d.size.c_str(), nullptr, 0);
    }
    if (count == 0) continue;
    const uint64_t elem = m.type == "string"       ? 5  // int32 length and the NUL
                          : IsLcmPrimitive(m.type) ? LcmPrimitiveBytes(m.type)
                                                   : ComputeMinWireSize(m.type, stack);
    total += count * elem;
  }
  stack->pop_back();
  min_wire_size_[full_name] = total;
  return total;
}

const LcmStruct* LcmTypeSet::Find(const std::string& full_name) const {
  auto it = structs_.find(full_name);
  return it == structs_.end() ? nullptr : &it->second;
}

const LcmStruct* LcmTypeSet::FindByFingerprint(uint64_t fingerprint) const {
  auto it = by_fingerprint_.find(fingerprint);
  return it == by_fingerprint_.end() ? nullptr : Find(it->second);
}

uint64_t LcmTypeSet::MinWireSize(const std::string& full_name) const {
  auto it = min_wire_size_.find(full_name);
  return it == min_wire_size_.end() ? 0 : it->second;
}

}  // namespace logtools
}  // namespace sarmap
