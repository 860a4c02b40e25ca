// DumpYaml and ToJson: complete, commented, and exact under a round trip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "config_test_util.h"
#include "rvlio/config/config.h"
#include "rvlio/config/config_json.h"
#include "rvlio/sim/options.h"

namespace rvlio {
namespace {

using test::TempDir;
using test::ToyOptions;

std::string JsonPointer(std::string key) {
  std::replace(key.begin(), key.end(), '.', '/');
  return "/" + key;
}

// Counts the leaves (non-object values) of a JSON object.
size_t CountLeaves(const nlohmann::json& j) {
  if (!j.is_object()) return 1;
  size_t n = 0;
  for (const auto& item : j) n += CountLeaves(item);
  return n;
}

// Sets every field to a random value of its type: numbers over many orders of
// magnitude (not limited to the valid range: dumping must not care), strings
// with YAML's special characters, choices picked among the allowed ones.
class Randomizer {
 public:
  explicit Randomizer(uint32_t seed) : rng_(seed) {}
  void Field(const char*, bool& v, const Spec&) { v = Coin(); }
  void Field(const char*, int& v, const Spec&) {
    v = std::uniform_int_distribution<int>(std::numeric_limits<int>::min(),
                                           std::numeric_limits<int>::max())(rng_);
  }
  void Field(const char*, int64_t& v, const Spec&) {
    v = std::uniform_int_distribution<int64_t>(std::numeric_limits<int64_t>::min(),
                                               std::numeric_limits<int64_t>::max())(rng_);
  }
  void Field(const char*, double& v, const Spec&) { v = Number(); }
  template <size_t N>
  void Field(const char*, std::array<double, N>& v, const Spec&) {
    for (double& x : v) x = Number();
  }
  void Field(const char*, std::string& v, const Spec& spec) {
    if (!spec.choices.empty()) {
      v = spec.choices[std::uniform_int_distribution<size_t>(0, spec.choices.size() - 1)(rng_)];
      return;
    }
    static const std::vector<std::string> kPieces = {
        "a",  "Z",  "_",  "/", ".", "-", " ",   ":",    ": ",   "#",  " #",       "'",   "\"",
        "\\", "\n", "\t", "[", "]", "{", "}",   ",",    "&",    "*",  "!",        "|",   ">",
        "%",  "@",  "`",  "?", "~", "0", "1.5", "true", "null", "no", "\xc3\xa9", "\x01"};
    const int n = std::uniform_int_distribution<int>(0, 6)(rng_);
    v.clear();
    for (int i = 0; i < n; ++i)
      v += kPieces[std::uniform_int_distribution<size_t>(0, kPieces.size() - 1)(rng_)];
  }
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  void Field(const char*, E& v, const Spec& spec) {
    const std::string name =
        spec.choices[std::uniform_int_distribution<size_t>(0, spec.choices.size() - 1)(rng_)];
    ASSERT_TRUE(ParseEnum(name, &v)) << name;
  }
  template <class Sub>
  void Section(const char*, Sub& sub) {
    sub.Visit(*this);
  }

 private:
  bool Coin() { return std::uniform_int_distribution<int>(0, 1)(rng_) == 1; }
  double Number() {
    switch (std::uniform_int_distribution<int>(0, 5)(rng_)) {
      case 0:
        return std::uniform_int_distribution<int>(-1000, 1000)(rng_);  // integral values
      case 1:
        return std::uniform_int_distribution<int>(-1000, 1000)(rng_) / 100.0;
      case 2:
        return std::numeric_limits<double>::denorm_min() * (Coin() ? 1 : 7);
      case 3:
        return (Coin() ? -1 : 1) * std::numeric_limits<double>::max();
      default: {
        const double mantissa = std::uniform_real_distribution<double>(-10.0, 10.0)(rng_);
        return mantissa * std::pow(10.0, std::uniform_int_distribution<int>(-30, 30)(rng_));
      }
    }
  }
  std::mt19937 rng_;
};

template <class Opts>
Opts RandomOptions(uint32_t seed) {
  Opts o;
  Randomizer r(seed);
  o.Visit(r);
  return o;
}

TEST(ConfigJson, ContainsEveryKeyWithItsValue) {
  Configuration o;
  o.rv.eps0 = 0.42;
  o.imu.topic = "/x";
  o.extrinsics.imu_T_lidar.translation = {1.0, 2.0, 3.0};
  const nlohmann::json j = ToJson(o);
  const std::vector<std::string> keys = ListKeys(o);
  for (const auto& key : keys) {
    const nlohmann::json::json_pointer p(JsonPointer(key));
    ASSERT_TRUE(j.contains(p)) << key;
    EXPECT_FALSE(j.at(p).is_object()) << key;
  }
  EXPECT_EQ(CountLeaves(j), keys.size());
  EXPECT_EQ(j["rv"]["eps0"], 0.42);
  EXPECT_TRUE(j["rv"]["enabled"].is_boolean());
  EXPECT_TRUE(j["rv"]["max_iterations"].is_number_integer());
  EXPECT_EQ(j["imu"]["topic"], "/x");
  EXPECT_EQ(j["extrinsics"]["imu_T_lidar"]["translation"], nlohmann::json({1.0, 2.0, 3.0}));
  EXPECT_EQ(j["backend"], "ieskf");
}

TEST(ConfigJson, NonFiniteNumbersBecomeNull) {
  ToyOptions t;
  t.rate = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(ToJson(t)["rate"].is_null());
}

TEST(ConfigDump, HasEveryKeyWithUnitsAndHelpAsComments) {
  const std::string text = DumpYaml(Configuration{});
  // Every key appears as "name:" under its section: count the leaf lines.
  size_t value_lines = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const size_t colon = line.find(':');
    if (colon != std::string::npos && colon + 1 < line.size()) ++value_lines;
  }
  EXPECT_EQ(value_lines, ListKeys(Configuration{}).size());
  EXPECT_NE(text.find("  min_range: 0.5"), std::string::npos) << text;
  EXPECT_NE(text.find("# [m] minimum point range"), std::string::npos) << text;
  EXPECT_NE(text.find("backend: ieskf"), std::string::npos);
  EXPECT_NE(text.find("ieskf | smoother"), std::string::npos);
  EXPECT_NE(text.find("  imu_T_lidar:\n    translation: [0.0, 0.0, 0.0]"), std::string::npos);
}

TEST(ConfigDump, NumbersAreShortAndReadAsFloats) {
  ToyOptions t;
  struct Case {
    double value;
    const char* text;
  };
  for (const Case& c : {Case{100.0, "100.0"}, Case{0.1, "0.1"}, Case{7.9e-5, "7.9e-05"},
                        Case{1.0e-5, "1.0e-05"}, Case{695.07, "695.07"}, Case{1e300, "1.0e+300"},
                        Case{-2.5, "-2.5"}, Case{12345678.9, "12345678.9"}}) {
    t.rate = c.value;
    const std::string text = DumpYaml(t);
    EXPECT_NE(text.find(std::string("rate: ") + c.text + " "), std::string::npos) << c.value << "\n"
                                                                                  << text;
  }
}

TEST(ConfigDump, NonFiniteNumbersRoundTrip) {
  ToyOptions t;
  t.rate = -std::numeric_limits<double>::infinity();
  t.inner.xy = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()};
  ToyOptions back;
  ASSERT_TRUE(ApplyYamlText(back, DumpYaml(t), "dump").ok());
  EXPECT_EQ(back.rate, t.rate);
  EXPECT_TRUE(std::isnan(back.inner.xy[0]));
  EXPECT_EQ(back.inner.xy[1], t.inner.xy[1]);
}

// Property: DumpYaml -> ApplyYamlText restores every field bit for bit, over
// random options (200 seeds each for the odometry and the toy struct).
TEST(ConfigDump, RoundTripRestoresRandomOptionsExactly) {
  for (uint32_t seed = 1; seed <= 200; ++seed) {
    const Configuration original = RandomOptions<Configuration>(seed);
    const std::string text = DumpYaml(original);
    Configuration back;
    Status s = ApplyYamlText(back, text, "dump");
    ASSERT_TRUE(s.ok()) << "seed " << seed << ": " << s.message() << "\n" << text;
    ASSERT_EQ(ToJson(back), ToJson(original)) << "seed " << seed << "\n" << text;
    ASSERT_EQ(DumpYaml(back), text) << "seed " << seed;

    const ToyOptions toy = RandomOptions<ToyOptions>(seed);
    ToyOptions toy_back;
    ASSERT_TRUE(ApplyYamlText(toy_back, DumpYaml(toy), "dump").ok()) << DumpYaml(toy);
    ASSERT_EQ(ToJson(toy_back), ToJson(toy)) << "seed " << seed << "\n" << DumpYaml(toy);
  }
}

// The simulator's options go through the same templates.
TEST(ConfigDump, SimOptionsRoundTripAndLoad) {
  for (uint32_t seed = 1; seed <= 50; ++seed) {
    const SimOptions original = RandomOptions<SimOptions>(seed);
    SimOptions back;
    Status s = ApplyYamlText(back, DumpYaml(original), "dump");
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(ToJson(back), ToJson(original)) << "seed " << seed;
  }
  const SimOptions defaults;
  const nlohmann::json j = ToJson(defaults);
  for (const auto& key : ListKeys(defaults))
    EXPECT_TRUE(j.contains(nlohmann::json::json_pointer(JsonPointer(key)))) << key;
  StatusOr<SimOptions> r = LoadOptions<SimOptions>({}, {"seed=5"});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->seed, 5);
  EXPECT_TRUE(test::IsConfigError(LoadOptions<SimOptions>({}, {"sed=5"}).status(),
                                  {"sed: unknown key in --set", "did you mean seed?"}));
}

TEST(ConfigDump, RoundTripThroughAFileOfTheResolvedConfig) {
  TempDir dir;
  StatusOr<Configuration> r =
      LoadConfig({std::string(RVLIO_SOURCE_DIR) + "/config/paper_sim.yaml"},
                 {"extrinsics.imu_T_lidar.translation=[0.1,0,0.05]", "lidar.topic=/a b:#c"});
  ASSERT_TRUE(r.ok()) << r.status().message();
  const std::string path = dir.Write("resolved.yaml", DumpYaml(*r));
  StatusOr<Configuration> back = LoadConfig({path}, {});
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(ToJson(*back), ToJson(*r));
  EXPECT_EQ(back->lidar.topic, "/a b:#c");
}

}  // namespace
}  // namespace rvlio
