#include "rvlio/formats/trajectory_io.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <Eigen/SVD>

#include "rvlio/common/text.h"
#include "rvlio/formats/atomic_file.h"

namespace rvlio {
namespace {

constexpr int kTumValues = 8;
constexpr int kKittiValues = 12;
// KITTI files print 6-7 significant digits, so R^T R deviates from I by ~1e-6;
// anything far beyond that is not a rotation.
constexpr double kKittiOrthonormalTol = 1e-3;
// Largest stamp in seconds whose ns value fits int64 (as ParseSecondsToNs).
constexpr double kMaxStampS = 9.2e9;

// One non-blank, non-comment line split into values.
struct DataLine {
  int number = 0;  // 1-based line number in the file
  std::vector<std::string> tokens;
};

Status LineError(const std::string& path, int line, const std::string& message) {
  return Status::InvalidInput(path + ", line " + std::to_string(line) + ": " + message);
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> tokens;
  size_t i = 0;
  const char* kSeparators = " \t\r,";
  while (i < line.size()) {
    const size_t begin = line.find_first_not_of(kSeparators, i);
    if (begin == std::string::npos) break;
    size_t end = line.find_first_of(kSeparators, begin);
    if (end == std::string::npos) end = line.size();
    tokens.push_back(line.substr(begin, end - begin));
    i = end;
  }
  return tokens;
}

// The whole text of a file; what = "trajectory" or "times" for messages.
Status ReadFileText(const std::string& path, const std::string& what, std::string* text) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    return Status::InvalidInput("cannot open " + what + " file '" + path +
                                "': " + std::strerror(errno));
  if (S_ISDIR(st.st_mode))
    return Status::InvalidInput("cannot read " + what + " file '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return Status::InvalidInput("cannot open " + what + " file '" + path +
                                "': " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return Status::InvalidInput("error while reading " + what + " file '" + path + "'");
  *text = buffer.str();
  return Status::Ok();
}

// All data lines of a text (blank lines and '#' comments dropped); `source`
// names it in messages.
StatusOr<std::vector<DataLine>> SplitDataLines(const std::string& text, const std::string& source,
                                               const std::string& what) {
  std::vector<DataLine> lines;
  size_t start = 0;
  for (int number = 1; start < text.size(); ++number) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    lines.push_back({number, Split(line)});
  }
  if (lines.empty()) return Status::InvalidInput(what + " file '" + source + "' contains no poses");
  return lines;
}

StatusOr<std::vector<DataLine>> ReadDataLines(const std::string& path, const std::string& what) {
  std::string text;
  if (Status s = ReadFileText(path, what, &text); !s.ok()) return s;
  return SplitDataLines(text, path, what);
}

// strtod reports ERANGE both for overflow (+-HUGE_VAL, rejected by isfinite)
// and for underflow; an underflowing value (a subnormal, or 0 for 1e-400) is
// a finite number as written, e.g. by our own writer for a rotation-matrix
// entry of 1e-320, and is accepted.
bool ParseFinite(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && std::isfinite(*value);
}

Status ParseValues(const std::string& path, const DataLine& line, size_t first, double* out) {
  for (size_t i = first; i < line.tokens.size(); ++i)
    if (!ParseFinite(line.tokens[i], &out[i - first]))
      return LineError(
          path, line.number,
          "value " + std::to_string(i + 1) + " '" + line.tokens[i] + "' is not a finite number");
  return Status::Ok();
}

Status CheckValueCount(const std::string& path, const DataLine& line, size_t expected,
                       const char* layout) {
  if (line.tokens.size() == expected) return Status::Ok();
  return LineError(path, line.number,
                   "expected " + std::to_string(expected) + " values (" + layout + "), found " +
                       std::to_string(line.tokens.size()));
}

Status ParseStamp(const std::string& path, const DataLine& line, TimeNs* t_ns) {
  if (ParseSecondsToNs(line.tokens[0], t_ns)) return Status::Ok();
  return LineError(path, line.number, "time stamp '" + line.tokens[0] + "' is not a number");
}

Status CheckOrder(const std::string& path, const std::vector<DataLine>& lines,
                  const Trajectory& trajectory) {
  bool earlier = false;
  const size_t i = FirstStampOrderViolation(trajectory, &earlier);
  if (i == 0) return Status::Ok();
  if (earlier)
    return LineError(path, lines[i].number,
                     "time stamp " + lines[i].tokens[0] + " is earlier than the previous one (line " +
                         std::to_string(lines[i - 1].number) + "); stamps must not decrease");
  return LineError(path, lines[i].number,
                   "time stamp " + lines[i].tokens[0] + " is the third in a row (lines " +
                       std::to_string(lines[i - 2].number) + ", " +
                       std::to_string(lines[i - 1].number) +
                       "); stamps must increase (written with too few digits?)");
}

StatusOr<StampedPose> ParseTumLine(const std::string& path, const DataLine& line) {
  if (Status s = CheckValueCount(path, line, kTumValues, "t x y z qx qy qz qw"); !s.ok()) return s;
  StampedPose pose;
  if (Status s = ParseStamp(path, line, &pose.t_ns); !s.ok()) return s;
  double v[kTumValues - 1];
  if (Status s = ParseValues(path, line, 1, v); !s.ok()) return s;
  pose.p_world_imu = Eigen::Vector3d(v[0], v[1], v[2]);
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);  // Eigen order: w, x, y, z
  // Scaled by the largest component first: the norm of 1e200 components
  // would overflow to inf (and the quaternion become zero).
  const double scale = q.coeffs().cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return LineError(path, line.number, "quaternion is zero");
  const Eigen::Vector4d scaled = q.coeffs() / scale;
  if (!(scale * scaled.norm() > 1e-12)) return LineError(path, line.number, "quaternion is zero");
  pose.q_world_imu = Eigen::Quaterniond(scaled.normalized());
  return pose;
}

StatusOr<StampedPose> ParseKittiLine(const std::string& path, const DataLine& line) {
  if (Status s = CheckValueCount(path, line, kKittiValues, "3x4 matrix [R|t] row by row"); !s.ok())
    return s;
  double v[kKittiValues];
  if (Status s = ParseValues(path, line, 0, v); !s.ok()) return s;
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  const double deviation = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if (!(deviation <= kKittiOrthonormalTol) || R.determinant() <= 0.0)
    return LineError(path, line.number, "the 3x3 block is not a rotation matrix");
  // Nearest rotation (polar decomposition) removes the print rounding.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  StampedPose pose;
  pose.q_world_imu = Eigen::Quaterniond(svd.matrixU() * svd.matrixV().transpose()).normalized();
  pose.p_world_imu = Eigen::Vector3d(v[3], v[7], v[11]);
  return pose;
}

template <typename ParseLine>
StatusOr<Trajectory> ParseAll(const std::string& path, const std::vector<DataLine>& lines,
                              ParseLine parse) {
  Trajectory trajectory;
  trajectory.reserve(lines.size());
  for (const DataLine& line : lines) {
    StatusOr<StampedPose> pose = parse(path, line);
    if (!pose.ok()) return pose.status();
    trajectory.push_back(*pose);
  }
  return trajectory;
}

StatusOr<Trajectory> TumFromLines(const std::string& path, const std::vector<DataLine>& lines) {
  StatusOr<Trajectory> trajectory = ParseAll(path, lines, ParseTumLine);
  if (!trajectory.ok()) return trajectory;
  if (Status s = CheckOrder(path, lines, *trajectory); !s.ok()) return s;
  return trajectory;
}

// The stamps of a KITTI times file, read only once the poses parsed.
using TimesLoader = StatusOr<std::vector<DataLine>> (*)(const std::string& source,
                                                        const std::string* text);

StatusOr<std::vector<DataLine>> LoadTimesFile(const std::string& path, const std::string*) {
  return ReadDataLines(path, "times");
}

StatusOr<std::vector<DataLine>> LoadTimesText(const std::string& source, const std::string* text) {
  return SplitDataLines(*text, source, "times");
}

struct KittiTimes {
  std::string source;                 // times file path or name; empty: constant rate
  const std::string* text = nullptr;  // the text, for LoadTimesText
  TimesLoader load = LoadTimesFile;
  double rate_hz = 10.0;
};

Status AssignKittiTimes(const std::string& path, const KittiTimes& times,
                        Trajectory* trajectory) {
  const std::string& times_path = times.source;
  if (times_path.empty()) {
    const double rate_hz = times.rate_hz;
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
      return Status::InvalidInput("KITTI rate must be positive (got " + std::to_string(rate_hz) +
                                  " Hz)");
    // The last stamp must fit int64 ns (a rate of 1e-300 Hz would not).
    const double last_s = static_cast<double>(trajectory->size() - 1) / rate_hz;
    if (!(last_s < kMaxStampS))
      return Status::InvalidInput("KITTI rate " + FormatG(rate_hz) + " Hz is too low for " +
                                  std::to_string(trajectory->size()) +
                                  " poses: the stamps would overflow");
    for (size_t i = 0; i < trajectory->size(); ++i)
      (*trajectory)[i].t_ns = SecondsToNs(static_cast<double>(i) / rate_hz);
    // Stamps are whole nanoseconds: above ~1 GHz two poses would share one,
    // and the trajectory would not read back (nor interpolate).
    for (size_t i = 1; i < trajectory->size(); ++i)
      if ((*trajectory)[i].t_ns <= (*trajectory)[i - 1].t_ns)
        return Status::InvalidInput("KITTI rate " + FormatG(rate_hz) + " Hz is too high: poses " +
                                    std::to_string(i) + " and " + std::to_string(i + 1) +
                                    " would share the time stamp " +
                                    std::to_string((*trajectory)[i].t_ns) +
                                    " ns (stamps are whole nanoseconds)");
    return Status::Ok();
  }
  StatusOr<std::vector<DataLine>> lines = times.load(times_path, times.text);
  if (!lines.ok()) return lines.status();
  if (lines->size() != trajectory->size())
    return Status::InvalidInput("times file '" + times_path + "' has " +
                                std::to_string(lines->size()) + " stamps but '" + path + "' has " +
                                std::to_string(trajectory->size()) + " poses");
  for (size_t i = 0; i < lines->size(); ++i) {
    const DataLine& line = (*lines)[i];
    if (Status s = CheckValueCount(times_path, line, 1, "t"); !s.ok()) return s;
    if (Status s = ParseStamp(times_path, line, &(*trajectory)[i].t_ns); !s.ok()) return s;
  }
  return CheckOrder(times_path, *lines, *trajectory);
}

StatusOr<Trajectory> KittiFromLines(const std::string& path, const std::vector<DataLine>& lines,
                                    const KittiTimes& times) {
  StatusOr<Trajectory> trajectory = ParseAll(path, lines, ParseKittiLine);
  if (!trajectory.ok()) return trajectory;
  if (Status s = AssignKittiTimes(path, times, &*trajectory); !s.ok()) return s;
  return trajectory;
}

KittiTimes TimesFile(const std::string& times_path, double rate_hz) {
  KittiTimes times;
  times.source = times_path;
  times.rate_hz = rate_hz;
  return times;
}

// Format detected from the value count of the first data line.
StatusOr<Trajectory> TrajectoryFromLines(const std::string& path,
                                         const std::vector<DataLine>& lines,
                                         const KittiTimes& times) {
  const DataLine& first = lines.front();
  if (first.tokens.size() == kTumValues) return TumFromLines(path, lines);
  if (first.tokens.size() == kKittiValues) return KittiFromLines(path, lines, times);
  return LineError(path, first.number,
                   "unknown trajectory format: expected 8 values (TUM: t x y z qx qy qz qw) or 12 "
                   "(KITTI: 3x4 matrix), found " +
                       std::to_string(first.tokens.size()));
}

// Digits of [begin, end) as an unsigned integer; false on overflow of `limit`.
bool AccumulateDigits(const std::string& s, size_t begin, size_t end, uint64_t limit,
                      uint64_t* out) {
  uint64_t v = 0;
  for (size_t i = begin; i < end; ++i) {
    v = v * 10 + static_cast<uint64_t>(s[i] - '0');
    if (v > limit) return false;
  }
  *out = v;
  return true;
}

}  // namespace

bool ParseSecondsToNs(const std::string& text, TimeNs* t_ns) {
  const size_t n = text.size();
  size_t i = (n > 0 && (text[0] == '-' || text[0] == '+')) ? 1 : 0;
  const bool negative = n > 0 && text[0] == '-';
  const size_t int_begin = i;
  while (i < n && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
  const size_t int_end = i;
  size_t frac_begin = i, frac_end = i;
  if (i < n && text[i] == '.') {
    frac_begin = ++i;
    while (i < n && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
    frac_end = i;
  }
  const bool plain = i == n && (int_end > int_begin || frac_end > frac_begin);
  if (!plain) {  // exponent notation or garbage: through double
    double seconds = 0.0;
    if (!ParseFinite(text, &seconds) || std::fabs(seconds) > kMaxStampS) return false;
    *t_ns = SecondsToNs(seconds);
    return true;
  }
  constexpr uint64_t kMaxSeconds = 9223372035;  // keeps ns inside int64
  uint64_t seconds = 0, frac_ns = 0;
  if (!AccumulateDigits(text, int_begin, int_end, kMaxSeconds, &seconds)) return false;
  for (size_t k = 0; k < 9; ++k) {
    const size_t pos = frac_begin + k;
    frac_ns = frac_ns * 10 + (pos < frac_end ? static_cast<uint64_t>(text[pos] - '0') : 0);
  }
  if (frac_begin + 9 < frac_end && text[frac_begin + 9] >= '5') ++frac_ns;  // round to nearest
  const int64_t magnitude = static_cast<int64_t>(seconds * 1000000000ULL + frac_ns);
  *t_ns = negative ? -magnitude : magnitude;
  return true;
}

StatusOr<Trajectory> ReadTum(const std::string& path) {
  StatusOr<std::vector<DataLine>> lines = ReadDataLines(path, "trajectory");
  if (!lines.ok()) return lines.status();
  return TumFromLines(path, *lines);
}

StatusOr<Trajectory> ReadKitti(const std::string& path, const std::string& times_path,
                               double rate_hz) {
  StatusOr<std::vector<DataLine>> lines = ReadDataLines(path, "trajectory");
  if (!lines.ok()) return lines.status();
  return KittiFromLines(path, *lines, TimesFile(times_path, rate_hz));
}

StatusOr<Trajectory> ReadTrajectory(const std::string& path, const std::string& kitti_times_path,
                                    double kitti_rate_hz) {
  StatusOr<std::vector<DataLine>> lines = ReadDataLines(path, "trajectory");
  if (!lines.ok()) return lines.status();
  return TrajectoryFromLines(path, *lines, TimesFile(kitti_times_path, kitti_rate_hz));
}

StatusOr<Trajectory> ParseTumText(const std::string& text, const std::string& source) {
  StatusOr<std::vector<DataLine>> lines = SplitDataLines(text, source, "trajectory");
  if (!lines.ok()) return lines.status();
  return TumFromLines(source, *lines);
}

StatusOr<Trajectory> ParseKittiText(const std::string& text, const std::string& source,
                                    double rate_hz) {
  StatusOr<std::vector<DataLine>> lines = SplitDataLines(text, source, "trajectory");
  if (!lines.ok()) return lines.status();
  return KittiFromLines(source, *lines, TimesFile("", rate_hz));
}

StatusOr<Trajectory> ParseKittiText(const std::string& text, const std::string& source,
                                    const std::string& times_text,
                                    const std::string& times_source) {
  StatusOr<std::vector<DataLine>> lines = SplitDataLines(text, source, "trajectory");
  if (!lines.ok()) return lines.status();
  KittiTimes times;
  times.source = times_source.empty() ? std::string("times") : times_source;
  times.text = &times_text;
  times.load = LoadTimesText;
  return KittiFromLines(source, *lines, times);
}

StatusOr<Trajectory> ParseTrajectoryText(const std::string& text, const std::string& source,
                                         double kitti_rate_hz) {
  StatusOr<std::vector<DataLine>> lines = SplitDataLines(text, source, "trajectory");
  if (!lines.ok()) return lines.status();
  return TrajectoryFromLines(source, *lines, TimesFile("", kitti_rate_hz));
}

std::string FormatTumLine(const StampedPose& pose) {
  const bool negative = pose.t_ns < 0;
  // Magnitude as unsigned so that INT64_MIN cannot overflow.
  const uint64_t magnitude =
      negative ? 0 - static_cast<uint64_t>(pose.t_ns) : static_cast<uint64_t>(pose.t_ns);
  const Eigen::Quaterniond q = pose.q_world_imu.normalized();
  const Eigen::Vector3d& p = pose.p_world_imu;
  char buf[1536];  // room for %.9f of any finite double
  std::snprintf(buf, sizeof(buf),
                "%s%" PRIu64 ".%09" PRIu64 " %.9f %.9f %.9f %.12f %.12f %.12f %.12f\n",
                negative ? "-" : "", magnitude / uint64_t{1000000000},
                magnitude % uint64_t{1000000000}, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
  return buf;
}

StatusOr<Trajectory> RoundTripTum(const Trajectory& trajectory, const std::string& source) {
  std::string text = kTumColumnsComment;
  for (const StampedPose& pose : trajectory) text += FormatTumLine(pose);
  return ParseTumText(text, source);
}

Status WriteTum(const std::string& path, const Trajectory& trajectory, const std::string& header) {
  AtomicFileWriter writer;
  if (Status s = writer.Open(path); !s.ok()) return s;
  std::string block;
  size_t start = 0;
  while (!header.empty() && start <= header.size()) {
    const size_t end = std::min(header.find('\n', start), header.size());
    block += "# " + header.substr(start, end - start) + "\n";
    start = end + 1;
  }
  block += kTumColumnsComment;
  for (const StampedPose& pose : trajectory) {
    block += FormatTumLine(pose);
    if (block.size() > (1 << 16)) {
      if (Status s = writer.Append(block); !s.ok()) return s;
      block.clear();
    }
  }
  if (Status s = writer.Append(block); !s.ok()) return s;
  return writer.Commit();
}

size_t FirstStampOrderViolation(const Trajectory& trajectory, bool* earlier) {
  for (size_t i = 1; i < trajectory.size(); ++i) {
    *earlier = trajectory[i].t_ns < trajectory[i - 1].t_ns;
    if (*earlier || (i >= 2 && trajectory[i].t_ns == trajectory[i - 2].t_ns)) return i;
  }
  return 0;
}

}  // namespace rvlio
