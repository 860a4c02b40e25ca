# The public API: the headers `cmake --install` puts under include/rvlio
# (docs/library.md "The public headers"). The entry points are rvlio/api.h
# (whole recordings), experiments/ (compare, ablation grids, the report's
# data), config/config.h, odometry/odometry.h (scan by scan),
# formats/sensor_stream.h and formats/trajectory_io.h (reading recordings and
# trajectories), eval/evaluate.h, sim/simulator.h and sim/presets.h, and
# math/so3.h; the rest of the list is what those include. Every other header
# of include/rvlio is private: the libraries' own, the tests' and the
# command's, free to change. scripts/install_test.sh compiles each listed
# header on its own from the prefix (so the list is closed under #include)
# and checks that no other header is installed. rvlio/version.h is generated.
set(rvlio_public_headers
  rvlio/api.h
  rvlio/common/check.h
  rvlio/common/options.h
  rvlio/common/status.h
  rvlio/common/time.h
  rvlio/common/types.h
  rvlio/config/config.h
  rvlio/config/configuration.h
  rvlio/config/yaml_tree.h
  rvlio/constraints/constraint.h
  rvlio/constraints/options.h
  rvlio/constraints/plane_fit.h
  rvlio/constraints/reference_surface.h
  rvlio/degeneracy/degeneracy.h
  rvlio/degeneracy/options.h
  rvlio/eval/align.h
  rvlio/eval/degeneracy_scores.h
  rvlio/eval/evaluate.h
  rvlio/eval/map_metrics.h
  rvlio/eval/metrics.h
  rvlio/eval/options.h
  rvlio/eval/stats.h
  rvlio/eval/time_matching.h
  rvlio/experiments/ablate_cells.h
  rvlio/experiments/ablate_grid.h
  rvlio/experiments/ablate_summary.h
  rvlio/experiments/compare.h
  rvlio/experiments/report_data.h
  rvlio/factors/parameter_blocks.h
  rvlio/formats/control_file.h
  rvlio/formats/live_options.h
  rvlio/formats/navsatfix.h
  rvlio/formats/reader_options.h
  rvlio/formats/sensor_bag.h
  rvlio/formats/sensor_stream.h
  rvlio/formats/trajectory_io.h
  rvlio/ieskf/options.h
  rvlio/imu/integrator.h
  rvlio/imu/options.h
  rvlio/imu/propagator.h
  rvlio/lidar/extrinsics.h
  rvlio/lidar/options.h
  rvlio/lidar/preprocess.h
  rvlio/lidar/range_window.h
  rvlio/map/map_cloud.h
  rvlio/map/options.h
  rvlio/map/reference_map.h
  rvlio/map/voxel_key.h
  rvlio/map/voxel_map.h
  rvlio/math/extrinsic_excitation.h
  rvlio/math/local_origin.h
  rvlio/math/pose.h
  rvlio/math/so3.h
  rvlio/math/time_offset_excitation.h
  rvlio/odometry/deviation.h
  rvlio/odometry/divergence.h
  rvlio/odometry/divergence_options.h
  rvlio/odometry/odometry.h
  rvlio/odometry/options.h
  rvlio/odometry/localization_options.h
  rvlio/odometry/reference.h
  rvlio/outputs/output_options.h
  rvlio/outputs/output_stage.h
  rvlio/outputs/run_outputs.h
  rvlio/refine/control.h
  rvlio/refine/control_options.h
  rvlio/refine/options.h
  rvlio/refine/refine.h
  rvlio/refine/jobs.h
  rvlio/refine/states.h
  rvlio/rv/criterion.h
  rvlio/rv/options.h
  rvlio/rv/rv.h
  rvlio/sim/geometry.h
  rvlio/sim/lidar_sim.h
  rvlio/sim/options.h
  rvlio/sim/presets.h
  rvlio/sim/random.h
  rvlio/sim/simulator.h
  rvlio/sim/survey.h
  rvlio/sim/trajectory.h
  rvlio/sim/world.h
  rvlio/sim/world_builder.h
  rvlio/window/options.h
)
