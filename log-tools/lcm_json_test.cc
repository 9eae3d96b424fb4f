#include "log-tools/lcm_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "common/wire_check.h"
#include "sarmap/message_registry.h"
#include "sarmap/message_samples.h"

namespace sarmap {
namespace logtools {
namespace {

using Json = nlohmann::ordered_json;

const LcmTypeSet& ProjectTypes() {
  static const LcmTypeSet* types = [] {
    auto* t = new LcmTypeSet;
    std::vector<std::string> errors;
    t->AddDirectory(SARMAP_LCMTYPES_DIR, &errors);
    t->Resolve(&errors);
    for (const auto& e : errors) ADD_FAILURE() << e;
    return t;
  }();
  return *types;
}

template <class T>
std::vector<uint8_t> Encode(const T& msg) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  EXPECT_EQ(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

LcmJsonResult Decode(const std::vector<uint8_t>& data, int64_t max_array = 0) {
  LcmJsonOptions options;
  options.max_array = max_array;
  return DecodeLcmToJson(ProjectTypes(), data.data(), data.size(), options);
}

// The test's own encoder of decoded JSON (arrays in full), written from the LCM encoding rules,
// so decoding and encoding again must give the generated class's bytes back.
void PutBigEndian(uint64_t v, int bytes, std::vector<uint8_t>* out) {
  for (int i = bytes - 1; i >= 0; --i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void EncodeStruct(const LcmStruct& s, const Json& j, std::vector<uint8_t>* out);

void EncodeScalar(const std::string& type, const Json& j, std::vector<uint8_t>* out) {
  if (type == "string") {
    const std::string v = j.get<std::string>();
    PutBigEndian(v.size() + 1, 4, out);
    out->insert(out->end(), v.begin(), v.end());
    out->push_back(0);
  } else if (type == "boolean") {
    out->push_back(j.get<bool>() ? 1 : 0);
  } else if (type == "float") {
    const float f = static_cast<float>(j.get<double>());
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    PutBigEndian(bits, 4, out);
  } else if (type == "double") {
    const double d = j.get<double>();
    uint64_t bits;
    std::memcpy(&bits, &d, 8);
    PutBigEndian(bits, 8, out);
  } else if (IsLcmPrimitive(type)) {
    PutBigEndian(static_cast<uint64_t>(j.get<int64_t>()), LcmPrimitiveBytes(type), out);
  } else {
    EncodeStruct(*ProjectTypes().Find(type), j, out);
  }
}

void EncodeArray(const LcmMember& m, size_t dim, const Json& j, std::vector<uint8_t>* out) {
  ASSERT_TRUE(j.is_array()) << m.name;
  for (const auto& item : j) {
    if (dim + 1 == m.dims.size()) {
      EncodeScalar(m.type, item, out);
    } else {
      EncodeArray(m, dim + 1, item, out);
    }
  }
}

void EncodeStruct(const LcmStruct& s, const Json& j, std::vector<uint8_t>* out) {
  for (const auto& m : s.members) {
    ASSERT_TRUE(j.contains(m.name)) << s.name << "." << m.name;
    if (m.dims.empty()) {
      EncodeScalar(m.type, j.at(m.name), out);
    } else {
      EncodeArray(m, 0, j.at(m.name), out);
    }
  }
}

TEST(LcmJsonTest, EveryProjectTypeDecodesToFieldsThatEncodeToTheSameBytes) {
  std::mt19937_64 rng(7);
  int types = 0;
#define SARMAP_ROUND_TRIP(T)                                              \
  for (int trial = 0; trial < 5; ++trial) {                               \
    sarmap::T msg;                                                        \
    sarmap::samples::Fill(msg, rng);                                      \
    const std::vector<uint8_t> bytes = Encode(msg);                       \
    const LcmJsonResult result = Decode(bytes);                           \
    ASSERT_TRUE(result.ok) << #T << ": " << result.error;                 \
    EXPECT_EQ(result.type, "sarmap." #T);                                 \
    EXPECT_EQ(result.trailing_bytes, 0u);                                 \
    std::vector<uint8_t> again(bytes.begin(), bytes.begin() + 8);         \
    EncodeStruct(*ProjectTypes().Find("sarmap." #T), result.msg, &again); \
    EXPECT_EQ(again, bytes) << #T << ": " << result.msg.dump();           \
    if (trial == 0) ++types;                                              \
  }
  SARMAP_FOR_EACH_LCM_TYPE(SARMAP_ROUND_TRIP)
#undef SARMAP_ROUND_TRIP
  EXPECT_EQ(types, static_cast<int>(ProjectTypes().structs().size()));
}

sarmap::people_detections_t TwoPeople() {
  sarmap::people_detections_t msg{};
  msg.header.utime = 1700000000123456;
  msg.header.seq = 42;
  msg.header.frame = "camera";
  msg.sensor_id = "kinect";
  msg.num_detections = 2;
  msg.detections.resize(2);
  for (int i = 0; i < 2; ++i) {
    auto& d = msg.detections[i];
    d.track_id = 10 + i;
    d.cue = i == 0 ? sarmap::person_detection_t::CUE_SEEN_RGBD
                   : sarmap::person_detection_t::CUE_SEEN_DEPTH;
    d.has_range = true;
    d.position_m[0] = 0.25 * (i + 1);
    d.position_m[1] = -0.5;
    d.position_m[2] = 3.1;
    d.position_covariance[4] = 0.01;
    d.azimuth_rad = -0.1;
    d.height_m = 1.7f;
    d.confidence = 0.1f;
    d.keyword = i == 0 ? "" : "help";
  }
  return msg;
}

TEST(LcmJsonTest, PeopleDetectionsReadAsTheirFields) {
  const LcmJsonResult r = Decode(Encode(TwoPeople()), 64);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.type, "sarmap.people_detections_t");
  const Json& m = r.msg;
  EXPECT_EQ(m["header"]["utime"], 1700000000123456);
  EXPECT_EQ(m["header"]["frame"], "camera");
  EXPECT_EQ(m["sensor_id"], "kinect");
  ASSERT_EQ(m["detections"].size(), 2u);
  const Json& d1 = m["detections"][1];
  EXPECT_EQ(d1["track_id"], 11);
  EXPECT_EQ(d1["cue"], 2);
  EXPECT_EQ(d1["cue_name"], "CUE_SEEN_DEPTH");  // from the member's comment "// CUE_*"
  EXPECT_EQ(m["detections"][0]["cue_name"], "CUE_SEEN_RGBD");
  EXPECT_EQ(d1["has_range"], true);
  EXPECT_EQ(d1["position_m"], Json::parse("[0.5, -0.5, 3.1]"));
  EXPECT_EQ(d1["position_covariance"][4], 0.01);
  EXPECT_EQ(d1["keyword"], "help");
  // Floats print with the digits that give the float back, not the double's.
  EXPECT_EQ(d1["height_m"].dump(), "1.7");
  EXPECT_EQ(d1["confidence"].dump(), "0.1");
  // Fields stay in declaration order.
  EXPECT_EQ(m.begin().key(), "header");
  const std::string line = EchoLine(2000000, 1500000, "PEOPLE_VISUAL", r, 0);
  EXPECT_EQ(line.find("{\"recv_utime\":2000000,\"t_s\":0.5,\"channel\":\"PEOPLE_VISUAL\","
                      "\"type\":\"sarmap.people_detections_t\",\"msg\":{\"header\""),
            0u)
      << line;
}

TEST(LcmJsonTest, BitSetsAreNamedByTheirConstants) {
  sarmap::people_map_t map{};
  map.num_people = 1;
  map.people.resize(1);
  map.people[0].cues = sarmap::mapped_person_t::CUE_SEEN_RGBD | sarmap::mapped_person_t::CUE_HEARD;
  map.people[0].keyword = "help";
  const LcmJsonResult r = Decode(Encode(map));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.msg["people"][0]["cues_name"], "CUE_SEEN_RGBD|CUE_HEARD");
  LcmJsonOptions plain;
  plain.constant_names = false;
  const auto bytes = Encode(map);
  const LcmJsonResult p = DecodeLcmToJson(ProjectTypes(), bytes.data(), bytes.size(), plain);
  EXPECT_FALSE(p.msg["people"][0].contains("cues_name"));
}

TEST(LcmJsonTest, LongArraysAreSummarisedAndNonFiniteNumbersNamed) {
  sarmap::image_t image{};
  image.width = 640;
  image.height = 480;
  image.size = 640 * 480 * 2;
  image.data.resize(image.size);
  for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i % 200 + 3);
  LcmJsonResult r = Decode(Encode(image), 64);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.msg["data"]["length"], 614400);
  EXPECT_EQ(r.msg["data"]["min"], 3);
  EXPECT_EQ(r.msg["data"]["max"], 202);
  EXPECT_EQ(r.msg["data"]["head"], Json::parse("[3, 4, 5, 6, 7, 8, 9, 10]"));
  EXPECT_EQ(r.msg["intrinsics"]["distortion"].size(), 5u);  // short arrays stay arrays

  sarmap::laser_scan_t scan{};
  scan.num_ranges = 100;
  scan.ranges_m.assign(100, 2.5f);
  scan.ranges_m[3] = std::numeric_limits<float>::infinity();
  scan.ranges_m[4] = std::numeric_limits<float>::quiet_NaN();
  scan.ranges_m[50] = 0.5f;
  r = Decode(Encode(scan), 0);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.msg["ranges_m"].size(), 100u);
  EXPECT_EQ(r.msg["ranges_m"][3], "inf");
  EXPECT_EQ(r.msg["ranges_m"][4], "nan");
  r = Decode(Encode(scan), 10);
  EXPECT_EQ(r.msg["ranges_m"]["length"], 100);
  EXPECT_EQ(r.msg["ranges_m"]["min"], 0.5);  // NaN and inf are no minimum/maximum of numbers
  EXPECT_EQ(r.msg["ranges_m"]["max"], 2.5);
  EXPECT_EQ(r.msg["ranges_m"]["head"][3], "inf");
}

TEST(LcmJsonTest, TwoDimensionalVariableArraysNestRowByRow) {
  sarmap::slam_anchors_t a{};
  a.num_anchors = 1;
  a.anchors.resize(1);
  a.anchors[0].node_id = 7;
  a.covariance_dim = 6;
  a.covariance.assign(6, std::vector<double>(6, 0.0));
  for (int i = 0; i < 6; ++i) a.covariance[i][i] = i + 1;
  a.covariance[1][4] = -3;
  const LcmJsonResult r = Decode(Encode(a));
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.msg["covariance"].size(), 6u);
  EXPECT_EQ(r.msg["covariance"][5][5], 6);
  EXPECT_EQ(r.msg["covariance"][1][4], -3);
  EXPECT_EQ(r.msg["anchors"][0]["node_id"], 7);
}

// Bytes of a message, and where one field sits in it.
std::vector<uint8_t> WithInt32At(std::vector<uint8_t> bytes, size_t offset, int32_t v) {
  for (int i = 0; i < 4; ++i)
    bytes[offset + i] = static_cast<uint8_t>(static_cast<uint32_t>(v) >> (24 - 8 * i));
  return bytes;
}

TEST(LcmJsonTest, EveryTruncationIsAnErrorNamingTheField) {
  const std::vector<uint8_t> bytes = Encode(TwoPeople());
  for (size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + n);
    const LcmJsonResult r = Decode(cut);
    EXPECT_FALSE(r.ok) << n;
    EXPECT_FALSE(r.error.empty()) << n;
  }
  const LcmJsonResult r = Decode(std::vector<uint8_t>(bytes.begin(), bytes.end() - 3));
  EXPECT_EQ(r.type, "sarmap.people_detections_t");
  EXPECT_NE(r.error.find("detections[1].keyword"), std::string::npos) << r.error;
  // Bytes after the message are reported, the message still read.
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  const LcmJsonResult l = Decode(longer);
  EXPECT_TRUE(l.ok);
  EXPECT_EQ(l.trailing_bytes, 1u);
}

TEST(LcmJsonTest, HostileLengthsAndCountsAreRefusedBeforeAllocating) {
  const std::vector<uint8_t> bytes = Encode(TwoPeople());
  // Layout: fingerprint 8, header.utime 8, header.seq 8, header.frame length at 24.
  const size_t frame_length_at = 24;
  const size_t sensor_length_at = frame_length_at + 4 + 7;  // "camera" + NUL
  const size_t count_at = sensor_length_at + 4 + 7;         // "kinect" + NUL
  struct Case {
    size_t offset;
    int32_t value;
    const char* expected;
  };
  const Case cases[] = {
      {frame_length_at, -5, "header.frame: string length -5 is not positive"},
      {frame_length_at, 0, "header.frame: string length 0 is not positive"},
      {frame_length_at, INT32_MAX, "header.frame: string length 2147483647 >"},
      {count_at, -1, "detections: count -1 (num_detections) is negative"},
      {count_at, INT32_MAX, "detections: count 2147483647 (num_detections) needs at least"},
      {count_at, 1000, "detections: count 1000 (num_detections) needs at least"},
  };
  for (const auto& c : cases) {
    const LcmJsonResult r = Decode(WithInt32At(bytes, c.offset, c.value));
    EXPECT_FALSE(r.ok) << c.expected;
    EXPECT_EQ(r.error.find(c.expected), 0u) << r.error;
  }
  std::vector<uint8_t> unknown = bytes;
  unknown[0] ^= 0xff;
  const LcmJsonResult u = Decode(unknown);
  EXPECT_FALSE(u.ok);
  EXPECT_EQ(u.error.find("unknown type (fingerprint 0x"), 0u) << u.error;
  EXPECT_TRUE(u.type.empty());
  EXPECT_NE(Decode({1, 2, 3}).error.find("no 8-byte fingerprint"), std::string::npos);
}

TEST(LcmJsonTest, RandomDamageNeverCrashes) {
  const std::vector<uint8_t> good = Encode(TwoPeople());
  std::mt19937_64 rng(3);
  int decoded = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<uint8_t> bytes = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f)
      bytes[8 + rng() % (bytes.size() - 8)] = static_cast<uint8_t>(rng());
    const LcmJsonResult r = Decode(bytes, 16);
    if (r.ok) {
      ++decoded;
      EXPECT_NO_THROW(EchoLine(0, 0, "X", r, bytes.size()));
    } else {
      EXPECT_FALSE(r.error.empty());
    }
  }
  EXPECT_GT(decoded, 0);  // flips in numbers decode, flips in lengths do not
}

// One random change of the kinds that break decoders: flipped bytes, a length or count field
// overwritten with an extreme value, a cut, bytes appended.
void Mutate(std::vector<uint8_t>* bytes, std::mt19937_64& rng) {
  const size_t body = bytes->size() - 8;
  switch (rng() % 4) {
    case 0:
      for (int f = 1 + static_cast<int>(rng() % 3); f > 0; --f) {
        (*bytes)[8 + rng() % body] = static_cast<uint8_t>(rng());
      }
      break;
    case 1: {
      if (body < 4) break;
      const int32_t extremes[] = {-1, 0, 1, 3, 1000, 65536, INT32_MAX, INT32_MIN};
      const uint32_t v = static_cast<uint32_t>(extremes[rng() % 8]);
      const size_t at = 8 + rng() % (body - 3);
      for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
      break;
    }
    case 2:
      bytes->resize(8 + rng() % body);
      break;
    default:
      bytes->push_back(static_cast<uint8_t>(rng()));
  }
}

TEST(LcmJsonTest, AgreesWithTheNodesWireCheckOnDamagedMessagesOfEveryType) {
  // What a node's wire check accepts decodes here to the last byte; what fails here, the wire
  // check refuses. The wire check refuses more: strings not ending with their one NUL (they
  // print here as they are, and echo's "refused" says so).
  std::mt19937_64 rng(11);
  int accepted = 0, refused_here = 0, nul_only = 0;
#define SARMAP_AGREE(T)                                                                          \
  for (int trial = 0; trial < 400; ++trial) {                                                    \
    sarmap::T msg;                                                                               \
    sarmap::samples::Fill(msg, rng);                                                             \
    std::vector<uint8_t> bytes = Encode(msg);                                                    \
    Mutate(&bytes, rng);                                                                         \
    std::string why;                                                                             \
    const bool wire_ok = sarmap::common::CheckWire<sarmap::T>(bytes.data(), bytes.size(), &why); \
    const LcmJsonResult r = Decode(bytes, 16);                                                   \
    const bool here_ok = r.ok && r.trailing_bytes == 0;                                          \
    if (wire_ok) {                                                                               \
      ++accepted;                                                                                \
      EXPECT_TRUE(here_ok) << #T << ": " << r.error;                                             \
    } else if (here_ok) {                                                                        \
      ++nul_only;                                                                                \
      EXPECT_NE(why.find("NUL"), std::string::npos) << #T << ": " << why;                        \
    }                                                                                            \
    if (!r.ok) {                                                                                 \
      ++refused_here;                                                                            \
      EXPECT_FALSE(wire_ok) << #T;                                                               \
      EXPECT_FALSE(r.error.empty());                                                             \
    }                                                                                            \
  }
  SARMAP_FOR_EACH_LCM_TYPE(SARMAP_AGREE)
#undef SARMAP_AGREE
  // Both outcomes occur often enough for the agreement to mean something.
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(refused_here, 1000);
  RecordProperty("accepted", accepted);
  RecordProperty("refused", refused_here);
  RecordProperty("nul_only", nul_only);
}

TEST(LcmJsonTest, StringsThatAreNotUtf8StillPrint) {
  sarmap::people_detections_t msg = TwoPeople();
  msg.sensor_id = std::string("cam\xff\xfe", 5);
  const LcmJsonResult r = Decode(Encode(msg));
  ASSERT_TRUE(r.ok);
  std::string line;
  ASSERT_NO_THROW(line = EchoLine(0, 0, "PEOPLE_VISUAL", r, 0));
  EXPECT_NE(line.find("\"sensor_id\":\"cam\xef\xbf\xbd\xef\xbf\xbd\""), std::string::npos) << line;
}

TEST(LcmJsonTest, SelfNestingIsBoundedInDepth) {
  LcmTypeSet types;
  std::vector<std::string> errors;
  ASSERT_TRUE(
      types.AddText("package p; struct node_t { int32_t n; node_t kids[n]; }", "n.lcm", &errors));
  ASSERT_TRUE(types.Resolve(&errors));
  std::vector<uint8_t> bytes;
  PutBigEndian(types.Find("p.node_t")->fingerprint, 8, &bytes);
  for (int level = 0; level < 1000; ++level) PutBigEndian(1, 4, &bytes);  // one kid each
  PutBigEndian(0, 4, &bytes);
  const LcmJsonResult r = DecodeLcmToJson(types, bytes.data(), bytes.size());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("nested deeper than 64"), std::string::npos) << r.error;
  // Shallow nesting decodes.
  bytes.resize(8);
  PutBigEndian(1, 4, &bytes);
  PutBigEndian(0, 4, &bytes);
  const LcmJsonResult ok = DecodeLcmToJson(types, bytes.data(), bytes.size());
  ASSERT_TRUE(ok.ok) << ok.error;
  EXPECT_EQ(ok.msg.dump(), R"({"n":1,"kids":[{"n":0,"kids":[]}]})");
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
