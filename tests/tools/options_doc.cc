// sarmap-options-doc: the configuration tables of the READMEs, generated from the options'
// help strings and the values of the shipped config files. A README asks for a table with
//   <!-- options: NAME -->
//   <!-- /options -->
// (NAME: a file config/NAME.yaml); --write fills every such block, --check fails when one is
// out of date (a test runs it, `make docs` writes).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <cstring>
#include <string>
#include <vector>

#include "common/args.h"
#include "tools/shipped_configs.h"

namespace fs = std::filesystem;
using namespace sarmap;

namespace {

constexpr const char* kOpen = "<!-- options: ";
constexpr const char* kClose = "<!-- /options -->";

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every README.md under `root`, build trees and hidden folders left out.
std::vector<fs::path> Readmes(const fs::path& root) {
  std::vector<fs::path> out;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator();
       ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() && (name.rfind("build", 0) == 0 || name[0] == '.')) {
      it.disable_recursion_pending();
    } else if (it->is_regular_file() && name == "README.md") {
      out.push_back(it->path());
    }
  }
  return out;
}

// `text` with every block's body regenerated; problems (unknown NAME, unclosed block) appended
// to `errors` as "path: what".
std::string Regenerate(const std::string& text, const std::string& path,
                       const fs::path& config_dir,
                       const std::map<std::string, const ShippedConfig*>& configs,
                       std::vector<std::string>* errors) {
  std::string out;
  size_t pos = 0;
  while (true) {
    const size_t open = text.find(kOpen, pos);
    if (open == std::string::npos) break;
    const size_t name_end = text.find(" -->", open);
    const size_t line_end = text.find('\n', open);
    const size_t close = text.find(kClose, open);
    if (name_end == std::string::npos || line_end == std::string::npos || name_end > line_end ||
        close == std::string::npos) {
      errors->push_back(path + ": an options block without its " + std::string(kClose));
      break;
    }
    const std::string name = text.substr(open + strlen(kOpen), name_end - open - strlen(kOpen));
    const auto config = configs.find(name + ".yaml");
    out += text.substr(pos, line_end + 1 - pos);
    if (config == configs.end()) {
      errors->push_back(path + ": no config/" + name + ".yaml among the shipped configs");
      out += text.substr(line_end + 1, close - line_end - 1);
    } else {
      out += "Keys and values of `config/" + name +
             ".yaml`, with each key's valid values and help (generated from the options: `make "
             "docs`).\n\n";
      out += config->second->markdown((config_dir / (name + ".yaml")).string());
    }
    pos = close;
  }
  return out + text.substr(pos);
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-options-doc", [&]() -> int {
    common::ArgParser parser("sarmap-options-doc",
                             "Writes or checks the generated configuration tables of the READMEs "
                             "(blocks <!-- options: NAME --> ... <!-- /options -->).");
    std::string root = ".";
    bool write = false, check = false;
    parser.AddFlag("--root", &root, "source tree whose README.md files are read");
    parser.AddSwitch("--write", &write, "rewrite the blocks that are out of date");
    parser.AddSwitch("--check", &check, "exit 1 naming the READMEs whose blocks are out of date");
    parser.SetEpilog("example: sarmap-options-doc --root . --write   (make docs)");
    if (!parser.Parse(argc, argv)) return 0;
    if (write == check) throw common::ArgError("give one of --write and --check");
    const fs::path config_dir = fs::path(root) / "config";
    if (!fs::is_directory(config_dir)) {
      throw common::ArgError(config_dir.string() + ": no such folder (is --root the source tree?)");
    }
    std::map<std::string, const ShippedConfig*> configs;
    for (const ShippedConfig& config : ShippedConfigs()) configs[config.file] = &config;

    std::vector<std::string> errors, stale;
    int blocks = 0;
    for (const fs::path& readme : Readmes(root)) {
      const std::string text = ReadFile(readme);
      const std::string path = fs::relative(readme, root).string();
      for (size_t at = text.find(kOpen); at != std::string::npos; at = text.find(kOpen, at + 1)) {
        ++blocks;
      }
      const std::string fresh = Regenerate(text, path, config_dir, configs, &errors);
      if (fresh == text) continue;
      stale.push_back(path);
      if (write) {
        std::ofstream(readme, std::ios::binary) << fresh;
        std::cout << "wrote " << path << "\n";
      }
    }
    for (const std::string& e : errors) std::cerr << "sarmap-options-doc: " << e << "\n";
    if (check) {
      for (const std::string& path : stale) {
        std::cerr << "sarmap-options-doc: " << path
                  << ": a configuration table is out of date (run make docs)\n";
      }
      std::cout << blocks << " options blocks, " << stale.size() << " out of date\n";
      return stale.empty() && errors.empty() ? 0 : 1;
    }
    return errors.empty() ? 0 : 1;
  });
}
