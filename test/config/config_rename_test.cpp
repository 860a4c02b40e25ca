// Renamed keys (common/options.h, DeprecatedName) and keys moved to another
// section (Configuration::kMovedKeys): the old name still sets the field
// under its new name, with one warning line naming both and where it was
// written; old and new name together in one mapping are an error.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config_test_util.h"
#include "rvlio/config/config.h"

namespace rvlio {
namespace {

using test::IsConfigError;
using test::TempDir;

std::string Deprecated(const std::string& where, const std::string& old_key,
                       const std::string& new_key) {
  return where + ": " + old_key + " is deprecated, renamed " + new_key +
         " (the old name is read until the next release)";
}

TEST(ConfigRename, OldSmootherHuberNamesSetTheScopedFieldsWithOneWarningEach) {
  TempDir dir;
  const std::string a =
      dir.Write("a.yaml", "smoother:\n  window_size: 8\n  huber_delta: 0.2\n");
  std::vector<std::string> warnings;
  ConfigSources sources;
  StatusOr<Configuration> r = LoadOptions<Configuration>(
      {a}, {"smoother.online_huber_delta=0.05"}, &sources, &warnings);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->refine.huber_delta, 0.2);
  EXPECT_EQ(r->smoother.sliding_window_huber_delta, 0.05);
  EXPECT_EQ(r->smoother.window_size, 8);
  EXPECT_EQ(sources.at("refine.huber_delta"), a + ":3");
  EXPECT_EQ(sources.at("smoother.sliding_window_huber_delta"), "--set");
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0], Deprecated(a + ":3", "smoother.huber_delta", "refine.huber_delta"));
  EXPECT_EQ(warnings[1], Deprecated("--set", "smoother.online_huber_delta",
                                    "smoother.sliding_window_huber_delta"));
  // The resolved configuration speaks only of the new names.
  const std::string dump = DumpYaml(*r);
  EXPECT_NE(dump.find("refine:\n  huber_delta: 0.2"), std::string::npos) << dump;
  EXPECT_EQ(dump.find("refine_huber_delta"), std::string::npos);
  EXPECT_EQ(dump.find(" huber_delta: 0.1"), std::string::npos);
  EXPECT_EQ(dump.find("online_huber_delta"), std::string::npos);
}

// Every key refine once had in the smoother's section is read there, with
// one warning each, and sets the same field as its new name.
TEST(ConfigRename, RefineKeysUnderTheSmootherSetTheRefineSectionWithOneWarningEach) {
  const std::vector<std::pair<std::string, std::string>> moved = {
      {"smoother.refine_huber_delta=0.25", "refine.huber_delta=0.25"},
      {"smoother.refine_rounds=7", "refine.rounds=7"},
      {"smoother.refine_chunk_scans=500", "refine.chunk_scans=500"},
      {"smoother.refine_solver_iterations=12", "refine.solver_iterations=12"},
      {"smoother.refine_threads=3", "refine.threads=3"},
      {"smoother.refine_plane_window=40", "refine.plane_window=40"},
      {"smoother.refine_job_overlap_s=4", "refine.job_overlap_s=4"},
      {"smoother.refine_summarize_pairs=false", "refine.summarize_pairs=false"}};
  std::vector<std::string> old_sets, new_sets;
  for (const auto& m : moved) {
    old_sets.push_back(m.first);
    new_sets.push_back(m.second);
  }
  std::vector<std::string> old_warnings, new_warnings;
  StatusOr<Configuration> old_names = LoadConfig({}, old_sets, &old_warnings);
  StatusOr<Configuration> new_names = LoadConfig({}, new_sets, &new_warnings);
  ASSERT_TRUE(old_names.ok()) << old_names.status().message();
  ASSERT_TRUE(new_names.ok()) << new_names.status().message();
  EXPECT_EQ(DumpYaml(*old_names), DumpYaml(*new_names));
  EXPECT_EQ(old_names->refine.rounds, 7);
  EXPECT_FALSE(old_names->refine.summarize_pairs);
  EXPECT_TRUE(new_warnings.empty());
  ASSERT_EQ(old_warnings.size(), moved.size());
  EXPECT_EQ(old_warnings[1], Deprecated("--set", "smoother.refine_rounds", "refine.rounds"));
  // In a file, under a section the file gives too.
  TempDir dir;
  const std::string a = dir.Write(
      "a.yaml", "refine:\n  threads: 2\nsmoother:\n  window_size: 8\n  refine_rounds: 6\n");
  std::vector<std::string> warnings;
  StatusOr<Configuration> f = LoadConfig({a}, {}, &warnings);
  ASSERT_TRUE(f.ok()) << f.status().message();
  EXPECT_EQ(f->refine.rounds, 6);
  EXPECT_EQ(f->refine.threads, 2);
  EXPECT_EQ(f->smoother.window_size, 8);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], Deprecated(a + ":5", "smoother.refine_rounds", "refine.rounds"));
}

TEST(ConfigRename, NewNamesGiveNoWarningAndTheValidationNamesTheNewKey) {
  std::vector<std::string> warnings;
  StatusOr<Configuration> r = LoadOptions<Configuration>(
      {}, {"refine.huber_delta=0.3", "smoother.sliding_window_huber_delta=0.04"}, nullptr,
      &warnings);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->refine.huber_delta, 0.3);
  EXPECT_EQ(r->smoother.sliding_window_huber_delta, 0.04);
  EXPECT_TRUE(warnings.empty());
  // A bad value under the old name is reported under the field's name.
  const Status bad = LoadConfig({}, {"smoother.huber_delta=-1"}).status();
  EXPECT_TRUE(IsConfigError(bad, {"refine.huber_delta", "--set"})) << bad.message();
}

TEST(ConfigRename, OldAndNewNameInOneMappingAreAnError) {
  TempDir dir;
  const std::string a = dir.Write(
      "a.yaml", "smoother:\n  refine_huber_delta: 0.2\n  huber_delta: 0.3\n");
  const Status s = LoadConfig({a}, {}).status();
  EXPECT_TRUE(IsConfigError(s, {"smoother.huber_delta", "refine.huber_delta", a + ":3"}))
      << s.message();
  const std::string both = dir.Write(
      "both.yaml", "smoother:\n  refine_rounds: 3\nrefine:\n  rounds: 5\n");
  const Status t = LoadConfig({both}, {}).status();
  EXPECT_TRUE(IsConfigError(t, {"smoother.refine_rounds", "refine.rounds", both + ":2"}))
      << t.message();
  // In separate files the later one wins, as for any key.
  const std::string b = dir.Write("b.yaml", "smoother:\n  huber_delta: 0.3\n");
  const std::string c = dir.Write("c.yaml", "refine:\n  huber_delta: 0.2\n");
  StatusOr<Configuration> r = LoadConfig({b, c}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->refine.huber_delta, 0.2);
}

}  // namespace
}  // namespace rvlio
