#pragma once
// Every file in config/ with the options struct of the program that reads it: the config test
// loads each through it, and sarmap-options-doc writes each as the configuration table of a
// README. A new config file is added here.

#include <functional>
#include <string>
#include <vector>

namespace sarmap {

struct ShippedConfig {
  std::string file;  // name in config/, e.g. "slam.yaml"
  // Loads and validates the file as its program does; throws common::OptionsError.
  std::function<void(const std::string& path)> load;
  // The options as the file sets them, one Markdown table row per key (help as the meaning).
  std::function<std::string(const std::string& path)> markdown;
};

const std::vector<ShippedConfig>& ShippedConfigs();

}  // namespace sarmap
