// Every file in config/ loads through the options struct of the program that reads it, and
// validates: a key renamed in code, or a value out of range in a file, fails here rather than
// when a user starts the program. A new config file is added to tests/tools/shipped_configs.cc.
#include <dirent.h>
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/robot_config.h"
#include "sim/world.h"
#include "tools/shipped_configs.h"

namespace sarmap {
namespace {

const std::string kConfig = std::string(SARMAP_SOURCE_DIR) + "/config/";

std::set<std::string> YamlFiles(const std::string& dir) {
  std::set<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, ".yaml") == 0) out.insert(name);
    }
    closedir(d);
  }
  return out;
}

TEST(ConfigFiles, EveryConfigFileLoadsThroughItsOptions) {
  std::map<std::string, const ShippedConfig*> loaders;
  for (const ShippedConfig& config : ShippedConfigs()) {
    loaders[config.file] = &config;
  }
  const std::set<std::string> files = YamlFiles(kConfig);
  ASSERT_FALSE(files.empty()) << "no config files in " << kConfig;
  for (const std::string& name : files) {
    const auto loader = loaders.find(name);
    if (loader == loaders.end()) {
      ADD_FAILURE() << "config/" << name
                    << ": not in tests/tools/shipped_configs.cc (which program reads it?)";
      continue;
    }
    try {
      loader->second->load(kConfig + name);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/" << name << ": " << e.what();
    }
  }
}

TEST(ConfigFiles, EveryWorldAndArrayLoads) {
  const std::set<std::string> worlds = YamlFiles(kConfig + "worlds");
  EXPECT_GE(worlds.size(), 4u);
  for (const std::string& name : worlds) {
    try {
      const sim::World world = sim::LoadWorld(kConfig + "worlds/" + name);
      EXPECT_FALSE(world.people.empty()) << "config/worlds/" << name << ": nobody to find";
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/worlds/" << name << ": " << e.what();
    }
  }
  const std::set<std::string> arrays = YamlFiles(kConfig + "arrays");
  EXPECT_GE(arrays.size(), 1u);
  for (const std::string& name : arrays) {
    try {
      const common::MicArrayOptions array = common::LoadMicArray(kConfig + "arrays/" + name);
      EXPECT_GE(array.num_mics(), 2) << "config/arrays/" << name;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/arrays/" << name << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace sarmap
