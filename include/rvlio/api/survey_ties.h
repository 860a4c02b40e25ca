#pragma once
// `rvlio refine --control FILE` and `gnss.topic` (docs/control.md): what the
// I/O layer does around the refinement to deliver it in the survey frame.
//
//   before reading   the control file and the GNSS fixes (already in the
//                    survey frame through PROJ) are checked;
//   while reading    every IMU sample is seen (the rest periods of
//                    stop-and-go marks) and every raw scan (wall targets);
//   before refining  each mark, target and fix becomes a PositionTie; the
//                    initial trajectory is carried into the survey frame by
//                    the yaw-and-translation fit (refine/control.h), then
//                    into a local frame near the ties (the survey's
//                    coordinates are large) where the refinement runs;
//   after refining   the residual of every row of the control file
//                    (control.csv), summary.json's "survey" and "control",
//                    and the warnings.
// Every refusal is InvalidInput naming the control file and line, or the key.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "rvlio/common/status.h"
#include "rvlio/api.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/control_file.h"
#include "rvlio/formats/navsatfix.h"
#include "rvlio/imu/rest.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/math/pose.h"
#include "rvlio/config/configuration.h"
#include "rvlio/refine/control.h"

namespace rvlio {

// A GNSS fix in the survey frame.
struct SurveyFix {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_survey = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Identity();
  double sigma_m = 0.03;  // a scalar for the alignment's weight (root of the mean variance)
};

class SurveyTies {
 public:
  // rows: the control file's (may be empty with GNSS only); fixes: GNSS.
  // init_origin: of the local frame the --init trajectory is read into
  // (targets' map_x, map_y, map_z are in the --init frame).
  SurveyTies(std::string control_path, std::vector<ControlRow> rows, std::vector<SurveyFix> fixes,
             const Configuration& options, const LocalOrigin& init_origin = LocalOrigin());

  bool active() const { return !rows_.empty() || !fixes_.empty(); }
  // The raw IMU samples and scans of the recording as they are read (scans
  // with their --init pose at the end, local frame; see NeedsScans).
  void ObserveImu(const ImuSample& imu);
  bool NeedsScans() const { return !sightings_.empty(); }
  void ObserveScan(const Scan& scan, const Trajectory& init);

  // Builds the ties from `init` (in the local frame of *origin: the frame of
  // --init, or of --map, minus *origin, math/local_origin.h), fits the
  // alignment and carries `init` into the survey frame's local frame, whose
  // origin (chosen from the ties) replaces *origin. With hold_frame (a --map
  // fixes the frame and --init is in it) the frame and *origin stay. *out:
  // the ties in the local frame (control points and fixes only) and the rests
  // of the stop-and-go control and check marks.
  Status Prepare(bool hold_frame, LocalOrigin* origin, Trajectory* init, SurveyFactors* out);
  const LocalOrigin& origin() const { return origin_; }
  // After the refinement: the residuals at the refined trajectory (local frame).
  void Evaluate(const Trajectory& refined_local);

  std::string ControlCsv() const;  // control.csv
  nlohmann::json SurveyJson(const std::string& crs) const;
  nlohmann::json ControlJson() const;
  const std::vector<std::string>& warnings() const { return warnings_; }
  const std::vector<ControlResidual>& residuals() const { return residuals_; }
  bool has_control_file() const { return !control_path_.empty(); }
  int GnssFixes() const { return static_cast<int>(fix_ties_.size()); }  // ties, outliers included
  int GnssOutliers() const;  // left out by the robust alignment
  // FNV-1a of the rows and fixes: part of a checkpoint's fingerprint.
  uint64_t ContentHash() const;
  void set_gnss_stats(const NavSatFixStats& stats) { gnss_stats_ = stats; }

 private:
  Status PairRestPeriods();
  Status MarkTies(const Trajectory& init);
  Status TargetTies();
  void FixTies(const Trajectory& init);
  Status Align(bool hold_frame, const LocalOrigin& init_origin);
  Status CheckDistances() const;
  std::string Where(const ControlRow& row) const;

  std::string control_path_;
  std::vector<ControlRow> rows_;
  std::vector<SurveyFix> fixes_;
  ControlOptions control_;
  GnssOptions gnss_;
  std::vector<ImuSample> imu_;
  Pose3 T_imu_lidar_;
  std::vector<Eigen::Vector3d> target_points_;  // per target row, in the --init local frame
  std::vector<int> target_rows_;
  TargetSightings sightings_;
  // Per row: its tie time window (marks) and ties in the survey frame.
  std::vector<ControlResidual> residuals_;
  std::vector<std::vector<PositionTie>> row_ties_;  // survey frame
  std::vector<Eigen::Vector3d> row_frame_points_;   // the row's point in the --init frame
  std::vector<PositionTie> fix_ties_;               // survey frame
  std::vector<Eigen::Vector3d> fix_frame_points_;
  std::vector<double> fix_sigma_m_;
  std::vector<bool> fix_outlier_;
  int fixes_outside_init_ = 0;
  YawTranslation alignment_;  // T_survey_frame: from the --init local frame
  bool aligned_ = false;
  LocalOrigin origin_;  // of the local frame the refinement runs in
  std::vector<double> fix_residual_m_;
  std::vector<std::string> warnings_;
  NavSatFixStats gnss_stats_;
};

// The control file (empty path: none) and, with gnss.topic, the recording's
// fixes in the survey frame (formats/navsatfix.h, PROJ); null when neither
// is given. InvalidInput naming the file, line, topic or key.
StatusOr<std::unique_ptr<SurveyTies>> OpenSurveyTies(const std::string& control_path,
                                                     const std::string& bag,
                                                     const Configuration& options,
                                                     const LocalOrigin& init_origin);
// The recording's NavSatFix fixes (gnss.topic) in survey.crs.
StatusOr<std::vector<SurveyFix>> ReadSurveyFixes(const std::string& bag,
                                                 const Configuration& options,
                                                 NavSatFixStats* stats);

// summary.json "control": per role count, rms_m, rms_xyz_m, max_m, max_name.
nlohmann::json ControlSummaryJson(const std::vector<ControlResidual>& rows);

// `rvlio merge` of chunk jobs refined with --control: each row's estimate
// from the chunk whose own span (chunk.json core_begin_ns .. core_end_ns)
// holds the row's tie time, carried into the merged frame by that chunk's
// transform (user frame); rows no chunk estimated stay without an estimate.
struct ChunkControl {
  std::vector<ControlResidual> rows;  // the chunk's control.csv
  TimeNs core_begin_ns = 0, core_end_ns = 0;
  Pose3 T_merged_chunk;  // in the user (survey) frame
};
std::vector<ControlResidual> MergeChunkControl(const std::vector<ChunkControl>& chunks);

// After the refinement, before its outputs leave the local frame: the
// residuals, control.csv's text and the warnings into *r.
void DeliverInSurveyFrame(SurveyTies* survey, RefineRunResult* r);
// summary.json's "survey" and "control".
void AddSurveySummary(const SurveyTies& survey, const std::string& crs, nlohmann::json* summary);

}  // namespace rvlio
