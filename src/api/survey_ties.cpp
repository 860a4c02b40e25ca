// SurveyTies (api/survey_ties.h): control points, check points, wall targets
// and GNSS fixes around `rvlio refine` (docs/control.md).
#include "rvlio/api/survey_ties.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "rvlio/math/pose_interpolation.h"
#include "rvlio/common/check.h"
#include "rvlio/common/fnv1a.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/crs.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/lidar/extrinsics.h"

namespace rvlio {
namespace {

constexpr int kAlignmentPasses = 10;  // of the reweighted alignment (converged well before)

Eigen::Vector3d LeverArm(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

std::string Seconds(TimeNs t_ns) { return FormatFixed(NsToSeconds(t_ns), 3); }

RestDetectorOptions RestOptions(const ControlOptions& c) {
  RestDetectorOptions r;
  r.window_s = c.rest_window_s;
  r.gyro_std = c.rest_gyro_std;
  r.accel_std = c.rest_accel_std;
  r.min_duration_s = c.min_rest_s;
  return r;
}

bool Overlaps(const RestPeriod& rest, const ControlRow& row) {
  return rest.t_begin_ns <= row.t_end_ns && row.t_start_ns <= rest.t_end_ns;
}

// RMS and largest 3D residual of the estimated rows of one role.
nlohmann::json RoleJson(const std::vector<ControlResidual>& rows, ControlRole role) {
  const ControlRoleSummary r = SummarizeControlRole(rows, role);
  nlohmann::json j = {{"count", r.count}};
  if (r.count == 0) return j;
  j["rms_m"] = r.rms_m;
  j["rms_xyz_m"] = {r.rms_xyz_m.x(), r.rms_xyz_m.y(), r.rms_xyz_m.z()};
  j["max_m"] = r.max_m;
  j["max_name"] = r.max_name;
  return j;
}

// The message's covariance (ENU, taken as the projected CRS's axes: the
// grid's meridian convergence, a degree or two, is neglected) when it has
// one and gnss.use_covariance, else gnss.sigma_m per axis.
SurveyFix ToSurveyFix(const NavSatFix& m, const Eigen::Vector3d& p_survey,
                      const GnssOptions& gnss) {
  SurveyFix f;
  f.t_ns = m.header_stamp_ns;
  f.p_survey = p_survey;
  f.sigma_m = gnss.sigma_m;
  f.sqrt_information = IsotropicSqrtInformation(gnss.sigma_m);
  if (!gnss.use_covariance || m.covariance_type == 0) return f;
  const Eigen::Matrix3d cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
      m.position_covariance.data());
  Eigen::Matrix3d W;
  if (!SqrtInformationOf(cov, &W)) return f;
  f.sqrt_information = W;
  f.sigma_m = std::sqrt(cov.trace() / 3.0);
  return f;
}

}  // namespace

SurveyTies::SurveyTies(std::string control_path, std::vector<ControlRow> rows,
                       std::vector<SurveyFix> fixes, const Configuration& options,
                       const LocalOrigin& init_origin)
    : control_path_(std::move(control_path)),
      rows_(std::move(rows)),
      fixes_(std::move(fixes)),
      control_(options.control),
      gnss_(options.gnss),
      sightings_({}, options.control.target_radius_m, options.control.target_max_scans) {
  for (size_t i = 0; i < rows_.size(); ++i) {
    if (!rows_[i].target) continue;
    target_points_.push_back(init_origin.ToLocal(rows_[i].p_map));
    target_rows_.push_back(static_cast<int>(i));
  }
  sightings_ = TargetSightings(target_points_, control_.target_radius_m, control_.target_max_scans);
  T_imu_lidar_ = ImuTLidar(options.extrinsics);
}

std::string SurveyTies::Where(const ControlRow& row) const {
  return control_path_ + " line " + std::to_string(row.line) + " (" + row.name + ")";
}

void SurveyTies::ObserveImu(const ImuSample& imu) {
  if (!rows_.empty()) imu_.push_back(imu);
}

void SurveyTies::ObserveScan(const Scan& scan, const Trajectory& init) {
  Pose3 T_world_imu;
  if (!InterpolatePose(init, scan.t_end_ns, &T_world_imu)) return;
  sightings_.AddScan(scan, T_world_imu, T_imu_lidar_);
}

// Stop-and-go rows without t_start,t_end take the rest periods the IMU
// shows (those not overlapping a row's given period), in order.
Status SurveyTies::PairRestPeriods() {
  std::vector<ControlRow*> open;
  for (ControlRow& row : rows_)
    if (!row.target && !row.has_times) open.push_back(&row);
  if (open.empty()) return Status::Ok();
  std::sort(imu_.begin(), imu_.end(),
            [](const ImuSample& a, const ImuSample& b) { return a.t_ns < b.t_ns; });
  std::vector<RestPeriod> rests;
  for (const RestPeriod& rest : FindRestPeriods(imu_, RestOptions(control_))) {
    const bool given = std::any_of(rows_.begin(), rows_.end(), [&](const ControlRow& row) {
      return !row.target && row.has_times && Overlaps(rest, row);
    });
    if (!given) rests.push_back(rest);
  }
  if (rests.size() != open.size())
    return Status::InvalidInput(
        control_path_ + ": " + std::to_string(open.size()) +
        " stop-and-go row(s) without t_start,t_end, but the IMU shows " +
        std::to_string(rests.size()) + " rest period(s) of at least control.min_rest_s (" +
        FormatG(control_.min_rest_s) +
        " s); give the rows t_start,t_end or change control.min_rest_s (docs/control.md)");
  for (size_t i = 0; i < open.size(); ++i) {
    open[i]->t_start_ns = rests[i].t_begin_ns;
    open[i]->t_end_ns = rests[i].t_end_ns;
  }
  return Status::Ok();
}

// A mark's tie: the middle of the part of its rest period that the initial
// trajectory covers; the mark in the IMU frame is -control.lever_arm.
Status SurveyTies::MarkTies(const Trajectory& init) {
  const Eigen::Vector3d p_imu_mark = -LeverArm(control_.lever_arm);
  for (size_t i = 0; i < rows_.size(); ++i) {
    const ControlRow& row = rows_[i];
    ControlResidual& r = residuals_[i];
    if (row.target) continue;
    r.kind = "mark";
    const TimeNs a = std::max(row.t_start_ns, init.front().t_ns);
    const TimeNs b = std::min(row.t_end_ns, init.back().t_ns);
    if (a > b)
      return Status::InvalidInput(Where(row) + ": its rest period " + Seconds(row.t_start_ns) +
                                  " .. " + Seconds(row.t_end_ns) +
                                  " s lies outside the --init trajectory (" +
                                  Seconds(init.front().t_ns) + " .. " +
                                  Seconds(init.back().t_ns) + " s)");
    r.t_ns = a + (b - a) / 2;
    RVLIO_CHECK(TiePointOnTrajectory(init, r.t_ns, p_imu_mark, &row_frame_points_[i]));
    PositionTie tie;
    tie.t_ns = r.t_ns;
    tie.p_imu_point = p_imu_mark;
    tie.p_world = row.p_survey;
    tie.sqrt_information = IsotropicSqrtInformation(r.sigma_m);
    tie.kernel = control_.kernel;
    tie.kernel_sigmas = control_.kernel_sigmas;
    row_ties_[i] = {tie};
  }
  return Status::Ok();
}

// A target's ties: one per scan that saw it, its sigma times sqrt(scans) so
// that together they weigh as one measurement.
Status SurveyTies::TargetTies() {
  for (size_t t = 0; t < target_rows_.size(); ++t) {
    const ControlRow& row = rows_[target_rows_[t]];
    ControlResidual& r = residuals_[target_rows_[t]];
    r.kind = "target";
    const std::vector<TargetSighting>& seen = sightings_.sightings()[t];
    if (seen.empty())
      return Status::InvalidInput(
          Where(row) + ": no scan saw the target (" + FormatFixed(row.p_map.x(), 3) + ", " +
          FormatFixed(row.p_map.y(), 3) + ", " + FormatFixed(row.p_map.z(), 3) +
          ") within control.target_radius_m (" + FormatG(control_.target_radius_m) +
          " m) at the --init poses; is it a point of that run's map.pcd?");
    r.scans = static_cast<int>(seen.size());
    r.t_ns = seen.front().t_ns;
    row_frame_points_[target_rows_[t]] = target_points_[t];
    const double sigma = r.sigma_m * std::sqrt(static_cast<double>(seen.size()));
    for (const TargetSighting& s : seen) {
      PositionTie tie;
      tie.t_ns = s.t_ns;
      tie.p_imu_point = s.p_imu_point;
      tie.p_world = row.p_survey;
      tie.sqrt_information = IsotropicSqrtInformation(sigma);
      tie.kernel = control_.kernel;
      tie.kernel_sigmas = control_.kernel_sigmas;
      row_ties_[target_rows_[t]].push_back(tie);
    }
  }
  return Status::Ok();
}

void SurveyTies::FixTies(const Trajectory& init) {
  const Eigen::Vector3d lever = LeverArm(gnss_.lever_arm);
  for (const SurveyFix& f : fixes_) {
    Eigen::Vector3d p_frame;
    if (!TiePointOnTrajectory(init, f.t_ns, lever, &p_frame)) {
      ++fixes_outside_init_;
      continue;
    }
    PositionTie tie;
    tie.t_ns = f.t_ns;
    tie.p_imu_point = lever;
    tie.p_world = f.p_survey;
    tie.sqrt_information = f.sqrt_information;
    tie.kernel = gnss_.kernel;
    tie.kernel_sigmas = gnss_.kernel_sigmas;
    fix_ties_.push_back(tie);
    fix_frame_points_.push_back(p_frame);
    fix_sigma_m_.push_back(f.sigma_m);
  }
  fix_outlier_.assign(fix_ties_.size(), false);
}

// Control rows and fixes (not outliers) fix the frame; check rows never do.
// Iteratively reweighted: each point's weight 1/sigma^2 times its kernel's
// weight at its residual of the previous fit (the kernels of the solve:
// Cauchy for fixes, Huber for marks), so that a few multipath fixes do not
// shift the frame; fixes farther than gnss.max_distance_m are left out.
Status SurveyTies::Align(bool hold_frame, const LocalOrigin& init_origin) {
  if (hold_frame) {  // the --init frame is the survey frame, moved by init_origin
    alignment_.T_survey_frame = Pose3(Eigen::Matrix3d::Identity(), init_origin.t_user_local);
    return Status::Ok();
  }
  std::vector<double> row_kernel(rows_.size(), 1.0), fix_kernel(fix_ties_.size(), 1.0);
  for (int pass = 0; pass < kAlignmentPasses; ++pass) {
    std::vector<AlignmentPoint> points;
    for (size_t i = 0; i < rows_.size(); ++i)
      if (rows_[i].role == ControlRole::kControl)
        points.push_back({row_frame_points_[i], rows_[i].p_survey,
                          row_kernel[i] / (residuals_[i].sigma_m * residuals_[i].sigma_m)});
    for (size_t i = 0; i < fix_ties_.size(); ++i)
      if (!fix_outlier_[i])
        points.push_back({fix_frame_points_[i], fix_ties_[i].p_world,
                          fix_kernel[i] / (fix_sigma_m_[i] * fix_sigma_m_[i])});
    StatusOr<YawTranslation> fit = FitYawTranslation(points, control_.min_spread_m,
                                                     control_.tilt_sigma_deg * M_PI / 180.0);
    if (!fit.ok())
      return Status::InvalidInput((rows_.empty() ? "gnss.topic" : control_path_) +
                                  ": the control points and GNSS fixes: " + fit.status().message());
    alignment_ = *fit;
    aligned_ = true;
    const Pose3& T = alignment_.T_survey_frame;
    for (size_t i = 0; i < rows_.size(); ++i) {
      const double d = (T * row_frame_points_[i] - rows_[i].p_survey).norm();
      row_kernel[i] = TieKernelWeight(control_.kernel, control_.kernel_sigmas, d / residuals_[i].sigma_m);
    }
    for (size_t i = 0; i < fix_ties_.size(); ++i) {
      const double d = (T * fix_frame_points_[i] - fix_ties_[i].p_world).norm();
      fix_outlier_[i] = d > gnss_.max_distance_m;
      fix_kernel[i] = TieKernelWeight(gnss_.kernel, gnss_.kernel_sigmas, d / fix_sigma_m_[i]);
    }
  }
  return Status::Ok();
}

// Every mark and target (control or check) must lie within
// control.max_distance_m of the aligned trajectory: the farthest is named.
Status SurveyTies::CheckDistances() const {
  const Pose3& T = alignment_.T_survey_frame;
  double worst = -1.0;
  size_t worst_row = 0;
  for (size_t i = 0; i < rows_.size(); ++i) {
    const double d = (T * row_frame_points_[i] - rows_[i].p_survey).norm();
    if (d > worst) worst = d, worst_row = i;
  }
  if (rows_.empty() || worst <= control_.max_distance_m) return Status::Ok();
  return Status::InvalidInput(Where(rows_[worst_row]) + ": " + FormatFixed(worst, 3) +
                              " m from the trajectory after the alignment (control.max_distance_m " +
                              FormatG(control_.max_distance_m) +
                              "); a typo in its coordinates, or another frame?");
}

Status SurveyTies::Prepare(bool hold_frame, LocalOrigin* origin, Trajectory* init,
                           SurveyFactors* out) {
  std::vector<PositionTie>* ties = &out->ties;
  residuals_.assign(rows_.size(), {});
  row_ties_.assign(rows_.size(), {});
  row_frame_points_.assign(rows_.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < rows_.size(); ++i)
    residuals_[i].sigma_m = rows_[i].sigma_m > 0.0 ? rows_[i].sigma_m : control_.sigma_m;
  int control_rows = 0;
  for (const ControlRow& row : rows_) control_rows += row.role == ControlRole::kControl ? 1 : 0;
  if (fixes_.empty() && control_rows < 2)
    return Status::InvalidInput(
        control_path_ + ": " + std::to_string(control_rows) +
        " control point(s) (role control); at least 2 are needed to fix the survey frame (check "
        "points do not count), or GNSS fixes (gnss.topic)");
  if (Status s = PairRestPeriods(); !s.ok()) return s;
  for (size_t i = 0; i < rows_.size(); ++i) residuals_[i].row = rows_[i];
  imu_.clear();
  imu_.shrink_to_fit();
  if (Status s = MarkTies(*init); !s.ok()) return s;
  if (Status s = TargetTies(); !s.ok()) return s;
  FixTies(*init);
  if (Status s = Align(hold_frame, *origin); !s.ok()) return s;
  if (Status s = CheckDistances(); !s.ok()) return s;
  // The local frame: the survey frame minus an origin chosen from the ties
  // (math/local_origin.h); with hold_frame the --init one.
  if (!hold_frame) {
    std::vector<Eigen::Vector3d> p_survey;
    for (const ControlRow& row : rows_) p_survey.push_back(row.p_survey);
    for (const PositionTie& t : fix_ties_) p_survey.push_back(t.p_world);
    *origin = ChooseLocalOrigin(p_survey);
  }
  origin_ = *origin;
  const Pose3 T_local_frame =
      Pose3(Eigen::Matrix3d::Identity(), -origin_.t_user_local) * alignment_.T_survey_frame;
  for (StampedPose& p : *init) {
    const Pose3 T = T_local_frame * Pose3(p.q_world_imu, p.p_world_imu);
    p.p_world_imu = T.t;
    p.q_world_imu = T.quaternion();
  }
  ties->clear();
  auto add = [&](PositionTie tie) {
    tie.p_world = origin_.ToLocal(tie.p_world);
    ties->push_back(tie);
  };
  for (size_t i = 0; i < rows_.size(); ++i)
    if (rows_[i].role == ControlRole::kControl)
      for (const PositionTie& t : row_ties_[i]) add(t);
  for (size_t i = 0; i < fix_ties_.size(); ++i)
    if (!fix_outlier_[i]) add(fix_ties_[i]);
  std::sort(ties->begin(), ties->end(),
            [](const PositionTie& a, const PositionTie& b) { return a.t_ns < b.t_ns; });
  out->rests.clear();
  for (const ControlRow& row : rows_)  // a check mark's rest is a rest too
    if (!row.target) out->rests.push_back({row.t_start_ns, row.t_end_ns});
  out->rest_sigma_v = control_.rest_sigma_v;
  return Status::Ok();
}

void SurveyTies::Evaluate(const Trajectory& refined_local) {
  for (size_t i = 0; i < rows_.size(); ++i) {
    ControlResidual& r = residuals_[i];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0;
    for (const PositionTie& t : row_ties_[i]) {
      Eigen::Vector3d p;
      if (!TiePointOnTrajectory(refined_local, t.t_ns, t.p_imu_point, &p)) continue;
      sum += p;
      ++n;
    }
    r.estimated = n > 0;
    if (!r.estimated) continue;
    r.p_estimated = origin_.ToUser(sum / n);
    const double d = r.Residual().norm();
    if (rows_[i].role == ControlRole::kControl && d > control_.warn_sigmas * r.sigma_m)
      warnings_.push_back("control point " + rows_[i].name + " (" + control_path_ + " line " +
                          std::to_string(rows_[i].line) + "): residual " + FormatFixed(d, 4) +
                          " m after the solve, " + FormatFixed(d / r.sigma_m, 1) +
                          " sigma (control.warn_sigmas " + FormatG(control_.warn_sigmas) + ")");
  }
  fix_residual_m_.clear();
  for (size_t i = 0; i < fix_ties_.size(); ++i) {
    Eigen::Vector3d p;
    if (TiePointOnTrajectory(refined_local, fix_ties_[i].t_ns, fix_ties_[i].p_imu_point, &p))
      fix_residual_m_.push_back((origin_.ToUser(p) - fix_ties_[i].p_world).norm());
  }
}

std::string SurveyTies::ControlCsv() const { return ControlCsvText(residuals_); }

nlohmann::json SurveyTies::SurveyJson(const std::string& crs) const {
  int control = 0, check = 0, targets = 0;
  for (const ControlRow& row : rows_) {
    (row.role == ControlRole::kControl ? control : check) += 1;
    targets += row.target ? 1 : 0;
  }
  const int outliers = GnssOutliers();
  nlohmann::json j = {{"crs", crs},
                      {"control_file", control_path_},
                      {"control_points", control},
                      {"check_points", check},
                      {"targets", targets},
                      {"gnss_fixes", fix_ties_.size() - outliers},
                      {"gnss_outliers", outliers},
                      {"gnss_outside_init", fixes_outside_init_},
                      {"gnss_messages", gnss_stats_.messages},
                      {"gnss_no_fix", gnss_stats_.no_fix}};
  if (aligned_) {
    const Eigen::Vector3d& t = alignment_.T_survey_frame.t;
    j["alignment"] = {{"yaw_deg", alignment_.yaw_deg},
                      {"tilt_deg", {alignment_.tilt_deg[0], alignment_.tilt_deg[1]}},
                      {"translation_m", {t.x(), t.y(), t.z()}},
                      {"spread_m", alignment_.spread_m}};
  }
  if (!fix_residual_m_.empty()) {
    double sum2 = 0.0;
    for (double d : fix_residual_m_) sum2 += d * d;
    j["gnss_rms_m"] = std::sqrt(sum2 / fix_residual_m_.size());
  }
  return j;
}

nlohmann::json SurveyTies::ControlJson() const { return ControlSummaryJson(residuals_); }

int SurveyTies::GnssOutliers() const {
  int outliers = 0;
  for (bool o : fix_outlier_) outliers += o ? 1 : 0;
  return outliers;
}

uint64_t SurveyTies::ContentHash() const {
  Fnv1a h;
  for (const ControlRow& row : rows_) {
    h.AddText(row.name);
    for (int a = 0; a < 3; ++a) h.Add(row.p_survey[a]), h.Add(row.p_map[a]);
    h.Add(static_cast<int>(row.role));
    h.Add(row.sigma_m);
    h.Add(row.has_times);
    h.Add(row.t_start_ns);
    h.Add(row.t_end_ns);
    h.Add(row.target);
  }
  for (const SurveyFix& f : fixes_) {
    h.Add(f.t_ns);
    for (int a = 0; a < 3; ++a) h.Add(f.p_survey[a]);
    for (int a = 0; a < 9; ++a) h.Add(f.sqrt_information(a));
  }
  return h.value();
}

StatusOr<std::unique_ptr<SurveyTies>> OpenSurveyTies(const std::string& control_path,
                                                     const std::string& bag,
                                                     const Configuration& options,
                                                     const LocalOrigin& init_origin) {
  std::vector<ControlRow> rows;
  if (!control_path.empty()) {
    StatusOr<std::vector<ControlRow>> read = ReadControlFile(control_path);
    if (!read.ok()) return read.status();
    rows = std::move(*read);
  }
  std::vector<SurveyFix> fixes;
  NavSatFixStats stats;
  if (!options.gnss.topic.empty()) {
    StatusOr<std::vector<SurveyFix>> read = ReadSurveyFixes(bag, options, &stats);
    if (!read.ok()) return read.status();
    fixes = std::move(*read);
  }
  if (rows.empty() && fixes.empty()) {
    if (options.gnss.topic.empty()) return std::unique_ptr<SurveyTies>();
    return Status::InvalidInput("gnss.topic '" + options.gnss.topic + "' in '" + bag +
                                "': no fix with a solution (" + std::to_string(stats.messages) +
                                " messages, " + std::to_string(stats.no_fix) + " without)");
  }
  auto ties = std::make_unique<SurveyTies>(control_path, std::move(rows), std::move(fixes),
                                           options, init_origin);
  ties->set_gnss_stats(stats);
  return ties;
}

StatusOr<std::vector<SurveyFix>> ReadSurveyFixes(const std::string& bag,
                                                 const Configuration& options,
                                                 NavSatFixStats* stats) {
  if (IsLocalCrs(options.survey.crs))
    return Status::InvalidInput(
        "gnss.topic '" + options.gnss.topic +
        "' needs survey.crs: the projected coordinate reference system the fixes go into (e.g. "
        "EPSG:25832); 'local' has none");
  StatusOr<GeodeticToCrs> to_crs = GeodeticToCrs::Create(options.survey.crs);
  if (!to_crs.ok()) return to_crs.status();
  StatusOr<std::vector<NavSatFix>> read = ReadNavSatFixes(bag, options.gnss.topic, stats);
  if (!read.ok()) return read.status();
  std::vector<SurveyFix> fixes;
  for (const NavSatFix& m : *read) {
    StatusOr<Eigen::Vector3d> p = to_crs->Transform(m.latitude_deg, m.longitude_deg, m.altitude_m);
    if (!p.ok())
      return Status::InvalidInput("gnss.topic '" + options.gnss.topic + "' in '" + bag +
                                  "': the fix at " + FormatFixed(NsToSeconds(m.header_stamp_ns), 3) +
                                  " s: " + p.status().message());
    fixes.push_back(ToSurveyFix(m, *p, options.gnss));
  }
  return fixes;
}

void DeliverInSurveyFrame(SurveyTies* survey, RefineRunResult* r) {
  survey->Evaluate(r->refine.trajectory);
  if (survey->has_control_file()) r->control_csv = survey->ControlCsv();
  r->control = survey->residuals();
  r->gnss_outliers = survey->GnssOutliers();
  r->gnss_fixes = survey->GnssFixes() - r->gnss_outliers;
  r->refine.warnings.insert(r->refine.warnings.end(), survey->warnings().begin(),
                            survey->warnings().end());
}

void AddSurveySummary(const SurveyTies& survey, const std::string& crs, nlohmann::json* summary) {
  (*summary)["survey"] = survey.SurveyJson(crs);
  (*summary)["control"] = survey.ControlJson();
}

nlohmann::json ControlSummaryJson(const std::vector<ControlResidual>& rows) {
  return {{"control", RoleJson(rows, ControlRole::kControl)},
          {"check", RoleJson(rows, ControlRole::kCheck)}};
}

std::vector<ControlResidual> MergeChunkControl(const std::vector<ChunkControl>& chunks) {
  std::vector<ControlResidual> merged = chunks.front().rows;
  for (ControlResidual& r : merged) {
    r.estimated = false;
    for (const ChunkControl& c : chunks) {
      if (r.t_ns < c.core_begin_ns || r.t_ns > c.core_end_ns) continue;
      for (const ControlResidual& e : c.rows) {
        if (e.row.name != r.row.name || !e.estimated) continue;
        r.p_estimated = c.T_merged_chunk * e.p_estimated;
        r.estimated = true;
      }
      if (r.estimated) break;
    }
  }
  return merged;
}

}  // namespace rvlio
