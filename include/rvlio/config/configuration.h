#pragma once
// The whole configuration of rvlio: what `--config` files and `--set
// key=value` fill (config/config.h LoadConfig), what summary.json records and
// `config/default.yaml` lists. It is the online odometry's options
// (OdometryOptions, the sections the core's estimators read) plus the
// sections only the other layers read: batch refinement, reading the
// recording, optional outputs and the survey frame. A Configuration is an
// OdometryOptions, so it is handed to Odometry::Create as it is.
#include "rvlio/common/options.h"
#include "rvlio/formats/live_options.h"
#include "rvlio/formats/reader_options.h"
#include "rvlio/odometry/options.h"
#include "rvlio/outputs/output_options.h"
#include "rvlio/refine/control_options.h"
#include "rvlio/refine/options.h"

namespace rvlio {

struct Configuration : OdometryOptions {
  RefineOptions refine;
  ReaderOptions io;
  OutputOptions output;  // optional output files (map.las)
  SurveyOptions survey;  // the map frame's coordinate reference system
  LiveOptions live;        // `rvlio live` only (docs/live.md)
  ControlOptions control;  // control and check points (`refine --control`, docs/control.md)
  GnssOptions gnss;        // GNSS fixes of the recording (refine, docs/control.md)

  // Keys that moved to another section, read under their former dotted name
  // with a warning until the next release (config/config.h).
  static constexpr DeprecatedName kMovedKeys[] = {
      {"smoother.refine_huber_delta", "refine.huber_delta"},
      {"smoother.huber_delta", "refine.huber_delta"},
      {"smoother.refine_rounds", "refine.rounds"},
      {"smoother.refine_chunk_scans", "refine.chunk_scans"},
      {"smoother.refine_solver_iterations", "refine.solver_iterations"},
      {"smoother.refine_threads", "refine.threads"},
      {"smoother.refine_plane_window", "refine.plane_window"},
      {"smoother.refine_job_overlap_s", "refine.job_overlap_s"},
      {"smoother.refine_summarize_pairs", "refine.summarize_pairs"}};

  template <class V>
  void Visit(V& v) {
    OdometryOptions::Visit(v);
    v.Section("refine", refine);
    v.Section("io", io);
    v.Section("output", output);
    v.Section("survey", survey);
    v.Section("live", live);
    v.Section("control", control);
    v.Section("gnss", gnss);
  }

  Status Validate() {
    if (Status s = OdometryOptions::Validate(); !s.ok()) return s;
    if (Status s = ValidateFields(*this); !s.ok()) return s;
    for (Status m : {refine.Validate(), io.Validate(), output.Validate(), survey.Validate(),
                     live.Validate(), control.Validate(), gnss.Validate()})
      if (!m.ok()) return m;
    return Status::Ok();
  }
};

}  // namespace rvlio
