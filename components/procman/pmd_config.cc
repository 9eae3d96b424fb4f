#include "procman/pmd_config.h"

#include <cctype>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "procman/exec_line.h"

namespace sarmap {
namespace procman {

std::string Location::ToString() const {
  return file + ":" + std::to_string(line) + ":" + std::to_string(col);
}

std::string Target::ToString() const {
  switch (kind) {
    case kCommand:
      return "cmd \"" + name + "\"";
    case kGroup:
      return "group \"" + name + "\"";
    case kEverything:
      return "everything";
  }
  return "?";
}

int ParseSignal(const std::string& text) {
  if (text.empty()) return -1;
  bool digits = true;
  for (char c : text) digits = digits && std::isdigit(static_cast<unsigned char>(c));
  if (digits) {
    const int n = std::atoi(text.c_str());
    return (n > 0 && n < 65) ? n : -1;
  }
  std::string name = text;
  for (auto& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (name.rfind("SIG", 0) == 0) name = name.substr(3);
  static const std::map<std::string, int> kSignals = {
      {"HUP", SIGHUP},   {"INT", SIGINT},   {"QUIT", SIGQUIT}, {"KILL", SIGKILL},
      {"USR1", SIGUSR1}, {"USR2", SIGUSR2}, {"TERM", SIGTERM}, {"ALRM", SIGALRM}};
  auto it = kSignals.find(name);
  return it == kSignals.end() ? -1 : it->second;
}

namespace {

struct Token {
  enum Kind { kIdent, kString, kNumber, kPunct, kEnd } kind = kEnd;
  std::string text;
  Location where;
};

class Lexer {
 public:
  Lexer(const std::string& text, const std::string& source) : text_(text), source_(source) {}

  std::vector<Token> Tokens() {
    std::vector<Token> out;
    while (true) {
      SkipSpaceAndComments();
      Token t;
      t.where = Here();
      if (pos_ >= text_.size()) {
        t.kind = Token::kEnd;
        out.push_back(t);
        return out;
      }
      const char c = text_[pos_];
      if (c == '"') {
        t.kind = Token::kString;
        Advance();
        while (true) {
          if (pos_ >= text_.size()) Fail(t.where, "unterminated string");
          char d = text_[pos_];
          if (d == '"') {
            Advance();
            break;
          }
          if (d == '\n') Fail(t.where, "unterminated string (newline inside quotes)");
          if (d == '\\' && pos_ + 1 < text_.size()) {
            Advance();
            d = text_[pos_];
            if (d == 'n')
              d = '\n';
            else if (d == 't')
              d = '\t';
            // \" and \\ and anything else: the character itself
          }
          t.text += d;
          Advance();
        }
      } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
        t.kind = Token::kIdent;
        while (pos_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos_])) ||
                                       text_[pos_] == '_' || text_[pos_] == '-')) {
          t.text += text_[pos_];
          Advance();
        }
      } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.') {
        t.kind = Token::kNumber;
        while (pos_ < text_.size() &&
               (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.' ||
                text_[pos_] == '-' || text_[pos_] == 'e' || text_[pos_] == 'E' ||
                text_[pos_] == '+')) {
          t.text += text_[pos_];
          Advance();
        }
      } else if (c == '{' || c == '}' || c == ';' || c == '=') {
        t.kind = Token::kPunct;
        t.text = std::string(1, c);
        Advance();
      } else {
        Fail(t.where, std::string("unexpected character '") + c + "'");
      }
      out.push_back(t);
    }
  }

 private:
  Location Here() const { return Location{source_, line_, col_}; }
  void Advance() {
    if (text_[pos_] == '\n') {
      ++line_;
      col_ = 1;
    } else {
      ++col_;
    }
    ++pos_;
  }
  void SkipSpaceAndComments() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (std::isspace(static_cast<unsigned char>(c))) {
        Advance();
      } else if (c == '#' || (c == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '/')) {
        while (pos_ < text_.size() && text_[pos_] != '\n') Advance();
      } else {
        break;
      }
    }
  }
  [[noreturn]] void Fail(const Location& where, const std::string& what) {
    throw ConfigError(where.ToString() + ": " + what);
  }

  const std::string& text_;
  std::string source_;
  size_t pos_ = 0;
  int line_ = 1;
  int col_ = 1;
};

std::string Describe(const Token& t) {
  switch (t.kind) {
    case Token::kEnd:
      return "end of file";
    case Token::kString:
      return "\"" + t.text + "\"";
    default:
      return "'" + t.text + "'";
  }
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, Config* config) : tokens_(std::move(tokens)), config_(config) {}

  void ParseFile() {
    while (Peek().kind != Token::kEnd) {
      const Token& t = Peek();
      if (IsWord(t, "cmd")) {
        ParseCommand("");
      } else if (IsWord(t, "group")) {
        ParseGroup("");
      } else if (IsWord(t, "script")) {
        ParseScript();
      } else {
        Fail(t, "expected 'cmd', 'group' or 'script', found " + Describe(t));
      }
    }
  }

 private:
  static bool IsWord(const Token& t, const char* word) {
    return t.kind == Token::kIdent && t.text == word;
  }
  const Token& Peek() const { return tokens_[pos_]; }
  const Token& Next() {
    const Token& t = tokens_[pos_];
    if (t.kind != Token::kEnd) ++pos_;
    return t;
  }
  [[noreturn]] void Fail(const Token& t, const std::string& what) {
    throw ConfigError(t.where.ToString() + ": " + what);
  }
  const Token& ExpectPunct(const char* p, const std::string& context) {
    const Token& t = Next();
    if (t.kind != Token::kPunct || t.text != p) {
      Fail(t, std::string("expected '") + p + "' " + context + ", found " + Describe(t));
    }
    return t;
  }
  const Token& ExpectString(const std::string& what) {
    const Token& t = Next();
    if (t.kind != Token::kString)
      Fail(t, "expected " + what + " in double quotes, found " + Describe(t));
    return t;
  }
  const Token& ExpectWord(const char* word, const std::string& context) {
    const Token& t = Next();
    if (!IsWord(t, word))
      Fail(t, std::string("expected '") + word + "' " + context + ", found " + Describe(t));
    return t;
  }

  void ParseGroup(const std::string& parent) {
    Next();  // group
    const Token& name = ExpectString("a group name");
    if (name.text.empty() || name.text.find('/') != std::string::npos) {
      Fail(name, "group name must be non-empty and contain no '/'");
    }
    const std::string path = parent.empty() ? name.text : parent + "/" + name.text;
    ExpectPunct("{", "after the group name");
    while (!(Peek().kind == Token::kPunct && Peek().text == "}")) {
      const Token& t = Peek();
      if (IsWord(t, "cmd")) {
        ParseCommand(path);
      } else if (IsWord(t, "group")) {
        ParseGroup(path);
      } else {
        Fail(t, "expected 'cmd', 'group' or '}' in group \"" + path + "\", found " + Describe(t));
      }
    }
    Next();  // }
  }

  static bool ParseBool(const Token& t, bool* out) {
    std::string v = t.text;
    for (auto& c : v) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (v == "true" || v == "1" || v == "yes") {
      *out = true;
      return true;
    }
    if (v == "false" || v == "0" || v == "no") {
      *out = false;
      return true;
    }
    return false;
  }

  // Fails at `name` when `defined` already holds a `kind` of that name (its `name_of` member).
  template <class Entry>
  void FailIfDefined(const Token& name, const std::string& kind, const std::vector<Entry>& defined,
                     std::string Entry::*name_of) {
    for (const auto& e : defined) {
      if (e.*name_of == name.text) {
        Fail(name, "duplicate " + kind + " \"" + name.text + "\" (first defined at " +
                       e.where.ToString() + ")");
      }
    }
  }

  void ParseCommand(const std::string& group) {
    const Token& kw = Next();  // cmd
    const Token& name = ExpectString("a command name");
    if (name.text.empty()) Fail(name, "command name must not be empty");
    FailIfDefined(name, "command", config_->commands, &CommandConfig::id);
    CommandConfig cmd;
    cmd.id = name.text;
    cmd.group = group;
    cmd.where = kw.where;
    ExpectPunct("{", "after the command name");
    bool has_exec = false;
    Token exec_token;
    std::set<std::string> seen;
    while (!(Peek().kind == Token::kPunct && Peek().text == "}")) {
      const Token& key = Next();
      if (key.kind != Token::kIdent)
        Fail(key, "expected an attribute name or '}', found " + Describe(key));
      if (!seen.insert(key.text == "host" ? "deputy" : key.text).second) {
        Fail(key, "attribute '" + key.text + "' given twice");
      }
      ExpectPunct("=", "after '" + key.text + "'");
      const Token& value = Next();
      if (value.kind != Token::kString && value.kind != Token::kNumber &&
          value.kind != Token::kIdent) {
        Fail(value, "expected a value for '" + key.text + "', found " + Describe(value));
      }
      if (key.text == "exec") {
        if (value.kind != Token::kString) Fail(value, "exec must be a quoted string");
        cmd.exec = value.text;
        exec_token = value;
        has_exec = !cmd.exec.empty();
        if (!has_exec) Fail(value, "exec must not be empty");
      } else if (key.text == "host" || key.text == "deputy") {
        if (value.text.empty()) Fail(value, key.text + " must not be empty");
        cmd.deputy = value.text;
      } else if (key.text == "auto_respawn" || key.text == "use_shell") {
        bool b = false;
        if (!ParseBool(value, &b))
          Fail(value, key.text + " must be true or false, is " + Describe(value));
        (key.text == "auto_respawn" ? cmd.auto_respawn : cmd.use_shell) = b;
      } else if (key.text == "stop_signal") {
        const int sig = ParseSignal(value.text);
        if (sig < 0)
          Fail(value, "unknown signal " + Describe(value) + " (e.g. SIGINT, SIGTERM, 15)");
        if (sig == SIGKILL)
          Fail(value,
               "stop_signal SIGKILL leaves no chance to clean up; use stop_time_allowed = 0");
        cmd.stop_signal = sig;
      } else if (key.text == "stop_time_allowed") {
        char* end = nullptr;
        const double s = std::strtod(value.text.c_str(), &end);
        if (value.text.empty() || *end != '\0' || !(s >= 0) || s > 3600) {
          Fail(value, "stop_time_allowed must be seconds in [0, 3600], is " + Describe(value));
        }
        cmd.stop_time_allowed_s = s;
      } else if (key.text == "nickname" || key.text == "group") {
        Fail(key, "'" + key.text +
                      "' is old procman syntax: name the command in cmd \"NAME\" and nest it in "
                      "group \"...\" { }");
      } else {
        Fail(key, "unknown attribute '" + key.text +
                      "' (known: exec, deputy/host, auto_respawn, stop_signal, stop_time_allowed, "
                      "use_shell)");
      }
      ExpectPunct(";", "after the value of '" + key.text + "'");
    }
    const Token& close = Next();  // }
    if (!has_exec) Fail(close, "command \"" + cmd.id + "\" has no exec");
    if (!cmd.use_shell) {
      // Catch quoting mistakes and shell syntax now, not when the deputy starts it.
      try {
        PlanExec(cmd.exec, [](const std::string&) { return "x"; });
      } catch (const std::invalid_argument& e) {
        Fail(exec_token, e.what());
      }
    }
    config_->commands.push_back(cmd);
  }

  Target ParseTarget(const std::string& verb) {
    const Token& t = Next();
    Target target;
    if (IsWord(t, "everything")) {
      target.kind = Target::kEverything;
    } else if (IsWord(t, "cmd") || IsWord(t, "group")) {
      target.kind = t.text == "cmd" ? Target::kCommand : Target::kGroup;
      const Token& name = ExpectString(t.text + " name");
      target.name = name.text;
      targets_.push_back({target, name.where});
    } else {
      Fail(t, "expected 'cmd', 'group' or 'everything' after '" + verb + "', found " + Describe(t));
    }
    return target;
  }

  double ParseTimeout() {
    const Token& t = Next();  // timeout
    const Token& v = Next();
    char* end = nullptr;
    const double s = std::strtod(v.text.c_str(), &end);
    if (v.kind != Token::kNumber || *end != '\0' || !(s > 0)) {
      Fail(v, "timeout must be a positive number of seconds, found " + Describe(v));
    }
    (void)t;
    return s;
  }

  std::string ParseStatus() {
    const Token& s = ExpectString("a status (\"running\" or \"stopped\")");
    if (s.text != "running" && s.text != "stopped") {
      Fail(s, "status must be \"running\" or \"stopped\", is \"" + s.text + "\"");
    }
    return s.text;
  }

  void ParseScript() {
    const Token& kw = Next();  // script
    const Token& name = ExpectString("a script name");
    FailIfDefined(name, "script", config_->scripts, &Script::name);
    Script script;
    script.name = name.text;
    script.where = kw.where;
    ExpectPunct("{", "after the script name");
    while (!(Peek().kind == Token::kPunct && Peek().text == "}")) {
      const Token& verb = Next();
      ScriptAction a;
      a.where = verb.where;
      if (IsWord(verb, "start") || IsWord(verb, "stop") || IsWord(verb, "restart")) {
        a.kind = verb.text == "start"  ? ScriptAction::kStart
                 : verb.text == "stop" ? ScriptAction::kStop
                                       : ScriptAction::kRestart;
        a.target = ParseTarget(verb.text);
        if (IsWord(Peek(), "wait")) {
          Next();
          a.wait_status = ParseStatus();
          if (IsWord(Peek(), "timeout")) a.timeout_s = ParseTimeout();
        }
      } else if (IsWord(verb, "wait")) {
        const Token& what = Peek();
        if (IsWord(what, "ms")) {
          Next();
          const Token& v = Next();
          char* end = nullptr;
          const long ms = std::strtol(v.text.c_str(), &end, 10);
          if (v.kind != Token::kNumber || *end != '\0' || ms < 0 || ms > 3600 * 1000) {
            Fail(v, "wait ms needs milliseconds in [0, 3600000], found " + Describe(v));
          }
          a.kind = ScriptAction::kWaitMs;
          a.wait_ms = static_cast<int>(ms);
        } else if (IsWord(what, "cmd") || IsWord(what, "group")) {
          a.kind = ScriptAction::kWaitStatus;
          a.target = ParseTarget("wait");
          ExpectWord("status", "after the wait target");
          a.wait_status = ParseStatus();
          if (IsWord(Peek(), "timeout")) a.timeout_s = ParseTimeout();
        } else {
          Fail(what, "expected 'ms', 'cmd' or 'group' after 'wait', found " + Describe(what));
        }
      } else if (IsWord(verb, "run_script")) {
        a.kind = ScriptAction::kRunScript;
        const Token& s = ExpectString("a script name");
        a.script = s.text;
        script_refs_.push_back({s.text, s.where});
      } else {
        Fail(verb, "expected start, stop, restart, wait, run_script or '}' in script \"" +
                       script.name + "\", found " + Describe(verb));
      }
      ExpectPunct(";", "at the end of the action");
      script.actions.push_back(a);
    }
    Next();  // }
    config_->scripts.push_back(script);
  }

 public:
  // Checks references once everything is read (scripts may come before the commands).
  void CheckReferences() {
    for (const auto& [target, where] : targets_) {
      if (target.kind == Target::kCommand && !config_->FindCommand(target.name)) {
        throw ConfigError(where.ToString() + ": no command \"" + target.name + "\"");
      }
      if (target.kind == Target::kGroup && !config_->HasGroup(target.name)) {
        throw ConfigError(where.ToString() + ": no group \"" + target.name + "\"");
      }
    }
    for (const auto& [name, where] : script_refs_) {
      if (!config_->FindScript(name))
        throw ConfigError(where.ToString() + ": no script \"" + name + "\"");
    }
    // run_script cycles would never end.
    std::map<std::string, int> mark;  // 0 new, 1 visiting, 2 done
    std::function<void(const Script&)> visit = [&](const Script& s) {
      mark[s.name] = 1;
      for (const auto& a : s.actions) {
        if (a.kind != ScriptAction::kRunScript) continue;
        const int m = mark[a.script];
        if (m == 1)
          throw ConfigError(a.where.ToString() + ": run_script \"" + a.script + "\" makes a cycle");
        if (m == 0) visit(*config_->FindScript(a.script));
      }
      mark[s.name] = 2;
    };
    for (const auto& s : config_->scripts) {
      if (mark[s.name] == 0) visit(s);
    }
  }

 private:
  std::vector<Token> tokens_;
  size_t pos_ = 0;
  Config* config_;
  std::vector<std::pair<Target, Location>> targets_;
  std::vector<std::pair<std::string, Location>> script_refs_;
};

bool GroupContains(const std::string& group, const std::string& path) {
  return group == path || (group.size() > path.size() && group.compare(0, path.size(), path) == 0 &&
                           group[path.size()] == '/');
}

}  // namespace

const CommandConfig* Config::FindCommand(const std::string& id) const {
  for (const auto& c : commands) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

const Script* Config::FindScript(const std::string& name) const {
  for (const auto& s : scripts) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

bool Config::HasGroup(const std::string& path) const {
  if (path.empty()) return false;
  for (const auto& c : commands) {
    if (GroupContains(c.group, path)) return true;
  }
  return false;
}

std::vector<const CommandConfig*> Config::Select(const Target& target) const {
  std::vector<const CommandConfig*> out;
  for (const auto& c : commands) {
    if (target.kind == Target::kEverything ||
        (target.kind == Target::kCommand && c.id == target.name) ||
        (target.kind == Target::kGroup && GroupContains(c.group, target.name))) {
      out.push_back(&c);
    }
  }
  return out;
}

std::vector<std::string> Config::Deputies() const {
  std::vector<std::string> out;
  for (const auto& c : commands) {
    bool seen = false;
    for (const auto& d : out) seen = seen || d == c.deputy;
    if (!seen) out.push_back(c.deputy);
  }
  return out;
}

Target Config::ResolveTarget(const std::string& name) const {
  Target t;
  if (name == "everything" || name == "all") return t;
  if (name.rfind("group:", 0) == 0) {
    t.kind = Target::kGroup;
    t.name = name.substr(6);
    if (!HasGroup(t.name)) throw ConfigError(source + ": no group \"" + t.name + "\"");
    return t;
  }
  if (name.rfind("cmd:", 0) == 0) {
    t.kind = Target::kCommand;
    t.name = name.substr(4);
    if (!FindCommand(t.name)) throw ConfigError(source + ": no command \"" + t.name + "\"");
    return t;
  }
  if (FindCommand(name)) {
    t.kind = Target::kCommand;
    t.name = name;
    return t;
  }
  if (HasGroup(name)) {
    t.kind = Target::kGroup;
    t.name = name;
    return t;
  }
  throw ConfigError(source + ": no command or group \"" + name + "\"");
}

Config ParseConfig(const std::string& text, const std::string& source) {
  Config config;
  config.source = source;
  Lexer lexer(text, source);
  Parser parser(lexer.Tokens(), &config);
  parser.ParseFile();
  parser.CheckReferences();
  return config;
}

Config LoadConfigFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseConfig(buffer.str(), path);
}

}  // namespace procman
}  // namespace sarmap
