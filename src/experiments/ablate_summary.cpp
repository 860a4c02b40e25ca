#include "rvlio/experiments/ablate_summary.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "csv_text.h"
#include "rvlio/common/text.h"
#include "ablate_records.h"
#include "rvlio/formats/atomic_file.h"

namespace rvlio::experiments::ablate {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Mean and sample standard deviation (n-1) of the finite values.
struct Stats {
  int n = 0;
  double mean = NAN, std = NAN;
};

Stats Describe(const std::vector<double>& values) {
  Stats s;
  double sum = 0.0;
  for (double v : values) sum += v;
  s.n = static_cast<int>(values.size());
  if (s.n == 0) return s;
  s.mean = sum / s.n;
  if (s.n < 2) return s;
  double sq = 0.0;
  for (double v : values) sq += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(sq / (s.n - 1));
  return s;
}

struct Group {
  const Cell* first = nullptr;  // sequence, label, params
  int cells = 0, done = 0, failed = 0, diverged = 0;
  std::map<std::string, std::vector<double>> values;  // metric -> finite values of done cells
};

double MetricOf(const json& record, const std::string& m) {
  if (!record.contains("metrics") || !record["metrics"].contains(m) ||
      !record["metrics"][m].is_number())
    return NAN;
  return record["metrics"][m].get<double>();
}

std::string SummaryCsv(const Plan& plan, const std::vector<json>& records) {
  std::ostringstream o;
  o << "id,sequence,variant,seed";
  for (const auto& k : plan.param_keys) o << "," << CsvField(k);
  o << ",status,exit_code";
  for (const MetricColumn& m : MetricColumns(MetricSetOf(plan))) o << "," << m.name;
  o << ",wall_s,error\n";
  for (size_t i = 0; i < plan.cells.size(); ++i) {
    const Cell& c = plan.cells[i];
    const json& r = records[i];
    o << c.id << "," << CsvField(c.sequence) << "," << CsvField(c.variant) << ","
      << (c.has_seed ? std::to_string(c.seed) : "");
    for (const auto& [k, v] : c.params) o << "," << CsvField(v);
    const std::string status = r.is_object() ? r.value("status", "missing") : "missing";
    o << "," << status << ","
      << (r.is_object() && r["exit_code"].is_number() ? std::to_string(r["exit_code"].get<int>())
                                                      : "");
    for (const MetricColumn& m : MetricColumns(MetricSetOf(plan)))
      o << "," << FormatFinite(r.is_object() ? MetricOf(r, m.name) : NAN, 12);
    o << "," << FormatFinite(r.is_object() ? r.value("wall_s", NAN) : NAN, 12) << ","
      << CsvField(r.is_object() && r["error"].is_string() ? r["error"].get<std::string>() : "")
      << "\n";
  }
  return o.str();
}

std::vector<Group> GroupCells(const Plan& plan, const std::vector<json>& records) {
  std::vector<Group> groups;
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < plan.cells.size(); ++i) {
    const Cell& c = plan.cells[i];
    const std::string key = c.sequence + "\n" + c.label;
    auto [it, fresh] = index.emplace(key, groups.size());
    if (fresh) {
      groups.emplace_back();
      groups.back().first = &c;
    }
    Group& g = groups[it->second];
    ++g.cells;
    const json& r = records[i];
    const std::string status = r.is_object() ? r.value("status", "") : "";
    if (status == "failed") ++g.failed;
    if (status == "diverged") ++g.diverged;
    if (status != "done") continue;
    ++g.done;
    for (const auto& [m, header] : MetricColumns(MetricSetOf(plan))) {
      const double v = MetricOf(r, m);
      if (std::isfinite(v)) g.values[m].push_back(v);
    }
  }
  return groups;
}

std::string TableCsv(const Plan& plan, const std::vector<Group>& groups) {
  std::ostringstream o;
  o << "sequence,variant";
  for (const auto& k : plan.param_keys) o << "," << CsvField(k);
  o << ",cells,n,failed,diverged";
  const MetricSet set = MetricSetOf(plan);
  for (const auto& [m, header] : MetricColumns(set)) o << "," << m << "_mean," << m << "_std";
  o << "\n";
  for (const Group& g : groups) {
    o << CsvField(g.first->sequence) << "," << CsvField(g.first->label);
    for (const auto& [k, v] : g.first->params) o << "," << CsvField(v);
    o << "," << g.cells << "," << g.done << "," << g.failed << "," << g.diverged;
    for (const auto& [m, header] : MetricColumns(set)) {
      const Stats s = Describe(g.values.count(m) ? g.values.at(m) : std::vector<double>());
      o << "," << FormatFinite(s.mean, 12) << "," << FormatFinite(s.std, 12);
    }
    o << "\n";
  }
  return o.str();
}

std::string MeanStd(const Stats& s, int precision) {
  if (s.n == 0) return "-";
  char buf[64];
  if (s.n < 2)
    std::snprintf(buf, sizeof(buf), "%.*f", precision, s.mean);
  else
    std::snprintf(buf, sizeof(buf), "%.*f ± %.*f", precision, s.mean, precision, s.std);
  return buf;
}

std::string TableMarkdown(const std::vector<Group>& groups, MetricSet set) {
  std::ostringstream o;
  o << "| sequence | variant | n | failed | diverged |";
  for (const auto& [m, header] : MetricColumns(set)) o << " " << header << " |";
  o << "\n|---|---|---|---|---|";
  for (size_t i = 0; i < MetricColumns(set).size(); ++i) o << "---|";
  o << "\n";
  for (const Group& g : groups) {
    o << "| " << g.first->sequence << " | " << g.first->label << " | " << g.done << " | "
      << g.failed << " | " << g.diverged << " |";
    for (const auto& [m, header] : MetricColumns(set)) {
      const int precision =
          m == "ate_rmse" || m == "rpe_rmse" || m.rfind("axis", 0) == 0 || m == "end_point" ||
                  m == "map_rms" || m == "map_completeness"
              ? 4
              : 2;
      o << " "
        << MeanStd(Describe(g.values.count(m) ? g.values.at(m) : std::vector<double>()), precision)
        << " |";
    }
    o << "\n";
  }
  return o.str();
}

}  // namespace

StatusOr<SummaryResult> WriteSummary(const Plan& plan) {
  SummaryResult result;
  std::vector<json> records;
  for (const Cell& c : plan.cells) {
    records.push_back(ReadCellRecord(c));
    const json& r = records.back();
    ++result.cells;
    if (!r.is_object())
      ++result.missing;
    else if (r.value("status", "") == "done")
      ++result.done;
    else if (r.value("status", "") == "diverged")
      ++result.diverged;
    else
      ++result.failed;
  }
  const std::vector<Group> groups = GroupCells(plan, records);
  result.table_md = TableMarkdown(groups, MetricSetOf(plan));
  const fs::path out(plan.out_dir);
  for (const auto& [name, text] :
       {std::pair<const char*, std::string>{"summary.csv", SummaryCsv(plan, records)},
        {"table.csv", TableCsv(plan, groups)},
        {"table.md", result.table_md}})
    if (Status s = WriteFileAtomically((out / name).string(), text); !s.ok()) return s;
  return result;
}

std::vector<std::string> SummaryPlotArgs(const Plan& plan, std::string* prefix) {
  *prefix = (fs::path(plan.out_dir) / "plots" / "summary").string();
  std::vector<std::string> args = {"ablation", "--table", plan.out_dir + "/table.csv", "--out",
                                   *prefix, "--metric", "ate_rmse", "--metric", "axis_max",
                                   "--metric", "ms_per_scan"};
  if (plan.HasRefMap()) args.insert(args.end(), {"--metric", "map_rms"});
  if (plan.HasSimulated())
    args.insert(args.end(), {"--metric", "detect_precision", "--metric", "detect_recall"});
  return args;
}

}  // namespace rvlio::experiments::ablate
