#include "common/args.h"

#include <cstdio>
#include <iostream>
#include <sstream>

#include "common/logging.h"
#include "common/options.h"

namespace sarmap {
namespace common {
namespace {

template <class T>
T ParseNumber(const std::string& name, const std::string& text) {
  std::istringstream in(text);
  T value;
  in >> value;
  if (!in || !in.eof()) throw ArgError(name + ": expected a number, got '" + text + "'");
  return value;
}

template <class T>
std::string ToText(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

ArgParser::ArgParser(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

void ArgParser::AddFlag(const std::string& name, std::string* value, const std::string& help) {
  options_.push_back({name, help, true, [value](const std::string& v) { *value = v; },
                      value->empty() ? "" : *value});
}
void ArgParser::AddFlag(const std::string& name, double* value, const std::string& help) {
  options_.push_back({name, help, true,
                      [value, name](const std::string& v) { *value = ParseNumber<double>(name, v); },
                      ToText(*value)});
}
void ArgParser::AddFlag(const std::string& name, int* value, const std::string& help) {
  options_.push_back({name, help, true,
                      [value, name](const std::string& v) { *value = ParseNumber<int>(name, v); },
                      ToText(*value)});
}
void ArgParser::AddFlag(const std::string& name, int64_t* value, const std::string& help) {
  options_.push_back({name, help, true,
                      [value, name](const std::string& v) { *value = ParseNumber<int64_t>(name, v); },
                      ToText(*value)});
}
void ArgParser::AddSwitch(const std::string& name, bool* value, const std::string& help) {
  options_.push_back({name, help, false, [value](const std::string&) { *value = true; }, ""});
}
void ArgParser::AddRepeated(const std::string& name, std::vector<std::string>* values,
                            const std::string& help) {
  options_.push_back({name, help, true, [values](const std::string& v) { values->push_back(v); }, ""});
}
void ArgParser::AddPositional(const std::string& name, std::string* value, const std::string& help,
                              bool required) {
  positionals_.push_back({name, help, required, value});
}
void ArgParser::AddRest(const std::string& name, std::vector<std::string>* values,
                        const std::string& help) {
  rest_ = values;
  rest_name_ = name;
  rest_help_ = help;
}

void ArgParser::AddNodeOptions(NodeArgs* args, const std::string& default_config) {
  if (args->config_path.empty()) args->config_path = default_config;
  AddFlag("--config", &args->config_path, "YAML options file");
  AddRepeated("--set", &args->overrides,
              "override one option: --set key=value (nested keys: a.b=value); repeatable");
  AddFlag("--lcm-url", &args->lcm_url,
          "LCM URL (default: $SARMAP_LCM_URL, else $LCM_DEFAULT_URL, else host-local udpm)");
  AddFlag("--bus-key-file", &args->bus_key_file,
          "key file of a signed bus (>= 16 random bytes, mode 600): sign every message published, "
          "act only on messages signed with it (default: none, an open bus)");
  AddFlag("--log-level", &args->log_level, "debug, info, warn or error");
  AddSwitch("--print-config", &args->print_config,
            "print the effective options (with help) and exit");
}

bool ArgParser::Parse(int argc, char** argv) {
  size_t next_positional = 0;
  bool only_positionals = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (!only_positionals && (arg == "-h" || arg == "--help")) {
      std::cout << Help();
      return false;
    }
    if (!only_positionals && arg == "--") {
      only_positionals = true;
      continue;
    }
    if (!only_positionals && arg.size() > 1 && arg[0] == '-') {
      std::string value;
      bool has_inline = false;
      const auto eq = arg.find('=');
      if (eq != std::string::npos && arg.rfind("--", 0) == 0) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        has_inline = true;
      }
      const Option* option = nullptr;
      for (const auto& o : options_) {
        if (o.name == arg) option = &o;
      }
      if (!option) throw ArgError("unknown option '" + arg + "' (see --help)");
      if (option->takes_value && !has_inline) {
        if (i + 1 >= argc) throw ArgError(arg + " needs a value");
        value = argv[++i];
      }
      option->set(value);
      continue;
    }
    if (next_positional < positionals_.size()) {
      *positionals_[next_positional++].value = arg;
    } else if (rest_) {
      rest_->push_back(arg);
      only_positionals = true;  // everything after belongs to the rest
    } else {
      throw ArgError("unexpected argument '" + arg + "' (see --help)");
    }
  }
  for (size_t p = next_positional; p < positionals_.size(); ++p) {
    if (positionals_[p].required) throw ArgError("missing " + positionals_[p].name + " (see --help)");
  }
  return true;
}

std::string ArgParser::Help() const {
  std::ostringstream out;
  out << "usage: " << program_ << " [options]";
  for (const auto& p : positionals_) out << (p.required ? " " : " [") << p.name << (p.required ? "" : "]");
  if (rest_) out << " [" << rest_name_ << "...]";
  out << "\n\n" << summary_ << "\n";
  if (!positionals_.empty() || rest_) {
    out << "\narguments:\n";
    for (const auto& p : positionals_) out << "  " << p.name << "\n      " << p.help << "\n";
    if (rest_) out << "  " << rest_name_ << "...\n      " << rest_help_ << "\n";
  }
  out << "\noptions:\n  -h, --help\n      show this help and exit\n";
  for (const auto& o : options_) {
    out << "  " << o.name << (o.takes_value ? " VALUE" : "") << "\n      " << o.help;
    if (!o.default_text.empty()) out << " (default: " << o.default_text << ")";
    out << "\n";
  }
  if (!epilog_.empty()) out << "\n" << epilog_ << "\n";
  return out.str();
}

int RunMain(const std::string& program, const std::function<int()>& body) {
  try {
    return body();
  } catch (const ArgError& e) {
    fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return 2;
  } catch (const OptionsError& e) {
    fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {
    fprintf(stderr, "%s: error: %s\n", program.c_str(), e.what());
    return 1;
  }
}

}  // namespace common
}  // namespace sarmap
