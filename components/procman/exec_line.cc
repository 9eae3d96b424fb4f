#include "procman/exec_line.h"

#include <unistd.h>

#include <cctype>

namespace sarmap {
namespace procman {
namespace {

bool IsNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

}  // namespace

ExecPlan PlanExec(const std::string& exec, const EnvLookup& lookup) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  bool literal = false;  // the word has quoted or literal parts (else an empty one vanishes)
  size_t i = 0;
  auto fail = [&](const std::string& why) {
    throw std::invalid_argument("exec \"" + exec + "\": " + why);
  };
  // Expands $NAME / ${NAME} at exec[i] == '$'; advances i past it.
  auto expand = [&]() {
    ++i;
    std::string name, fallback;
    bool has_fallback = false;
    if (i < exec.size() && exec[i] == '{') {
      const size_t close = exec.find('}', i);
      if (close == std::string::npos) fail("unterminated ${");
      name = exec.substr(i + 1, close - i - 1);
      const size_t dash = name.find(":-");
      if (dash != std::string::npos) {
        fallback = name.substr(dash + 2);
        has_fallback = true;
        name = name.substr(0, dash);
      }
      if (name.empty() || !IsNameStart(name[0])) fail("bad variable name '${" + name + "}'");
      for (char c : name) {
        if (!IsNameChar(c)) fail("bad variable name '${" + name + "}'");
      }
      i = close + 1;
    } else if (i < exec.size() && IsNameStart(exec[i])) {
      while (i < exec.size() && IsNameChar(exec[i])) name += exec[i++];
    } else if (i < exec.size() && exec[i] == '(') {
      fail("command substitution $( ) needs use_shell = true");
    } else {
      word += '$';  // a lone '$' is literal
      return;
    }
    const char* value = lookup(name);
    if (value && *value) {
      word += value;
    } else if (has_fallback) {
      word += fallback;  // ${NAME:-default}, as in sh
    }
  };
  while (i < exec.size()) {
    const char c = exec[i];
    if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word && (literal || !word.empty())) words.push_back(word);
      word.clear();
      in_word = false;
      literal = false;
      ++i;
    } else if (c == '\'') {
      in_word = literal = true;
      const size_t close = exec.find('\'', i + 1);
      if (close == std::string::npos) fail("unterminated single quote");
      word += exec.substr(i + 1, close - i - 1);
      i = close + 1;
    } else if (c == '"') {
      in_word = literal = true;
      ++i;
      while (true) {
        if (i >= exec.size()) fail("unterminated double quote");
        const char d = exec[i];
        if (d == '"') {
          ++i;
          break;
        }
        if (d == '\\' && i + 1 < exec.size() &&
            (exec[i + 1] == '"' || exec[i + 1] == '\\' || exec[i + 1] == '$')) {
          word += exec[i + 1];
          i += 2;
        } else if (d == '$') {
          expand();
        } else if (d == '`') {
          fail("backquotes need use_shell = true");
        } else {
          word += d;
          ++i;
        }
      }
    } else if (c == '\\') {
      in_word = literal = true;
      if (i + 1 >= exec.size()) fail("trailing backslash");
      word += exec[i + 1];
      i += 2;
    } else if (c == '$') {
      in_word = true;
      expand();
    } else if (c == '|' || c == '&' || c == ';' || c == '<' || c == '>' || c == '`' || c == '(' ||
               c == ')') {
      fail(std::string("'") + c + "' is shell syntax; set use_shell = true to run through /bin/sh");
    } else {
      in_word = literal = true;
      word += c;
      ++i;
    }
  }
  if (in_word && (literal || !word.empty())) words.push_back(word);

  ExecPlan plan;
  size_t w = 0;
  for (; w < words.size(); ++w) {
    const std::string& s = words[w];
    const size_t eq = s.find('=');
    if (eq == std::string::npos || eq == 0 || !IsNameStart(s[0])) break;
    bool name_ok = true;
    for (size_t k = 0; k < eq; ++k) name_ok = name_ok && IsNameChar(s[k]);
    if (!name_ok) break;
    plan.env.emplace_back(s.substr(0, eq), s.substr(eq + 1));
  }
  plan.argv.assign(words.begin() + static_cast<long>(w), words.end());
  if (plan.argv.empty()) fail("no program to run");
  return plan;
}

std::string FindExecutable(const std::string& program, const std::string& path_list) {
  if (program.find('/') != std::string::npos) {
    return access(program.c_str(), X_OK) == 0 ? program : "";
  }
  size_t start = 0;
  while (start <= path_list.size()) {
    size_t end = path_list.find(':', start);
    if (end == std::string::npos) end = path_list.size();
    std::string dir = path_list.substr(start, end - start);
    if (dir.empty()) dir = ".";
    const std::string candidate = dir + "/" + program;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

}  // namespace procman
}  // namespace sarmap
