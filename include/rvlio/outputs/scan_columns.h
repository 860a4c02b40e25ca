#pragma once
// The per-scan columns: one table of name, unit and how to compute each from
// a scan's record. scans.csv (outputs/run_outputs.h, WriteScansCsv) and the Python
// per-scan table (rvlio.run(...).scans) are both generated from it, so they
// have the same columns in the same order (docs/outputs.md lists them).
#include <string>
#include <vector>

#include "rvlio/odometry/odometry.h"

namespace rvlio {

// What a column describes one scan from: the odometry's result and the
// process's resident memory when the scan was done (MB, NaN: not measured).
struct ScanRecord {
  const ScanResult& scan;
  double rss_mb;
};

// The value of a column: its type for numeric readers (Python's dtype).
enum class ScanValueType {
  kText,     // a name (numeric readers get the text)
  kFlag,     // true / false (CSV: 1 / 0, or the text when the column has one)
  kInteger,  // a count
  kReal,     // a real number; NaN: none
};

// How a column is written to the CSV.
enum class ScanCsvFormat {
  kSeconds,      // nine decimals (a stamp)
  kPlain,        // text, whole number, or 9 significant digits (nan and inf as printed)
  kRealOrEmpty,  // 9 significant digits; empty when NaN (none)
  kStatistic,    // 6 significant digits; empty when not finite (unknown)
  kPosition,     // as kPlain, with at least 6 decimals: a coordinate in a national grid
                 // (northings of 5e6 m) keeps its micrometres
};

// Columns that only some runs have: they are present when some scan carries
// a value (online extrinsic or time-offset estimation, a reference map).
enum class ScanColumnGroup { kAlways, kExtrinsic, kTimeOffset, kReference };

struct ScanColumn {
  const char* name;
  const char* unit;  // SI unit, "1" dimensionless, "" text or count
  ScanValueType type;
  ScanCsvFormat format;
  ScanColumnGroup group;
  double (*value)(const ScanRecord&);      // numeric value (flags 0/1); null for text only
  std::string (*text)(const ScanRecord&);  // text form written to the CSV; null: the value
};

// Every column, in the order of scans.csv.
const std::vector<ScanColumn>& AllScanColumns();

// The columns of a run's table: AllScanColumns() without the groups no scan
// of `scans` carries.
std::vector<const ScanColumn*> ScanColumnsOf(const std::vector<ScanResult>& scans);

// One CSV field of a column (no separator).
std::string FormatScanCell(const ScanColumn& column, const ScanRecord& record);

}  // namespace rvlio
