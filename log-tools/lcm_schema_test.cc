#include "log-tools/lcm_schema.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <regex>
#include <set>

#include "sarmap/message_registry.h"

namespace sarmap {
namespace logtools {
namespace {

LcmTypeSet ProjectTypes() {
  LcmTypeSet types;
  std::vector<std::string> errors;
  EXPECT_TRUE(types.AddDirectory(SARMAP_LCMTYPES_DIR, &errors));
  EXPECT_TRUE(types.Resolve(&errors));
  for (const auto& e : errors) ADD_FAILURE() << e;
  return types;
}

TEST(LcmSchemaTest, EveryProjectTypeHasTheFingerprintOfItsGeneratedClass) {
  const LcmTypeSet types = ProjectTypes();
  std::set<std::string> checked;
#define SARMAP_CHECK_FINGERPRINT(T)                                                     \
  {                                                                                     \
    const LcmStruct* s = types.Find("sarmap." #T);                                      \
    ASSERT_NE(s, nullptr) << #T;                                                        \
    EXPECT_EQ(s->fingerprint, static_cast<uint64_t>(sarmap::T::getHash())) << #T;       \
    EXPECT_EQ(types.FindByFingerprint(static_cast<uint64_t>(sarmap::T::getHash())), s); \
    checked.insert("sarmap." #T);                                                       \
  }
  SARMAP_FOR_EACH_LCM_TYPE(SARMAP_CHECK_FINGERPRINT)
#undef SARMAP_CHECK_FINGERPRINT
  // Every type the parser found is one lcm-gen generated, and the other way round.
  std::set<std::string> parsed;
  for (const auto& [name, s] : types.structs()) parsed.insert(name);
  EXPECT_EQ(parsed, checked);
  EXPECT_GE(checked.size(), 30u);
  EXPECT_TRUE(types.ambiguities().empty());
}

TEST(LcmSchemaTest, MinWireSizeCountsFixedPartsOnly) {
  const LcmTypeSet types = ProjectTypes();
  // header_t: utime, seq, an empty frame string (length + NUL).
  EXPECT_EQ(types.MinWireSize("sarmap.header_t"), 8u + 8u + 5u);
  // slam_anchor_t: two int64 and three doubles.
  EXPECT_EQ(types.MinWireSize("sarmap.slam_anchor_t"), 40u);
}

const char kTricky[] = R"(package xpkg;
/* a block comment
   over lines */
struct weird_t {
  int32_t a, b;        // KIND_*
  double m[a][3][b];
  string names[2];
  const int8_t KIND_X = 1, KIND_Y = -2;
  const double SCALE = 1.5e-3;
  byte this_is_a_very_long_member_name_that_goes_on_and_on_and_on_and_on_and_on_and_on_and_on_and_on_and_on_and_on_and_and_done;
  boolean flag;
  inner_t inner[a];
  xpkg.inner_t one;
}

struct inner_t
{
  int64_t n;
  float v[n];
}
)";

TEST(LcmSchemaTest, ParsesMemberListsConstantsAndMultiDimensionalArrays) {
  std::vector<LcmStruct> parsed;
  std::string error;
  ASSERT_TRUE(ParseLcm(kTricky, "weird.lcm", &parsed, &error)) << error;
  ASSERT_EQ(parsed.size(), 2u);
  const LcmStruct& w = parsed[0];
  EXPECT_EQ(w.full_name(), "xpkg.weird_t");
  ASSERT_EQ(w.members.size(), 8u);
  EXPECT_EQ(w.members[1].name, "b");
  EXPECT_EQ(w.members[1].comment, " KIND_*");
  const LcmMember& m = w.members[2];
  ASSERT_EQ(m.dims.size(), 3u);
  EXPECT_TRUE(m.dims[0].variable);
  EXPECT_EQ(m.dims[0].size, "a");
  EXPECT_FALSE(m.dims[1].variable);
  EXPECT_EQ(m.dims[1].size, "3");
  EXPECT_EQ(w.members[6].type, "xpkg.inner_t");
  EXPECT_EQ(w.members[7].type, "xpkg.inner_t");
  ASSERT_EQ(w.constants.size(), 3u);
  EXPECT_EQ(w.constants[1].name, "KIND_Y");
  EXPECT_EQ(w.constants[1].value, "-2");
}

// lcm-gen --debug prints each struct's own hash ("hash=0x" followed by it in decimal).
std::vector<int64_t> LcmGenBaseHashes(const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "/lcm_schema_test_" + std::to_string(getpid()) + ".lcm";
  std::ofstream(path) << text;
  FILE* pipe = popen((std::string(SARMAP_LCM_GEN) + " --debug " + path).c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof(buf), pipe)) out.append(buf, n);
  pclose(pipe);
  std::vector<int64_t> hashes;
  const std::regex hash_re(R"(\[hash=0x\s*(-?[0-9]+)\])");
  for (std::sregex_iterator it(out.begin(), out.end(), hash_re), end; it != end; ++it) {
    hashes.push_back(std::stoll((*it)[1]));
  }
  return hashes;
}

TEST(LcmSchemaTest, OwnHashIsLcmGensOnDeclarationsThatStressIt) {
  // A member name over 127 characters (lcm-gen hashes its length as a signed char), three
  // dimensions of both kinds, members declared in a list, struct members with and without
  // the package.
  std::vector<LcmStruct> parsed;
  std::string error;
  ASSERT_TRUE(ParseLcm(kTricky, "weird.lcm", &parsed, &error)) << error;
  const std::vector<int64_t> expected = LcmGenBaseHashes(kTricky);
  ASSERT_EQ(expected.size(), parsed.size()) << "lcm-gen --debug printed no hashes";
  for (size_t i = 0; i < parsed.size(); ++i) {
    EXPECT_EQ(LcmBaseHash(parsed[i]), expected[i]) << parsed[i].name;
  }
}

TEST(LcmSchemaTest, FingerprintOfNestedTypesAddsEachMemberAndRotates) {
  LcmTypeSet types;
  std::vector<std::string> errors;
  ASSERT_TRUE(types.AddText(kTricky, "weird.lcm", &errors));
  ASSERT_TRUE(types.Resolve(&errors));
  const LcmStruct* inner = types.Find("xpkg.inner_t");
  const LcmStruct* weird = types.Find("xpkg.weird_t");
  auto rotl = [](uint64_t h) { return (h << 1) + ((h >> 63) & 1); };
  EXPECT_EQ(inner->fingerprint, rotl(static_cast<uint64_t>(inner->base_hash)));
  // Two members of type inner_t: its fingerprint counts twice.
  EXPECT_EQ(weird->fingerprint,
            rotl(static_cast<uint64_t>(weird->base_hash) + 2 * inner->fingerprint));
}

TEST(LcmSchemaTest, TypesWithOneFingerprintAreReportedAndTheFirstIsUsed) {
  LcmTypeSet types;
  std::vector<std::string> errors;
  // The name of a type is not part of its fingerprint.
  ASSERT_TRUE(types.AddText("package p; struct b_t { int8_t x; } struct a_t { int8_t x; }",
                            "same.lcm", &errors));
  ASSERT_TRUE(types.Resolve(&errors));
  EXPECT_EQ(types.Find("p.a_t")->fingerprint, types.Find("p.b_t")->fingerprint);
  EXPECT_EQ(types.FindByFingerprint(types.Find("p.b_t")->fingerprint)->name, "a_t");
  ASSERT_EQ(types.ambiguities().size(), 1u);
  EXPECT_NE(types.ambiguities()[0].find("p.b_t has the same fingerprint as p.a_t"),
            std::string::npos);
}

TEST(LcmSchemaTest, TypeContainingItselfContributesZeroInsideItself) {
  LcmTypeSet types;
  std::vector<std::string> errors;
  ASSERT_TRUE(
      types.AddText("package p; struct node_t { int32_t n; node_t kids[n]; }", "n.lcm", &errors));
  ASSERT_TRUE(types.Resolve(&errors));
  const LcmStruct* node = types.Find("p.node_t");
  const uint64_t base = static_cast<uint64_t>(node->base_hash);
  EXPECT_EQ(node->fingerprint, (base << 1) + ((base >> 63) & 1));
  EXPECT_EQ(types.MinWireSize("p.node_t"), 4u);
}

struct BadCase {
  const char* text;
  const char* expected;  // part of the message
};

TEST(LcmSchemaTest, MistakesAreReportedWithFileAndLine) {
  const BadCase cases[] = {
      {"package p;\nstruct a_t {\n  int32_t x\n}", "bad.lcm:4: expected ';'"},
      {"package p;\nstruct a_t {\n  double v[n];\n}", "bad.lcm:3: unknown array size 'n'"},
      {"package p;\nstruct a_t {\n  double n;\n  double v[n];\n}",
       "bad.lcm:4: array size 'n' must be"},
      {"package p;\nstruct a_t {\n  int8_t x;\n  int8_t x;\n}",
       "bad.lcm:4: duplicate member name 'x'"},
      {"package p;\nstruct a_t {\n  const string S = 1;\n}", "bad.lcm:3: invalid type for const"},
      {"package p;\nstruct a_t {\n  const int8_t S = x1;\n}", "bad.lcm:3: invalid value"},
      {"package p;\nstruct a_t {\n  double v[0];\n}", "bad.lcm:3: constant array size"},
      {"package p;\nenum e_t { A, B }", "bad.lcm:2: enum is not supported"},
      {"package p;\nstruct a_t {\n  int8_t x;\n", "bad.lcm:3: missing '}'"},
      {"package p;\nstruct a_t { int8_t x; } /* open", "bad.lcm:2: unexpected character or open"},
      {"package p;\nstruct a_t {\n  int8_t x @;\n}", "bad.lcm:3: unexpected character"},
  };
  for (const auto& c : cases) {
    LcmTypeSet types;
    std::vector<std::string> errors;
    EXPECT_FALSE(types.AddText(c.text, "bad.lcm", &errors)) << c.text;
    ASSERT_EQ(errors.size(), 1u) << c.text;
    EXPECT_NE(errors[0].find(c.expected), std::string::npos) << errors[0];
  }
  LcmTypeSet types;
  std::vector<std::string> errors;
  ASSERT_TRUE(types.AddText("package p;\nstruct a_t {\n  b_t b;\n}", "bad.lcm", &errors));
  EXPECT_FALSE(types.Resolve(&errors));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("bad.lcm:3: unknown type p.b_t of p.a_t.b"), std::string::npos)
      << errors[0];
  // Two declarations of one type, and a directory without types.
  ASSERT_FALSE(types.AddText("package p;\nstruct a_t { int8_t y; }", "again.lcm", &errors));
  EXPECT_NE(errors.back().find("already declared in bad.lcm"), std::string::npos);
  EXPECT_FALSE(types.AddDirectory(::testing::TempDir() + "/no_such_dir_lcm", &errors));
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
