// Renamed keys (common/options.h, DeprecatedName): the old name still sets the
// field under its new name, with one warning line naming both and where it
// was written; old and new name together in one mapping are an error.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config_test_util.h"
#include "rvlio/config/config.h"

namespace rvlio {
namespace {

using test::IsConfigError;
using test::TempDir;

TEST(ConfigRename, OldSmootherHuberNamesSetTheScopedFieldsWithOneWarningEach) {
  TempDir dir;
  const std::string a =
      dir.Write("a.yaml", "smoother:\n  window_size: 8\n  huber_delta: 0.2\n");
  std::vector<std::string> warnings;
  ConfigSources sources;
  StatusOr<OdometryOptions> r = LoadOptions<OdometryOptions>(
      {a}, {"smoother.online_huber_delta=0.05"}, &sources, &warnings);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->smoother.refine_huber_delta, 0.2);
  EXPECT_EQ(r->smoother.sliding_window_huber_delta, 0.05);
  EXPECT_EQ(r->smoother.window_size, 8);
  EXPECT_EQ(sources.at("smoother.refine_huber_delta"), a + ":3");
  EXPECT_EQ(sources.at("smoother.sliding_window_huber_delta"), "--set");
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0], a + ":3: smoother.huber_delta is deprecated, renamed "
                             "smoother.refine_huber_delta (the old name is read until the next release)");
  EXPECT_EQ(warnings[1], "--set: smoother.online_huber_delta is deprecated, renamed "
                         "smoother.sliding_window_huber_delta (the old name is read until the next release)");
  // The resolved configuration speaks only of the new names.
  const std::string dump = DumpYaml(*r);
  EXPECT_NE(dump.find("refine_huber_delta: 0.2"), std::string::npos);
  EXPECT_EQ(dump.find(" huber_delta:"), std::string::npos);
  EXPECT_EQ(dump.find("online_huber_delta"), std::string::npos);
}

TEST(ConfigRename, NewNamesGiveNoWarningAndTheValidationNamesTheNewKey) {
  std::vector<std::string> warnings;
  StatusOr<OdometryOptions> r = LoadOptions<OdometryOptions>(
      {}, {"smoother.refine_huber_delta=0.3", "smoother.sliding_window_huber_delta=0.04"}, nullptr,
      &warnings);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->smoother.refine_huber_delta, 0.3);
  EXPECT_EQ(r->smoother.sliding_window_huber_delta, 0.04);
  EXPECT_TRUE(warnings.empty());
  // A bad value under the old name is reported under the field's name.
  const Status bad = LoadConfig({}, {"smoother.huber_delta=-1"}).status();
  EXPECT_TRUE(IsConfigError(bad, {"smoother.refine_huber_delta", "--set"})) << bad.message();
}

TEST(ConfigRename, OldAndNewNameInOneMappingAreAnError) {
  TempDir dir;
  const std::string a = dir.Write(
      "a.yaml", "smoother:\n  refine_huber_delta: 0.2\n  huber_delta: 0.3\n");
  const Status s = LoadConfig({a}, {}).status();
  EXPECT_TRUE(IsConfigError(s, {"smoother.huber_delta", "smoother.refine_huber_delta", a + ":3"}))
      << s.message();
  // In separate files the later one wins, as for any key.
  const std::string b = dir.Write("b.yaml", "smoother:\n  huber_delta: 0.3\n");
  const std::string c = dir.Write("c.yaml", "smoother:\n  refine_huber_delta: 0.2\n");
  StatusOr<OdometryOptions> r = LoadConfig({b, c}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->smoother.refine_huber_delta, 0.2);
}

}  // namespace
}  // namespace rvlio
