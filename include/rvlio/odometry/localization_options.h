#pragma once
// The options of localization in a reference map (section `localization`,
// `rvlio run --map`; the localization: odometry/reference.h). Options only,
// so that odometry/options.h holds the configuration without the
// localization's code.
#include <string>

#include "rvlio/common/options.h"
#include "rvlio/common/status.h"
#include "rvlio/odometry/deviation.h"

namespace rvlio {

struct LocalizationOptions {
  double min_overlap = 0.3;        // share of a scan's points on reference planes to count as localized
  double align_radius_max = 2.0;   // m, first (coarsest) association radius of the start alignment
  double align_radius_min = 0.2;   // m, last (finest) radius; each stage halves the radius
  int align_iterations = 6;        // Gauss-Newton iterations per radius
  double min_start_overlap = 0.3;  // the aligned first scan must overlap the reference this much
  double max_start_distance = 10.0;  // m, a reference point must lie this close to the initial position
  double min_start_axis_constraints = 5.0;   // the aligned first scan must fix every translation axis this well
  bool trust_initial_pose = false;  // take the initial pose along an axis the first scan does not fix
  double search_step = 2.0;         // m, position grid of the global search (no initial pose)
  double search_yaw_step = 15.0;    // deg, yaw step of the global search
  int search_keep = 20;             // best grid candidates aligned in full
  double search_ambiguity = 0.03;   // a distinct candidate within this fit of the best: ambiguous
  double start_check_radius = 3.0;  // m, an initial pose is checked against the candidates within this of it (0: not)
  double min_start_fit = 0.9;       // share of the aligned start's matched points within 3 lidar_noise of their plane
  double reference_voxel_size = 0.5;  // m, voxel edge of the reference's search structure
  // k-NN search in the reference: the 27 voxels around the query, or exact
  // (map.neighbor_search's choices). A reference is complete around the
  // sensor, so the k nearest nearly always lie in those voxels (where the
  // working map, holding only what the flight has seen, often has them
  // farther: map.neighbor_search stays exact); measured in docs/survey.md.
  std::string reference_neighbor_search = "nearby";
  DeviationOptions deviation;       // deviation_m of map.pcd and deviation.csv

  template <class V>
  void Visit(V& v) {
    v.Field("min_overlap", min_overlap, Spec().Range(0.0, 1.0)
        .Help("share of a scan's points with a reference plane below which the scan is matched to the working map (out of the reference)"));
    v.Field("align_radius_max", align_radius_max, Spec().Unit("m").Range(0.05, 20.0)
        .Help("first association radius of the alignment of the first scan to the reference"));
    v.Field("align_radius_min", align_radius_min, Spec().Unit("m").Range(0.01, 20.0)
        .Help("last association radius of that alignment (the radius halves per stage)"));
    v.Field("align_iterations", align_iterations, Spec().Range(1, 100)
        .Help("Gauss-Newton iterations per radius of that alignment"));
    v.Field("min_start_overlap", min_start_overlap, Spec().Range(0.0, 1.0)
        .Help("the aligned first scan must have this share of its points on reference planes, else the run stops (exit 2)"));
    v.Field("max_start_distance", max_start_distance, Spec().Unit("m").Positive()
        .Help("the reference must have a point this close to the initial position, else it is taken to be in another frame or unit (exit 2)"));
    v.Field("min_start_axis_constraints", min_start_axis_constraints, Spec().Range(0.0, 1e9)
        .Help("the aligned first scan must hold its least-fixed translation direction d as well as this many constraints along d would (lidar_noise^2 / largest position variance), else the start is ambiguous along d (a featureless tunnel's axis) and the run stops (exit 2)"));
    v.Field("trust_initial_pose", trust_initial_pose,
            Spec().Help("go on from the initial pose along a direction the first scan does not fix, instead of stopping"));
    v.Field("search_step", search_step, Spec().Unit("m").Range(0.1, 100.0)
        .Help("global search without an initial pose: position grid step over the reference's free space"));
    v.Field("search_yaw_step", search_yaw_step, Spec().Unit("deg").Range(1.0, 90.0)
        .Help("global search: yaw step (roll and pitch come from gravity)"));
    v.Field("search_keep", search_keep, Spec().Range(1, 1000)
        .Help("global search: the best grid candidates (overlap at the candidate) aligned in full"));
    v.Field("search_ambiguity", search_ambiguity, Spec().Range(0.0, 1.0)
        .Help("a start candidate more than 1 m or 10 deg from the best with a fit (share of the scan's points within 3 constraints.lidar_noise of a reference plane) within this of the best's makes the start ambiguous (exit 2); with an initial pose, a candidate whose fit beats it by more makes it wrong (exit 2)"));
    v.Field("start_check_radius", start_check_radius, Spec().Unit("m").Range(0.0, 100.0)
        .Help("an initial pose is checked as the global search checks its best candidate: against the candidates (every yaw) within this distance of it, aligned in full (0: not checked)"));
    v.Field("min_start_fit", min_start_fit, Spec().Range(0.0, 1.0)
        .Help("the best aligned start must have this share of its points with a reference plane within 3 constraints.lidar_noise of it, else the map is taken not to be of this place (exit 2)"));
    v.Field("reference_voxel_size", reference_voxel_size, Spec().Unit("m").Range(0.01, 20.0)
        .Help("voxel edge of the reference's search structure for association (thinned as the working map: 20 points per voxel, 0.1 m apart)"));
    v.Field("reference_neighbor_search", reference_neighbor_search, Spec().Choices({"exact", "nearby"})
        .Help("k-nearest search in the reference: exact, or among the 27 voxels around the query (cheaper; exact whenever the k nearest lie there, which a complete reference makes likely)"));
    v.Section("deviation", deviation);
  }
  Status Validate() {
    if (Status s = ValidateFields(*this, "localization"); !s.ok()) return s;
    if (align_radius_min > align_radius_max)
      return Status::InvalidInput("localization.align_radius_min (" +
                                  std::to_string(align_radius_min) +
                                  ") must not exceed localization.align_radius_max");
    return Status::Ok();
  }
};

}  // namespace rvlio
