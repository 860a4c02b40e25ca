#pragma once
// Trajectory files.
//
// TUM:   one pose per line, `t x y z qx qy qz qw` (t in seconds, position in
//        metres, Hamilton quaternion of the body in the world frame).
// KITTI: one pose per line, the 12 values of the 3x4 matrix [R | t] row by
//        row; times from a separate file (one value in seconds per line, e.g.
//        KITTI's times.txt) or, without one, an assumed constant rate.
//
// Both readers accept blank lines and '#' comments. Errors name the file and
// the line: unreadable file, no poses, wrong number of values, a value that is
// not a finite number, a zero quaternion or a matrix that is not a rotation,
// and a time stamp earlier than the previous one (equal stamps are accepted,
// as evo does). Non-unit quaternions are normalized.
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"

namespace rvlio {

StatusOr<Trajectory> ReadTum(const std::string& path);

// `times_path` empty: t_i = i / rate_hz (s). Otherwise the times file must
// hold exactly one stamp per pose.
StatusOr<Trajectory> ReadKitti(const std::string& path, const std::string& times_path = "",
                               double rate_hz = 10.0);

// Detects the format from the value count of the first data line: 8 -> TUM,
// 12 -> KITTI (read with ReadKitti(path, kitti_times_path, kitti_rate_hz)).
StatusOr<Trajectory> ReadTrajectory(const std::string& path,
                                    const std::string& kitti_times_path = "",
                                    double kitti_rate_hz = 10.0);

// The stamp order every trajectory reader enforces: stamps must increase; a
// stamp repeated once is accepted (evo accepts it, and the TUM RGB-D ground
// truth has one); a third pose at one stamp is refused (stamps written with
// too few digits, 1.7e+09, collapse into runs of equal values). Returns the
// index of the first pose breaking it (0: none); *earlier tells whether it
// goes back in time (else it is the third of equal stamps).
size_t FirstStampOrderViolation(const Trajectory& trajectory, bool* earlier);

// The same parsers on text in memory (the file readers above read the file
// and parse it with these); `source` stands for the path in error messages.
StatusOr<Trajectory> ParseTumText(const std::string& text, const std::string& source);
// KITTI poses at a constant rate: t_i = i / rate_hz (s).
StatusOr<Trajectory> ParseKittiText(const std::string& text, const std::string& source,
                                    double rate_hz = 10.0);
// KITTI poses with the text of a times file (one stamp per pose).
StatusOr<Trajectory> ParseKittiText(const std::string& text, const std::string& source,
                                    const std::string& times_text,
                                    const std::string& times_source);
// Format detected like ReadTrajectory; KITTI at a constant rate.
StatusOr<Trajectory> ParseTrajectoryText(const std::string& text, const std::string& source,
                                         double kitti_rate_hz = 10.0);

// Formats one TUM line (with '\n'): time with 9 decimals (exact ns), position
// with 9 decimals (nm), quaternion with 12 decimals.
std::string FormatTumLine(const StampedPose& pose);

// The trajectory as its TUM file holds it (FormatTumLine's decimals, read
// back as ReadTum reads them): what `rvlio eval` and `refine --init` see of
// it, without the file. `source` names it in error messages (no poses).
StatusOr<Trajectory> RoundTripTum(const Trajectory& trajectory, const std::string& source);

// The comment line naming the columns, after the header of every TUM file we write.
inline constexpr const char* kTumColumnsComment = "# t x y z qx qy qz qw\n";

// Writes a TUM file atomically (formats/atomic_file.h); `header`, when not empty,
// is written first as '#' comment lines.
Status WriteTum(const std::string& path, const Trajectory& trajectory,
                const std::string& header = "");

// Exact decimal seconds ("1305031102.160407", "-0.5", "12") to ns without a
// detour through double, rounding beyond 9 decimals to nearest; exponent
// notation ("1.3e9") is accepted through double. False if not a number or out
// of the int64 ns range.
bool ParseSecondsToNs(const std::string& text, TimeNs* t_ns);

}  // namespace rvlio
