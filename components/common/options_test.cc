#include "common/options.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <fstream>

namespace sarmap {
namespace common {
namespace {

struct GridOptions {
  double resolution_m = 0.05;
  int width = 100;
  template <class V>
  void Visit(V& v) {
    v("resolution_m", resolution_m, "cell size", Positive());
    v("width", width, "cells", AtLeast(1));
  }
};

struct TestOptions {
  double min_range_m = 0.0;
  double max_range_m = 4.5;
  bool enabled = true;
  std::string mode = "fast";
  std::vector<double> weights = {1.0, 2.0};
  GridOptions grid;
  template <class V>
  void Visit(V& v) {
    v("min_range_m", min_range_m, "min range", NonNegative());
    v("max_range_m", max_range_m, "max range", Positive());
    v("enabled", enabled, "on/off");
    v("mode", mode, "fast or exact", OneOf({"fast", "exact"}));
    v("weights", weights, "weights", InRange(0, 10));
    v("grid", grid, "grid");
  }
  // What involves several keys.
  void Validate(Validator& check) const {
    check.That(max_range_m > min_range_m, "max_range_m", "must exceed min_range_m");
  }
};

// One file per process and test: CTest runs the cases as parallel processes, and a shared name
// let one case read another's half-written file (a flaky OptionsTest.WrongTypeIsNamed).
std::string WriteTemp(const std::string& text) {
  const std::string path = ::testing::TempDir() + "/options_test_" +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           std::to_string(getpid()) + ".yaml";
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  try {
    LoadOptions<TestOptions>(yaml.empty() ? "" : WriteTemp(yaml), overrides);
  } catch (const OptionsError& e) {
    return e.what();
  }
  return "";
}

TEST(OptionsTest, DefaultsFileAndOverridesApplyInOrder) {
  const auto path = WriteTemp("max_range_m: 3.0\ngrid:\n  width: 7\nweights: [0.5]\n");
  const auto o = LoadOptions<TestOptions>(path, {"grid.resolution_m=0.1", "mode=exact"});
  EXPECT_DOUBLE_EQ(o.max_range_m, 3.0);
  EXPECT_EQ(o.grid.width, 7);
  EXPECT_DOUBLE_EQ(o.grid.resolution_m, 0.1);
  EXPECT_EQ(o.mode, "exact");
  EXPECT_EQ(o.weights, std::vector<double>({0.5}));
  EXPECT_TRUE(o.enabled);
}

TEST(OptionsTest, UnknownKeyIsNamedWithItsLine) {
  const std::string e = ErrorOf("max_range_m: 3\ngrid:\n  widht: 7\n");
  EXPECT_NE(e.find("grid.widht"), std::string::npos) << e;
  EXPECT_NE(e.find(":3:3"), std::string::npos) << e;  // line 3, column 3
}

TEST(OptionsTest, WrongTypeIsNamed) {
  const std::string e = ErrorOf("max_range_m: far\n");
  EXPECT_NE(e.find("max_range_m"), std::string::npos) << e;
  EXPECT_NE(e.find("'far'"), std::string::npos) << e;
}

TEST(OptionsTest, ValidationNamesEveryBadKeyIncludingNested) {
  const std::string e =
      ErrorOf("", {"max_range_m=-1", "grid.width=0", "mode=slow", "weights=[1, 11]"});
  EXPECT_NE(e.find("max_range_m: must be > 0, is -1"), std::string::npos) << e;
  EXPECT_NE(e.find("grid.width: must be >= 1, is 0"), std::string::npos) << e;
  EXPECT_NE(e.find("mode: must be one of {fast, exact}, is 'slow'"), std::string::npos) << e;
  EXPECT_NE(e.find("weights: must be in [0, 10], is 11"), std::string::npos) << e;
  EXPECT_EQ(e.find("weights:"), e.rfind("weights:")) << e;  // 11 only, not 1
  // Validate() still runs beside the rules.
  const std::string cross = ErrorOf("", {"min_range_m=5"});
  EXPECT_NE(cross.find("max_range_m: must exceed min_range_m"), std::string::npos) << cross;
  EXPECT_EQ(ErrorOf("", {"min_range_m=1", "grid.width=1", "weights=[0, 10]"}), "");
}

struct MisruledOptions {
  double gain = 1;
  bool on = true;
  std::string name = "a";
  template <class V>
  void Visit(V& v) {
    v("gain", gain, "gain", OneOf({"a"}));
    v("on", on, "on", Positive());
    v("name", name, "name", Positive());
  }
};

TEST(OptionsTest, ARuleThatCannotApplyToItsTypeIsAnError) {
  Validator check;
  CheckOptions(MisruledOptions(), &check);
  ASSERT_EQ(check.errors().size(), 3u);
  EXPECT_EQ(check.errors()[0], "gain: a number cannot be one of {a}");
  EXPECT_EQ(check.errors()[1], "on: a yes/no option has no rule");
  EXPECT_EQ(check.errors()[2], "name: a text cannot be > 0");
}

TEST(OptionsTest, PrintedHelpShowsEachKeysRule) {
  const std::string yaml = OptionsToYaml(TestOptions(), true);
  EXPECT_NE(yaml.find("max_range_m: 4.5  # a number, > 0\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("mode: fast  # a string, one of {fast, exact}\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("enabled: true  # a boolean\n"), std::string::npos) << yaml;
}

TEST(OptionsTest, BadOverridesAreRejected) {
  EXPECT_NE(ErrorOf("", {"nope=1"}).find("--set nope: unknown key"), std::string::npos);
  EXPECT_NE(ErrorOf("", {"novalue"}).find("key=value"), std::string::npos);
  EXPECT_NE(ErrorOf("", {"max_range_m=nan"}).find("max_range_m"), std::string::npos);
}

TEST(OptionsTest, SyntaxErrorsAndMissingFilesAreClear) {
  EXPECT_NE(ErrorOf("a: [1, 2\n").find("YAML syntax error"), std::string::npos);
  try {
    LoadOptions<TestOptions>("/nonexistent/x.yaml", {});
    FAIL();
  } catch (const OptionsError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

TEST(OptionsTest, PrintedYamlLoadsBackToTheSameOptions) {
  TestOptions o;
  o.max_range_m = 2.25;
  o.grid.width = 9;
  o.mode = "exact";
  const auto back = LoadOptions<TestOptions>(WriteTemp(OptionsToYaml(o, true)), {});
  EXPECT_DOUBLE_EQ(back.max_range_m, 2.25);
  EXPECT_EQ(back.grid.width, 9);
  EXPECT_EQ(back.mode, "exact");
}

TEST(OptionsTest, MarkdownTableHasEveryLeafKeyItsValueAndHelp) {
  TestOptions o;
  o.mode = "exact";
  o.grid.width = 9;
  EXPECT_EQ(OptionsToMarkdown(o),
            "| key | value | valid | meaning |\n"
            "|---|---|---|---|\n"
            "| `min_range_m` | `0` | >= 0 | min range |\n"
            "| `max_range_m` | `4.5` | > 0 | max range |\n"
            "| `enabled` | `true` |  | on/off |\n"
            "| `mode` | `exact` | one of {fast, exact} | fast or exact |\n"
            "| `weights` | `[1, 2]` | in [0, 10] | weights |\n"
            "| `grid.resolution_m` | `0.05` | > 0 | cell size |\n"
            "| `grid.width` | `9` | >= 1 | cells |\n");
  EXPECT_EQ(options_internal::MarkdownCell("a | b\nc"), "a \\| b c");
}

TEST(OptionsTest, SectionSelectsATopLevelKey) {
  const auto path = WriteTemp("slam:\n  max_range_m: 1.5\nother: 3\n");
  EXPECT_DOUBLE_EQ(LoadOptions<TestOptions>(path, {}, "slam").max_range_m, 1.5);
  EXPECT_THROW(LoadOptions<TestOptions>(path, {}, "missing"), OptionsError);
}

TEST(OptionsTest, ExtendsLaysTheFileOverItsBase) {
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/options_base.yaml") << "max_range_m: 3.0\nmode: exact\ngrid:\n  width: 7\n"
                                               "  resolution_m: 0.2\nweights: [1, 2, 3]\n";
  std::ofstream(dir + "/options_robot.yaml")
      << "extends: options_base.yaml\ngrid:\n  width: 9\nweights: [4]\n";
  const auto o = LoadOptions<TestOptions>(dir + "/options_robot.yaml", {"grid.resolution_m=0.1"});
  EXPECT_DOUBLE_EQ(o.max_range_m, 3.0);  // from the base
  EXPECT_EQ(o.mode, "exact");            // from the base
  EXPECT_EQ(o.grid.width, 9);            // nested key overridden, its sibling kept
  EXPECT_DOUBLE_EQ(o.grid.resolution_m, 0.1);
  EXPECT_EQ(o.weights, std::vector<double>({4}));  // lists are replaced, not merged

  // Errors still name a key's line and both files; a missing base and a cycle are clear.
  std::ofstream(dir + "/options_robot.yaml") << "extends: options_base.yaml\ngrid:\n  widht: 9\n";
  try {
    LoadOptions<TestOptions>(dir + "/options_robot.yaml", {});
    FAIL();
  } catch (const OptionsError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("grid.widht"), std::string::npos) << what;
    EXPECT_NE(what.find("extends"), std::string::npos) << what;
  }
  std::ofstream(dir + "/options_robot.yaml") << "extends: missing_base.yaml\n";
  EXPECT_THROW(LoadOptions<TestOptions>(dir + "/options_robot.yaml", {}), OptionsError);
  std::ofstream(dir + "/options_robot.yaml") << "extends: options_robot.yaml\n";
  try {
    LoadOptions<TestOptions>(dir + "/options_robot.yaml", {});
    FAIL();
  } catch (const OptionsError& e) {
    EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace common
}  // namespace sarmap

#include "common/robot_config.h"

namespace sarmap {
namespace common {
namespace {

TEST(RobotConfigTest, ShippedConfigsLoadAndCameraLooksForward) {
  const auto robot = LoadRobot(std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml");
  // The optical axis (camera +z) points along base +x; camera +y (down) along base -z.
  const Rigid3d base_from_camera = robot.base_from_camera.ToRigid3d();
  EXPECT_NEAR((base_from_camera.rotation() * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 0, 1e-9);
  EXPECT_NEAR((base_from_camera.rotation() * Eigen::Vector3d::UnitY() + Eigen::Vector3d::UnitZ()).norm(), 0, 1e-9);
  for (const char* name : {"kinect", "respeaker4"}) {
    const auto array = LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/" + name + ".yaml");
    EXPECT_EQ(array.num_mics(), 4) << name;
  }
  EXPECT_THROW(LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/kinect.yaml",
                            {"channel_map=[0, 1]"}), OptionsError);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
