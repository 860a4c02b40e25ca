// `rvlio report DIR`: one self-contained report.html for a compare, demo,
// ablate or run folder (docs/report.md). compare, demo and ablate call
// WriteFolderReport at their end.
#include <cstdio>
#include <string>

#include "cli.h"
#include "commands.h"
#include "report_html.h"

namespace rvlio::cli {
namespace {

constexpr const char* kReport = "report";
constexpr long long kMaxPointsLimit = 50000000;

CommandSpec ReportSpec() {
  return {kReport,
          "The folder comes first: rvlio report DIR [options]. Writes DIR/report.html, one\n"
          "page that opens offline in a browser: the trajectories over the ground truth, the\n"
          "RV activity and health per scan, the map as a 3D point cloud and the table of\n"
          "metrics. DIR is a compare, demo, ablate or run output folder.",
          {{"out", "FILE", "write the page here instead of DIR/report.html"},
           {"gt", "FILE", "ground truth for a run folder (TUM or KITTI; compare/ablate know theirs)"},
           {"max-points", "N", "map points embedded at most (default 1000000; more are thinned)"}}};
}

int ReadMaxPoints(const Args& args, size_t* max_points) {
  if (!args.Has("max-points")) return 0;
  const std::string text = args.Get("max-points");
  long long v = 0;
  if (!ParseWholeNumber(text, 1, kMaxPointsLimit, &v))
    return Fail(kReport, "--max-points '" + text + "' is not a whole number in [1, " +
                           std::to_string(kMaxPointsLimit) + "]");
  *max_points = static_cast<size_t>(v);
  return 0;
}

}  // namespace

void WriteFolderReport(const std::string& command, const std::string& dir, bool quiet) {
  StatusOr<report::WrittenReport> r = report::WriteReport(dir, "", report::ReportOptions());
  if (!r.ok()) {
    std::fprintf(stderr, "rvlio %s: warning: report.html not written: %s\n", command.c_str(),
                 r.status().message().c_str());
    return;
  }
  if (!quiet) std::printf("  report: %s\n", r->path.c_str());
}

int CmdReport(int argc, char** argv) {
  const CommandSpec spec = ReportSpec();
  // DIR comes first (rvlio report DIR [options]); --help alone prints the usage.
  const bool has_dir = argc > 2 && std::string(argv[2]).rfind("--", 0) != 0;
  Args args;
  if (int rc = Parse(spec, argc, argv, has_dir ? 3 : 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  if (!has_dir) return Fail(kReport, "missing the folder: rvlio report DIR (see --help)");
  const std::string dir = argv[2];
  report::ReportOptions options;
  options.gt = args.Get("gt");
  if (int rc = ReadMaxPoints(args, &options.max_points); rc != 0) return rc;
  StatusOr<report::WrittenReport> r = report::WriteReport(dir, args.Get("out"), options);
  if (!r.ok()) return Fail(kReport, r.status());
  std::printf("rvlio report: wrote %s (%.1f MB)\n", r->path.c_str(),
              static_cast<double>(r->bytes) / 1e6);
  return 0;
}

}  // namespace rvlio::cli
