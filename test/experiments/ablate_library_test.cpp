// The ablation's library parts in-process (rvlio/experiments/ablate_grid.h,
// ablate_cells.h): a grid read through the public YAML tree, the plan's
// cells, cell records and their status; and the number parsing they share
// with the configuration (rvlio/common/number_text.h).
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../cli/cli_util.h"
#include "rvlio/common/number_text.h"
#include "rvlio/config/yaml_tree.h"
#include "rvlio/experiments/ablate_cells.h"
#include "rvlio/experiments/ablate_grid.h"
#include "rvlio/experiments/ablate_runner.h"

namespace rvlio::experiments::ablate {
namespace {

namespace fs = std::filesystem;
using testing_cli::MakeTempDir;

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

constexpr const char* kSmallGrid = R"(sequences:
  - name: sim
    simulate: {preset: tunnel, duration: 3}
    seeds: [1, 2]
variants:
  off: {rv: {enabled: false}}
  on: {}
parameters:
  rv.eps0: {from: 0.1, to: 0.2, step: 0.1}
)";

TEST(NumberText, OneImplementationOfEachCheck) {
  for (const char* yes : {"0", "-12", "+7", "9223372036854775807"})
    EXPECT_TRUE(IsIntegerText(yes)) << yes;
  for (const char* no : {"", "+", "1.5", "1e3", "0x10", " 5", "5 "})
    EXPECT_FALSE(IsIntegerText(no)) << no;
  int64_t v = 0;
  EXPECT_TRUE(ParseInteger("-42", &v));
  EXPECT_EQ(v, -42);
  EXPECT_FALSE(ParseInteger("99999999999999999999", &v));  // out of int64
  double d = 0.0;
  EXPECT_TRUE(ParseNumber("2.5e-1", &d));
  EXPECT_EQ(d, 0.25);
  for (const char* no : {"", "1x", "nan", "inf", "1e999"}) EXPECT_FALSE(ParseNumber(no, &d)) << no;
}

TEST(YamlTree, ReadsAFileWithLinesAndFindsKeys) {
  const std::string dir = MakeTempDir("rvlio_yaml_tree");
  Write(dir + "/a.yaml", "x: 1\nmap:\n  y: [a, b]\n");
  StatusOr<YamlNode> root = ReadYamlFile(dir + "/a.yaml");
  ASSERT_TRUE(root.ok()) << root.status().message();
  ASSERT_NE(root->Find("map"), nullptr);
  const YamlNode* y = root->Find("map")->Find("y");
  ASSERT_NE(y, nullptr);
  EXPECT_EQ(y->kind, YamlNode::Kind::kSequence);
  EXPECT_EQ(y->items.at(1).scalar, "b");
  EXPECT_EQ(y->line, 3);
  EXPECT_EQ(root->Find("missing"), nullptr);
  EXPECT_EQ(YamlWhere("a.yaml", 3), "a.yaml:3");
  Write(dir + "/bad.yaml", "x: [1\n");
  StatusOr<YamlNode> bad = ReadYamlFile(dir + "/bad.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find(dir + "/bad.yaml"), std::string::npos);
  fs::remove_all(dir);
}

TEST(AblateLibrary, PlanExpandsTheGridAndCellsRecordTheirStatus) {
  const std::string dir = MakeTempDir("rvlio_ablate_lib");
  Write(dir + "/grid.yaml", kSmallGrid);
  StatusOr<Plan> plan = LoadPlan(dir + "/grid.yaml", dir + "/out");
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  EXPECT_EQ(plan->data.size(), 2u);           // two seeds
  EXPECT_EQ(plan->cells.size(), 2u * 2 * 2);  // seeds x variants x eps0 values
  EXPECT_EQ(plan->param_keys, std::vector<std::string>{"rv.eps0"});
  const nlohmann::json j = nlohmann::json::parse(PlanJsonText(*plan));
  EXPECT_EQ(j["cells"].size(), plan->cells.size());
  EXPECT_EQ(j["cells"][0]["id"], plan->cells[0].id);

  const Cell& cell = plan->cells[0];
  EXPECT_EQ(ReadCellStatus(cell), CellStatus::kMissing);
  fs::create_directories(cell.dir);
  StatusOr<CellStatus> recorded = RecordDataFailure(cell, plan->data[cell.data_index], "tail");
  ASSERT_TRUE(recorded.ok()) << recorded.status().message();
  EXPECT_EQ(*recorded, CellStatus::kFailed);
  EXPECT_EQ(ReadCellStatus(cell), CellStatus::kFailed);
  EXPECT_FALSE(Finished(ReadCellStatus(cell)));
  CellRunEnd crashed;
  crashed.how = "killed by signal 11 (Segmentation fault)";
  recorded = RecordCell(cell, crashed);
  ASSERT_TRUE(recorded.ok());
  EXPECT_EQ(*recorded, CellStatus::kFailed);
  EXPECT_NE(testing_cli::ReadFile(cell.CellJson()).find("rvlio run killed by signal 11"),
            std::string::npos);

  Write(dir + "/typo.yaml", std::string(kSmallGrid) + "varaints: {}\n");
  StatusOr<Plan> typo = LoadPlan(dir + "/typo.yaml", dir + "/out");
  ASSERT_FALSE(typo.ok());
  EXPECT_EQ(typo.status().message().rfind(dir + "/typo.yaml:10: varaints: unknown key", 0), 0u)
      << typo.status().message();
  fs::remove_all(dir);
}

// The hooks see every batch and item; a program that cannot be started is
// a failed item, recorded, never a crash (no process runs here).
class CountingHooks : public RunnerHooks {
 public:
  void BatchStarted(const std::string& what, int total, int skipped) override {
    batches.push_back(what + ":" + std::to_string(total) + ":" + std::to_string(skipped));
  }
  void Finished(const std::string&, bool ok, double) override { ok ? ++ok_items : ++failed_items; }
  void BatchEnded() override { ++ended; }
  std::vector<std::string> batches;
  int ok_items = 0, failed_items = 0, ended = 0;
};

TEST(AblateLibrary, RunnerRecordsItemsThatCannotStartAndCallsTheHooks) {
  const std::string dir = MakeTempDir("rvlio_ablate_runner");
  Write(dir + "/grid.yaml", kSmallGrid);
  StatusOr<Plan> plan = LoadPlan(dir + "/grid.yaml", dir + "/out");
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  RunnerOptions options;
  options.rvlio_bin = dir + "/no_such_program";
  CountingHooks hooks;
  const RunCounts c = RunPlan(*plan, options, &hooks);
  EXPECT_EQ(hooks.batches, (std::vector<std::string>{"data:2:0", "cell:8:0"}));
  EXPECT_EQ(hooks.ended, 2);
  EXPECT_EQ(hooks.ok_items, 0);
  EXPECT_EQ(hooks.failed_items, 2 + 8);
  EXPECT_EQ(c.total, 8);
  EXPECT_EQ(c.failed, 8);
  EXPECT_EQ(c.done + c.skipped + c.interrupted + c.not_started, 0);
  for (const Cell& cell : plan->cells) EXPECT_EQ(ReadCellStatus(cell), CellStatus::kFailed);
  RunCounts one;
  EXPECT_FALSE(RunOne(*plan, "no_such_cell", options, &hooks, &one));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio::experiments::ablate
