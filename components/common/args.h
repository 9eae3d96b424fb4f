#pragma once
// Command-line parsing shared by every sarmap program: flags, positionals, a generated
// --help, and the standard node options (--config, --set, --lcm-url, --log-level,
// --print-config).

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sarmap {
namespace common {

class ArgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The options every node takes.
struct NodeArgs {
  std::string config_path;             // --config FILE (YAML)
  std::vector<std::string> overrides;  // --set key=value, repeatable
  std::string lcm_url;                 // --lcm-url URL ("" = default)
  std::string bus_key_file;            // --bus-key-file FILE: sign and verify (common/bus_auth.h)
  std::string log_level = "info";      // --log-level
  bool print_config = false;           // --print-config: print effective options and exit
};

class ArgParser {
 public:
  ArgParser(std::string program, std::string summary);

  void AddFlag(const std::string& name, std::string* value, const std::string& help);
  void AddFlag(const std::string& name, double* value, const std::string& help);
  void AddFlag(const std::string& name, int* value, const std::string& help);
  void AddFlag(const std::string& name, int64_t* value, const std::string& help);
  void AddSwitch(const std::string& name, bool* value, const std::string& help);
  void AddRepeated(const std::string& name, std::vector<std::string>* values,
                   const std::string& help);
  void AddPositional(const std::string& name, std::string* value, const std::string& help,
                     bool required = true);
  // Remaining positionals (e.g. a command line after "--").
  void AddRest(const std::string& name, std::vector<std::string>* values, const std::string& help);
  void AddNodeOptions(NodeArgs* args, const std::string& default_config = "");
  // Extra text printed after the option list (examples, channels).
  void SetEpilog(std::string text) { epilog_ = std::move(text); }

  // Returns false when --help was printed (the caller exits 0). Throws ArgError.
  bool Parse(int argc, char** argv);
  std::string Help() const;

 private:
  struct Option {
    std::string name;
    std::string help;
    bool takes_value;
    std::function<void(const std::string&)> set;
    std::string default_text;
  };
  struct Positional {
    std::string name;
    std::string help;
    bool required;
    std::string* value;
  };
  std::string program_;
  std::string summary_;
  std::string epilog_;
  std::vector<Option> options_;
  std::vector<Positional> positionals_;
  std::vector<std::string>* rest_ = nullptr;
  std::string rest_name_, rest_help_;
};

// Runs `body` and turns the errors a user can cause (bad arguments, bad options, missing
// files) into one clear line on stderr and exit code 2; anything else into exit code 1.
int RunMain(const std::string& program, const std::function<int()>& body);

}  // namespace common
}  // namespace sarmap
