// Loading order, value parsing and every error class of config/config.h.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "config_test_util.h"
#include "rvlio/config/config.h"
#include "rvlio/config/config_json.h"

namespace rvlio {
namespace {

using test::IsConfigError;
using test::TempDir;
using test::ToyOptions;

// ---------------------------------------------------------------------------
// Precedence and merging.

TEST(ConfigLoad, NoFilesGivesBuiltInDefaults) {
  StatusOr<Configuration> r = LoadConfig({}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(ToJson(*r), ToJson(Configuration{}));
}

TEST(ConfigLoad, LaterFileWinsAndPartialSectionsKeepOtherKeys) {
  TempDir dir;
  const std::string a =
      dir.Write("a.yaml", "rv:\n  eps0: 0.3\n  k0: 2.0\nlidar:\n  max_range: 50\n");
  const std::string b = dir.Write("b.yaml", "rv:\n  eps0: 0.4\n");
  ConfigSources sources;
  StatusOr<Configuration> r = LoadOptions<Configuration>({a, b}, {}, &sources);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.eps0, 0.4);  // b wins
  EXPECT_EQ(r->rv.k0, 2.0);    // only in a
  EXPECT_EQ(r->lidar.max_range, 50.0);
  const Configuration d;
  EXPECT_EQ(r->rv.eps1, d.rv.eps1);  // untouched keys keep defaults
  EXPECT_EQ(r->lidar.min_range, d.lidar.min_range);
  EXPECT_EQ(r->lidar.topic, d.lidar.topic);
  EXPECT_EQ(sources.at("rv.eps0"), b + ":2");
  EXPECT_EQ(sources.at("rv.k0"), a + ":3");
  EXPECT_EQ(sources.count("rv.eps1"), 0u);

  // The other order gives the other value.
  StatusOr<Configuration> r2 = LoadConfig({b, a}, {});
  ASSERT_TRUE(r2.ok());
  EXPECT_EQ(r2->rv.eps0, 0.3);
}

TEST(ConfigLoad, SetWinsOverFilesAndLastSetWins) {
  TempDir dir;
  const std::string a = dir.Write("a.yaml", "rv: {eps0: 0.3, enabled: true}\nbackend: ieskf\n");
  ConfigSources sources;
  StatusOr<Configuration> r = LoadOptions<Configuration>(
      {a}, {"rv.eps0=0.45", "rv.enabled=false", "backend=smoother", "rv.eps0=0.6"}, &sources);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.eps0, 0.6);
  EXPECT_FALSE(r->rv.enabled);
  EXPECT_EQ(r->backend, "smoother");
  EXPECT_EQ(sources.at("rv.eps0"), "--set");
}

TEST(ConfigLoad, NestedKeysAndArrays) {
  TempDir dir;
  const std::string a = dir.Write("a.yaml",
                                  "extrinsics:\n"
                                  "  imu_T_lidar:\n"
                                  "    translation: [0.1, -0.2, 0.3]\n"
                                  "    rotation_xyzw:\n"
                                  "      - 0\n"
                                  "      - 0\n"
                                  "      - 0.7071067811865476\n"
                                  "      - 0.7071067811865476\n");
  StatusOr<Configuration> r =
      LoadConfig({a}, {"extrinsics.imu_T_lidar.translation=[0.1,0,0.05]"});
  ASSERT_TRUE(r.ok()) << r.status().message();
  const auto& e = r->extrinsics.imu_T_lidar;
  EXPECT_EQ(e.translation, (std::array<double, 3>{0.1, 0.0, 0.05}));
  EXPECT_EQ(e.rotation_xyzw, (std::array<double, 4>{0, 0, 0.7071067811865476, 0.7071067811865476}));
}

TEST(ConfigLoad, SetAcceptsAFlowMappingForASection) {
  StatusOr<Configuration> r = LoadConfig({}, {"rv={eps0: 0.35, k0: 3}"});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.eps0, 0.35);
  EXPECT_EQ(r->rv.k0, 3.0);
}

TEST(ConfigLoad, EmptyFilesCommentsAndEmptySectionsChangeNothing) {
  TempDir dir;
  const std::string empty = dir.Write("empty.yaml", "");
  const std::string comments = dir.Write("comments.yaml", "# nothing here\n\n");
  const std::string bare = dir.Write("bare.yaml", "rv:\nlidar:\n");
  StatusOr<Configuration> r = LoadConfig({empty, comments, bare}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(ToJson(*r), ToJson(Configuration{}));
}

TEST(ConfigLoad, StringsKeepTheirTextAndQuotedValues) {
  TempDir dir;
  const std::string a =
      dir.Write("a.yaml", "lidar:\n  topic: \"/a b: c # d\"\nimu:\n  topic: 123\n");
  StatusOr<Configuration> r = LoadConfig({a}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->lidar.topic, "/a b: c # d");
  EXPECT_EQ(r->imu.topic, "123");  // a string key takes any scalar as text
  StatusOr<Configuration> s = LoadConfig({}, {"lidar.topic='x: y'", "imu.topic=/imu"});
  ASSERT_TRUE(s.ok()) << s.status().message();
  EXPECT_EQ(s->lidar.topic, "x: y");
  EXPECT_EQ(s->imu.topic, "/imu");
}

TEST(ConfigLoad, NumbersInYamlSpellings) {
  Configuration o;
  struct Case {
    const char* text;
    double value;
  };
  for (const Case& c : {Case{"1", 1.0}, Case{"-2.5e-3", -2.5e-3}, Case{".5", 0.5}, Case{"1.", 1.0},
                        Case{"+3.25", 3.25}, Case{"7.9E-5", 7.9e-5}, Case{"1e2", 100.0}}) {
    ASSERT_TRUE(ApplyOverride(o, std::string("rv.k0=") + c.text).ok()) << c.text;
    EXPECT_EQ(o.rv.k0, c.value) << c.text;
  }
  ASSERT_TRUE(ApplyOverride(o, "lidar.max_range=.inf").ok());
  EXPECT_TRUE(std::isinf(o.lidar.max_range));
}

TEST(ConfigLoad, FailedApplyLeavesOptionsUntouched) {
  TempDir dir;
  // The first key is valid, the second is not: nothing may be applied.
  const std::string bad = dir.Write("bad.yaml", "rv:\n  eps0: 0.2\n  k0: abc\n");
  Configuration o;
  EXPECT_FALSE(ApplyYamlFile(o, bad).ok());
  EXPECT_EQ(ToJson(o), ToJson(Configuration{}));
  EXPECT_FALSE(ApplyOverride(o, "rv={eps0: 0.2, nope: 1}").ok());
  EXPECT_EQ(o.rv.eps0, Configuration{}.rv.eps0);
}

// ---------------------------------------------------------------------------
// Error classes: each names the key and the file (or --set).

TEST(ConfigErrors, UnknownKeySuggestsTheClosestKnownKey) {
  TempDir dir;
  const std::string f = dir.Write("foo.yaml", "rv:\n  eps1: 0.05\n  epss0: 0.3\n");
  Status s = LoadConfig({f}, {}).status();
  EXPECT_TRUE(
      IsConfigError(s, {"rv.epss0: unknown key in " + f + ":3", "(did you mean rv.eps0?)"}));

  // Right name, wrong section.
  const std::string g = dir.Write("g.yaml", "lidar:\n  gravity: 9.8\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({g}, {}).status(),
                            {"lidar.gravity: unknown key in " + g, "did you mean imu.gravity?"}));

  // Nothing close: no suggestion.
  const std::string h = dir.Write("h.yaml", "frobnicate: 1\n");
  Status sh = LoadConfig({h}, {}).status();
  EXPECT_TRUE(IsConfigError(sh, {"frobnicate: unknown key in " + h + ":1"}));
  EXPECT_EQ(sh.message().find("did you mean"), std::string::npos) << sh.message();

  // A shortened name: the only key of the section that it begins.
  EXPECT_TRUE(IsConfigError(
      LoadConfig({}, {"smoother.window=3"}).status(),
      {"smoother.window: unknown key in --set", "did you mean smoother.window_size?"}));
  // Ambiguous prefix (gyro_noise_density, gyro_bias_random_walk): no guess.
  Status amb = LoadConfig({}, {"imu.gyro=1"}).status();
  EXPECT_TRUE(IsConfigError(amb, {"imu.gyro: unknown key in --set"}));
  EXPECT_EQ(amb.message().find("did you mean"), std::string::npos) << amb.message();

  // An unknown section is reported at its own name.
  const std::string k = dir.Write("k.yaml", "rvv:\n  eps0: 0.3\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({k}, {}).status(),
                            {"rvv: unknown key in " + k + ":1", "did you mean rv?"}));
}

TEST(ConfigErrors, UnknownKeyInSet) {
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.epss0=1"}).status(),
                            {"rv.epss0: unknown key in --set", "did you mean rv.eps0?"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.eps0.x=1"}).status(),
                            {"rv.eps0 in --set", "expected a number, got a mapping"}));
}

TEST(ConfigErrors, SetWithoutEqualsOrWithABadKey) {
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.eps0"}).status(),
                            {"--set 'rv.eps0'", "expected KEY=VALUE"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"=3"}).status(), {"--set '=3'", "expected KEY=VALUE"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv..eps0=3"}).status(),
                            {"--set 'rv..eps0=3'", "malformed key"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.eps0=[1, 2"}).status(),
                            {"rv.eps0 in --set: cannot parse value '[1, 2'"}));
}

TEST(ConfigErrors, WrongTypeNamesKeyFileAndValue) {
  TempDir dir;
  const std::string f = dir.Write("foo.yaml", "rv:\n  eps0: abc\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({f}, {}).status(),
                            {"rv.eps0 in " + f + ":2: expected a number, got 'abc'"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.eps0=abc"}).status(),
                            {"rv.eps0 in --set: expected a number, got 'abc'"}));
  const std::string g = dir.Write("g.yaml", "rv:\n  eps0:\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({g}, {}).status(),
                            {"rv.eps0 in " + g + ":2: expected a number, got an empty value"}));
  const std::string h = dir.Write("h.yaml", "rv:\n  eps0: [1]\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({h}, {}).status(), {"rv.eps0 in " + h, "got a list"}));
  const std::string k = dir.Write("k.yaml", "rv: 3\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({k}, {}).status(),
                            {"rv in " + k + ":1: expected a section of keys, got '3'"}));
  const std::string m = dir.Write("m.yaml", "lidar:\n  topic: [a, b]\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({m}, {}).status(),
                            {"lidar.topic in " + m + ":2: expected a string, got a list"}));
}

TEST(ConfigErrors, NumbersRejectNonDecimalText) {
  for (const char* bad : {"1,5", "0x10", "inf", "nan", "1e", "--1", "1.2.3", "e3", "true", "''"}) {
    EXPECT_TRUE(IsConfigError(LoadConfig({}, {std::string("rv.k0=") + bad}).status(),
                              {"rv.k0 in --set: expected a number"}))
        << bad;
  }
}

TEST(ConfigErrors, IntegersRejectFractionsAndOtherText) {
  for (const char* bad : {"1.5", "1e3", "0x10", "2.0", "abc", "true", "[1]"}) {
    EXPECT_TRUE(IsConfigError(LoadConfig({}, {std::string("rv.max_iterations=") + bad}).status(),
                              {"rv.max_iterations in --set: expected an integer"}))
        << bad;
  }
  // Beyond the range of int: a type error, not a silent wrap-around.
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.max_iterations=4294967297"}).status(),
                            {"rv.max_iterations in --set: expected an integer in [-2147483648"}));
  StatusOr<Configuration> r = LoadConfig({}, {"rv.max_iterations=+7"});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.max_iterations, 7);
}

TEST(ConfigErrors, BoolsAcceptOnlyTrueAndFalse) {
  for (const char* bad : {"yes", "no", "on", "1", "0", "t", "'maybe'"}) {
    EXPECT_TRUE(IsConfigError(LoadConfig({}, {std::string("rv.repair=") + bad}).status(),
                              {"rv.repair in --set: expected true or false"}))
        << bad;
  }
  for (const char* t : {"true", "True", "TRUE"}) {
    StatusOr<Configuration> r =
        LoadConfig({}, {"rv.repair=false", std::string("rv.repair=") + t});
    ASSERT_TRUE(r.ok()) << t;
    EXPECT_TRUE(r->rv.repair);
  }
}

TEST(ConfigErrors, ArraysNeedExactlyNNumbers) {
  TempDir dir;
  const std::string f =
      dir.Write("foo.yaml", "extrinsics:\n  imu_T_lidar:\n    translation: [1, 2]\n");
  EXPECT_TRUE(IsConfigError(
      LoadConfig({f}, {}).status(),
      {"extrinsics.imu_T_lidar.translation in " + f + ":3: expected a list of 3 numbers, got 2"}));
  EXPECT_TRUE(IsConfigError(
      LoadConfig({}, {"extrinsics.imu_T_lidar.translation=[1,2,3,4]"}).status(),
      {"extrinsics.imu_T_lidar.translation in --set: expected a list of 3 numbers, got 4"}));
  EXPECT_TRUE(IsConfigError(
      LoadConfig({}, {"extrinsics.imu_T_lidar.translation=[1,x,3]"}).status(),
      {"extrinsics.imu_T_lidar.translation[1] in --set: expected a number, got 'x'"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"extrinsics.imu_T_lidar.translation=1"}).status(),
                            {"expected a list of 3 numbers, got '1'"}));
}

TEST(ConfigErrors, OutOfRangeIsPrefixedWithItsSource) {
  TempDir dir;
  const std::string f = dir.Write("foo.yaml", "# comment\nrv:\n  eps0: 2\n");
  EXPECT_TRUE(
      IsConfigError(LoadConfig({f}, {}).status(), {f + ":3: rv.eps0 = 2 is out of range [0, 1]"}));
  EXPECT_TRUE(IsConfigError(LoadConfig({f}, {"rv.eps0=-1"}).status(),
                            {"--set: rv.eps0 = -1 is out of range"}));
  // Integer range, exclusive minimum, array element.
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.max_iterations=0"}).status(),
                            {"--set: rv.max_iterations = 0 is out of range [1, 100]"}));
  EXPECT_TRUE(
      IsConfigError(LoadConfig({}, {"rv.k0=0"}).status(), {"--set: rv.k0 = 0 is out of range (0"}));
  const std::string g =
      dir.Write("g.yaml", "extrinsics:\n  imu_T_lidar:\n    rotation_xyzw: [2, 0, 0, 1]\n");
  EXPECT_TRUE(
      IsConfigError(LoadConfig({g}, {}).status(),
                    {g + ":3: extrinsics.imu_T_lidar.rotation_xyzw[0] = 2 is out of range"}));
}

TEST(ConfigErrors, ChoicesAreValidated) {
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"backend=kalman"}).status(),
                            {"--set: backend = 'kalman' is not one of ieskf|smoother"}));
  TempDir dir;
  const std::string f = dir.Write("foo.yaml", "lidar:\n  type: sick\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({f}, {}).status(),
                            {f + ":2: lidar.type = 'sick' is not one of auto|ouster"}));
}

TEST(ConfigErrors, CrossFieldRulesNameEverySource) {
  TempDir dir;
  // rv.eps1 > rv.eps0 violates Alg. 3's eps1 <= eps0.
  const std::string f = dir.Write("foo.yaml", "rv:\n  eps0: 0.2\n  eps1: 0.3\n");
  Status s = LoadConfig({f}, {}).status();
  EXPECT_TRUE(IsConfigError(s, {f + ":3: rv.eps1 must not exceed rv.eps0",
                                "rv.eps1 from " + f + ":3", "rv.eps0 from " + f + ":2"}));
  // Only one side set: the other is named as the built-in default (eps1 0.03).
  EXPECT_TRUE(IsConfigError(LoadConfig({}, {"rv.eps0=0.02"}).status(),
                            {"--set: rv.eps1 must not exceed rv.eps0",
                             "rv.eps1 from built-in default", "rv.eps0 from --set"}));
  // Equal values are allowed (the paper's real preset is nearly equal).
  EXPECT_TRUE(LoadConfig({}, {"rv.eps0=0.3", "rv.eps1=0.3"}).ok());
  // Another module's rule.
  const std::string g = dir.Write("g.yaml", "lidar:\n  min_range: 20\n  max_range: 10\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({g}, {}).status(),
                            {"lidar.max_range must be greater than lidar.min_range", g}));
}

TEST(ConfigErrors, MissingFile) {
  TempDir dir;
  const std::string f = dir.Path("does_not_exist.yaml");
  EXPECT_TRUE(IsConfigError(LoadConfig({f}, {}).status(), {f + ": config file not found"}));
  // A folder is not a config file either.
  EXPECT_TRUE(IsConfigError(LoadConfig({dir.Path("")}, {}).status(), {"config file not found"}));
}

TEST(ConfigErrors, YamlSyntaxErrorHasTheLineNumber) {
  TempDir dir;
  const std::string f =
      dir.Write("foo.yaml", "rv:\n  eps0: 0.3\n  eps1: [0.1, 0.2\nlidar:\n  min_range: 1\n");
  Status s = LoadConfig({f}, {}).status();
  EXPECT_TRUE(IsConfigError(s, {f + ":", "YAML syntax error"}));
  // yaml-cpp stops where the flow sequence is found unterminated (line 4 or 5
  // depending on look-ahead); the reported line must be one of the file's.
  const std::string prefix = f + ":";
  const int line = std::stoi(s.message().substr(prefix.size()));
  EXPECT_GE(line, 3);
  EXPECT_LE(line, 5);

  const std::string g = dir.Write("g.yaml", "rv:\n  eps0: 0.3\n   eps1: 0.1\n");
  Status sg = LoadConfig({g}, {}).status();
  EXPECT_TRUE(IsConfigError(sg, {g + ":3:", "YAML syntax error"}));
}

TEST(ConfigErrors, DuplicateKeysAndNonMappingDocuments) {
  TempDir dir;
  const std::string f = dir.Write("foo.yaml", "rv:\n  eps0: 0.3\n  eps0: 0.4\n");
  EXPECT_TRUE(
      IsConfigError(LoadConfig({f}, {}).status(), {"rv.eps0: duplicate key in " + f + ":3"}));
  const std::string g = dir.Write("g.yaml", "- a\n- b\n");
  EXPECT_TRUE(IsConfigError(LoadConfig({g}, {}).status(),
                            {g + ": expected a mapping of keys at the top level, got a list"}));
}

// ---------------------------------------------------------------------------
// The same machinery on a struct of its own.

TEST(ConfigGeneric, WorksOnAnyOptionsStruct) {
  TempDir dir;
  const std::string f = dir.Write("toy.yaml",
                                  "rate: 20\n"
                                  "inner:\n"
                                  "  seed: 9000000000\n"  // beyond int32
                                  "  xy: [-1.5, 4]\n"
                                  "  deep: {flag: true}\n");
  ConfigSources sources;
  StatusOr<ToyOptions> r =
      LoadOptions<ToyOptions>({f}, {"inner.mode=b", "inner.deep.count=9"}, &sources);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rate, 20.0);
  EXPECT_EQ(r->inner.seed, 9000000000LL);
  EXPECT_EQ(r->inner.xy, (std::array<double, 2>{-1.5, 4.0}));
  EXPECT_EQ(r->inner.mode, "b");
  EXPECT_TRUE(r->inner.deep.flag);
  EXPECT_EQ(r->inner.deep.count, 9);
  EXPECT_EQ(r->name, "toy");
  EXPECT_EQ(sources.at("inner.deep.flag"), f + ":5");
  EXPECT_EQ(sources.at("inner.deep.count"), "--set");

  EXPECT_TRUE(
      IsConfigError(LoadOptions<ToyOptions>({}, {"inner.deep.cont=1"}).status(),
                    {"inner.deep.cont: unknown key in --set", "did you mean inner.deep.count?"}));
  EXPECT_TRUE(IsConfigError(LoadOptions<ToyOptions>({}, {"inner.seed=-1"}).status(),
                            {"--set: inner.seed = -1 is out of range"}));
  EXPECT_TRUE(IsConfigError(LoadOptions<ToyOptions>({f}, {"inner.xy=[5, 4]"}).status(),
                            {"--set: inner.xy must be increasing"}));
  EXPECT_TRUE(IsConfigError(LoadOptions<ToyOptions>({}, {"inner.xy=[1, 2, 3]"}).status(),
                            {"inner.xy in --set: expected a list of 2 numbers, got 3"}));
  EXPECT_TRUE(
      IsConfigError(LoadOptions<ToyOptions>({}, {"inner.seed=99999999999999999999"}).status(),
                    {"inner.seed in --set: expected an integer in"}));
}

TEST(ConfigGeneric, ListKeysIsEveryLeafInVisitOrder) {
  const std::vector<std::string> keys = ListKeys(ToyOptions{});
  EXPECT_EQ(keys, (std::vector<std::string>{"rate", "name", "inner.seed", "inner.xy", "inner.mode",
                                            "inner.deep.flag", "inner.deep.count"}));
}

}  // namespace
}  // namespace rvlio
