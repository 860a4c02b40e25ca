// MergeRefineChunks (rvlio/api.h): the output folders of `rvlio refine
// --chunk K --of N` into one trajectory and map (refine/jobs.h for
// the alignment and the blend). `rvlio merge` is this call plus arguments.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <set>
#include <utility>

#include "rvlio/api.h"
#include "rvlio/api/result_json.h"
#include "rvlio/api/survey_ties.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/config/config.h"
#include "rvlio/outputs/deviation_outputs.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/formats/reference_map_file.h"
#include "rvlio/api/refine_checkpoint.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/map/output_map.h"
#include "rvlio/refine/jobs.h"

namespace rvlio {
namespace {

using nlohmann::json;

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// One chunk folder as read.
struct ChunkFolder {
  std::string dir;
  json manifest;  // chunk.json
  RefineJobTrajectory job;
  std::vector<std::string> warnings;  // its summary.json "warnings"
  json config;                        // its summary.json "config" (the refinement's options)
  std::string control_csv;            // its control.csv (refine --control), "" without
  // Its trajectory_imu.tum, when it was refined with output.imu_trajectory.
  std::optional<Trajectory> imu_trajectory;
};

std::string FilePath(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
}

// chunk.json's fields as the merge needs them; InvalidInput naming the file.
Status ParseManifest(const std::string& path, const json& m, RefineJobSpan* span) {
  static const char* kKeys[] = {"chunk",    "of",          "overlap_s",    "core_begin_ns",
                                "core_end_ns", "begin_ns", "end_ns",       "options_hash",
                                "init_hash", "interrupted", "map_output_resolution"};
  for (const char* key : kKeys)
    if (!m.is_object() || !m.contains(key)) return Status::InvalidInput(path + ": no \"" + std::string(key) + "\"");
  try {
    span->chunk = m["chunk"].get<int>();
    span->count = m["of"].get<int>();
    span->core_begin_ns = m["core_begin_ns"].get<TimeNs>();
    span->core_end_ns = m["core_end_ns"].get<TimeNs>();
    span->begin_ns = m["begin_ns"].get<TimeNs>();
    span->end_ns = m["end_ns"].get<TimeNs>();
    (void)m["options_hash"].get<std::string>();
    (void)m["init_hash"].get<std::string>();
    (void)m["overlap_s"].get<double>();
    (void)m["map_output_resolution"].get<double>();
    if (m["interrupted"].get<bool>())
      return Status::InvalidInput(path + ": chunk " + std::to_string(span->chunk) +
                                  " was interrupted before its last round; run it again");
  } catch (const json::exception& e) {
    return Status::InvalidInput(path + ": " + e.what());
  }
  if (span->count < 1 || span->chunk < 1 || span->chunk > span->count)
    return Status::InvalidInput(path + ": chunk " + std::to_string(span->chunk) + " of " +
                                std::to_string(span->count) + " is not a chunk");
  return Status::Ok();
}

// trajectory.tum must be the one the chunk wrote: as many poses as it refined,
// from its first to its last stamp (a file cut short, or replaced, is refused).
Status CheckTrajectoryAgainstManifest(const std::string& path, const json& m,
                                      const Trajectory& trajectory) {
  for (const char* key : {"scans_refined", "t_first_ns", "t_last_ns"})
    if (!m.contains(key) || !m[key].is_number_integer())
      return Status::InvalidInput(path + ": no integer \"" + std::string(key) + "\"");
  const int64_t scans = m["scans_refined"].get<int64_t>();
  const TimeNs first_ns = m["t_first_ns"].get<TimeNs>(), last_ns = m["t_last_ns"].get<TimeNs>();
  const std::string tum = FilePath(std::filesystem::path(path).parent_path().string(), "trajectory.tum");
  if (static_cast<int64_t>(trajectory.size()) != scans)
    return Status::InvalidInput(tum + " has " + std::to_string(trajectory.size()) + " poses, but " +
                                path + " records " + std::to_string(scans) +
                                " refined scans: the trajectory is cut short or not this chunk's");
  if (trajectory.front().t_ns != first_ns || trajectory.back().t_ns != last_ns)
    return Status::InvalidInput(tum + " spans " + std::to_string(trajectory.front().t_ns) + " .. " +
                                std::to_string(trajectory.back().t_ns) + " ns, but " + path +
                                " records " + std::to_string(first_ns) + " .. " +
                                std::to_string(last_ns) + ": not this chunk's trajectory");
  return Status::Ok();
}

// trajectory_imu.tum of a chunk refined with output.imu_trajectory (its
// summary's config says so): it must span the chunk's trajectory.tum.
Status ReadChunkImuTrajectory(ChunkFolder* c) {
  const json& config = c->config;
  if (!config.is_object() || !config.contains("output") || !config["output"].is_object() ||
      !config["output"].value("imu_trajectory", false))
    return Status::Ok();
  const std::string path = FilePath(c->dir, kImuTrajectoryFile);
  StatusOr<Trajectory> imu = ReadTum(path);
  if (!imu.ok())
    return imu.status().WithMessage(imu.status().message() + " (the chunk was refined with "
                                    "output.imu_trajectory=true)");
  const Trajectory& scans = c->job.trajectory;
  if (imu->front().t_ns != scans.front().t_ns || imu->back().t_ns != scans.back().t_ns)
    return Status::InvalidInput(path + " spans " + std::to_string(imu->front().t_ns) + " .. " +
                                std::to_string(imu->back().t_ns) + " ns, its trajectory.tum " +
                                std::to_string(scans.front().t_ns) + " .. " +
                                std::to_string(scans.back().t_ns) + ": not this chunk's");
  c->imu_trajectory = std::move(*imu);
  return Status::Ok();
}

StatusOr<ChunkFolder> ReadChunkFolder(const std::string& dir) {
  ChunkFolder c;
  c.dir = dir;
  const std::string manifest = FilePath(dir, "chunk.json");
  if (!std::filesystem::exists(manifest))
    return Status::InvalidInput(manifest + ": no such file (not the output of `rvlio refine --chunk K --of N`)");
  c.manifest = json::parse(ReadFileText(manifest), nullptr, false);
  if (c.manifest.is_discarded()) return Status::InvalidInput(manifest + ": not valid JSON");
  if (Status s = ParseManifest(manifest, c.manifest, &c.job.span); !s.ok()) return s;
  StatusOr<Trajectory> trajectory = ReadTum(FilePath(dir, "trajectory.tum"));
  if (!trajectory.ok()) return trajectory.status();
  c.job.trajectory = std::move(*trajectory);
  if (Status s = CheckTrajectoryAgainstManifest(manifest, c.manifest, c.job.trajectory); !s.ok())
    return s;
  const json summary = json::parse(ReadFileText(FilePath(dir, "summary.json")), nullptr, false);
  if (summary.is_object() && summary.contains("warnings") && summary["warnings"].is_array())
    for (const json& w : summary["warnings"])
      if (w.is_string()) c.warnings.push_back(w.get<std::string>());
  if (summary.is_object() && summary.contains("config")) c.config = summary["config"];
  c.control_csv = ReadFileText(FilePath(dir, "control.csv"));
  if (Status s = ReadChunkImuTrajectory(&c); !s.ok()) return s;
  return c;
}

// map.las as the chunks were refined: their output.las and survey.crs (the
// chunks share their options, CheckChunks); absent keys keep the defaults.
StatusOr<MapLasRequest> MergedLasRequest(const ChunkFolder& chunk) {
  OutputOptions output;
  SurveyOptions survey;
  const json& c = chunk.config;
  if (c.is_object() && c.contains("output") && c["output"].is_object())
    output.las = c["output"].value("las", output.las);
  if (c.is_object() && c.contains("survey") && c["survey"].is_object())
    survey.crs = c["survey"].value("crs", survey.crs);
  StatusOr<MapLasRequest> las = MapLasRequestOf(output, survey);
  if (!las.ok())
    return las.status().WithMessage(FilePath(chunk.dir, "summary.json") + ": " + las.status().message());
  return las;
}

// The chunks of one refinement, in order 1..N: InvalidInput naming what differs or is missing.
Status CheckChunks(std::vector<ChunkFolder>* chunks) {
  if (chunks->empty()) return Status::InvalidInput("no chunk folders to merge");
  std::sort(chunks->begin(), chunks->end(),
            [](const ChunkFolder& a, const ChunkFolder& b) { return a.job.span.chunk < b.job.span.chunk; });
  const ChunkFolder& first = chunks->front();
  const int n = first.job.span.count;
  // map_hash: "" without --map (and in chunks written before it was recorded).
  for (const char* key : {"of", "options_hash", "init_hash", "overlap_s", "map_hash"})
    for (const ChunkFolder& c : *chunks)
      if (c.manifest.value(key, json("")) != first.manifest.value(key, json("")))
        return Status::InvalidInput(
            "chunks of different refinements: " + FilePath(c.dir, "chunk.json") + " has " + key +
            " " + c.manifest.value(key, json("")).dump() + ", " + FilePath(first.dir, "chunk.json") +
            " " + first.manifest.value(key, json("")).dump() +
            (std::string(key) == "options_hash" ? " (other --config/--set)"
             : std::string(key) == "map_hash"   ? " (another --map)"
                                                : ""));
  std::set<int> have;
  for (const ChunkFolder& c : *chunks)
    if (!have.insert(c.job.span.chunk).second)
      return Status::InvalidInput("chunk " + std::to_string(c.job.span.chunk) + " of " +
                                  std::to_string(n) + " given twice (" + c.dir + ")");
  std::string missing;
  for (int k = 1; k <= n; ++k)
    if (!have.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  if (!missing.empty())
    return Status::InvalidInput("missing chunk " + missing + " of " + std::to_string(n) +
                                " (have " + std::to_string(chunks->size()) + " folders)");
  return Status::Ok();
}

// A chunk map's scan indices (rows of the chunk's trajectory.tum) as rows of
// the merged trajectory: the row with the same stamp. InvalidInput naming
// the map for an index past the chunk's trajectory or a stamp the merged
// trajectory lacks.
Status RemapScanIndices(const std::string& path, const Trajectory& chunk, const Trajectory& merged,
                        MapCloud* map) {
  for (uint32_t& index : map->scan_index) {
    if (index >= chunk.size())
      return Status::InvalidInput(path + ": scan_index " + std::to_string(index) + " is past the " +
                                  std::to_string(chunk.size()) + " poses of its trajectory.tum");
    const TimeNs t_ns = chunk[index].t_ns;
    const auto at = std::lower_bound(merged.begin(), merged.end(), t_ns,
                                     [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
    if (at == merged.end() || at->t_ns != t_ns)
      return Status::InvalidInput(path + ": scan " + std::to_string(index) + " (" +
                                  FormatSeconds(t_ns) + " s) is not in the merged trajectory");
    index = static_cast<uint32_t>(at - merged.begin());
  }
  return Status::Ok();
}

// Each chunk's map carried into the merged frame, re-voxelized at the
// chunks' resolution, with the attributes the chunks' maps have (scan_index
// as rows of the merged trajectory); in the local frame of `origin`, as the
// trajectories.
StatusOr<MapCloud> MergeMaps(const std::vector<ChunkFolder>& chunks, const RefineJobMerge& merge,
                             const LocalOrigin& origin) {
  OutputMap output(chunks.front().manifest["map_output_resolution"].get<double>());
  for (size_t k = 0; k < chunks.size(); ++k) {
    const std::string path = FilePath(chunks[k].dir, "map.pcd");
    StatusOr<MapCloudFile> read = ReadMapCloud(path);
    if (!read.ok()) return read.status();
    MapCloud& map = read->map;
    if (Status s = RemapScanIndices(path, chunks[k].job.trajectory, merge.trajectory, &map); !s.ok())
      return s;
    origin.ToLocal(&map.p);
    const Pose3& T = merge.alignments[k].T_merged_chunk;
    for (Eigen::Vector3d& p : map.p) p = T * p;
    output.InsertCloud(map);
  }
  return output.Cloud();
}

MergedChunk Merged(const ChunkFolder& c, const RefineJobAlignment& a) {
  MergedChunk m;
  m.chunk = a.chunk;
  m.dir = c.dir;
  m.scans = c.job.trajectory.size();
  m.shared_poses = a.shared_poses;
  m.translation_m = a.T_merged_chunk.t.norm();
  m.rotation_deg = Eigen::AngleAxisd(a.T_merged_chunk.R).angle() * kRadToDeg;
  m.residual_rms_m = a.rms_residual_m;
  m.residual_max_m = a.max_residual_m;
  m.residual_max_deg = a.max_residual_deg;
  return m;
}

json Summary(const std::vector<ChunkFolder>& chunks, const MergeResult& r) {
  json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "merge";
  j["of"] = chunks.front().job.span.count;
  j["overlap_s"] = chunks.front().manifest["overlap_s"];
  j["options_hash"] = chunks.front().manifest["options_hash"];
  j["init_hash"] = chunks.front().manifest["init_hash"];
  j["scan_count"] = r.trajectory.size();
  j["sequence_duration_s"] = NsToSeconds(r.trajectory.back().t_ns - r.trajectory.front().t_ns);
  j["map_points"] = r.map.size();
  j["chunks"] = json::array();
  for (const MergedChunk& c : r.chunks) j["chunks"].push_back(MergedChunkJson(c));
  j["warnings"] = r.warnings;
  return j;
}

Status WriteOutputs(const std::string& out_dir, const MergeResult& r,
                    const MapDeviation* deviation, const MapLasRequest& las) {
  OutputStage stage(out_dir);  // all outputs or none
  if (Status s = stage.Open(); !s.ok()) return s;
  if (Status s = WriteTrajectoryOutputs(&stage, r.trajectory, r.imu_trajectory); !s.ok())
    return s;
  if (!r.control_csv.empty())
    if (Status s = WriteFileAtomically(stage.Path("control.csv"), r.control_csv); !s.ok())
      return stage.Explain(s);
  if (Status s = WriteMapOutputs(&stage, r.map, deviation, las); !s.ok()) return s;
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), r.summary_json);
      !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

// The reference of `merge --map`, checked against the map the chunks were
// refined with (chunk.json's map_hash: the file's content), and the chunks'
// deviation options. Null without --map.
struct MergeReference {
  std::shared_ptr<const ReferenceMap> surface;  // in its local frame
  LocalOrigin origin;
  DeviationOptions options;
};

StatusOr<MergeReference> LoadMergeReference(const std::string& map, const ChunkFolder& first,
                                            std::vector<std::string>* warnings) {
  MergeReference ref;
  if (map.empty()) return ref;
  const std::string manifest = FilePath(first.dir, "chunk.json");
  const std::string chunk_hash = first.manifest.value("map_hash", std::string());
  if (chunk_hash.empty())
    return Status::InvalidInput("--map " + map + ": the chunks were refined without --map (" +
                                manifest + ")");
  StatusOr<uint64_t> hash = FileContentHash(map);
  if (!hash.ok()) return Status::InvalidInput("--map " + hash.status().message());
  if (HashText(*hash) != chunk_hash)
    return Status::InvalidInput("--map " + map + ": not the map the chunks were refined with (" +
                                manifest + " has map " +
                                first.manifest.value("map", std::string()) + ", content hash " +
                                chunk_hash + ")");
  if (Status s = ApplyYamlText(ref.options, first.manifest.value("deviation", std::string()),
                               manifest + " deviation");
      !s.ok())
    return s;
  StatusOr<std::shared_ptr<const ReferenceMap>> surface =
      LoadReferenceSurface(map, &ref.origin, warnings);
  if (!surface.ok()) return surface.status();
  ref.surface = std::move(*surface);
  return ref;
}

// trajectory_imu.tum of the merge, in the local frame of `origin`: the
// chunks' merged as their trajectory.tum were (MergeAlignedTrajectories),
// when every chunk has one; a warning naming those without one when only
// some have.
Status MergeImuTrajectories(const std::vector<ChunkFolder>& chunks, const RefineJobMerge& merge,
                            const LocalOrigin& origin, MergeResult* r) {
  std::vector<RefineJobTrajectory> jobs;
  std::string without;
  for (const ChunkFolder& c : chunks) {
    if (!c.imu_trajectory) {
      without += (without.empty() ? "" : ", ") + std::to_string(c.job.span.chunk);
      continue;
    }
    jobs.push_back({c.job.span, *c.imu_trajectory});
    origin.ToLocal(&jobs.back().trajectory);
  }
  if (jobs.empty()) return Status::Ok();
  if (!without.empty()) {
    r->warnings.push_back("no trajectory_imu.tum is merged: chunk(s) " + without +
                          " were refined without output.imu_trajectory=true");
    return Status::Ok();
  }
  StatusOr<Trajectory> merged = MergeAlignedTrajectories(jobs, merge.alignments);
  if (!merged.ok()) return merged.status();
  r->imu_trajectory = std::move(*merged);
  return Status::Ok();
}

}  // namespace

// control.csv of chunks refined with --control (all or none of them): every
// row's estimate from the chunk that owns its tie time, in the merged frame.
Status MergeControl(const std::vector<ChunkFolder>& chunks, const RefineJobMerge& merge,
                    const LocalOrigin& origin, MergeResult* r) {
  const size_t with = std::count_if(chunks.begin(), chunks.end(),
                                    [](const ChunkFolder& c) { return !c.control_csv.empty(); });
  if (with == 0) return Status::Ok();
  std::vector<ChunkControl> controls;
  for (size_t k = 0; k < chunks.size(); ++k) {
    const ChunkFolder& c = chunks[k];
    const std::string path = FilePath(c.dir, "control.csv");
    if (c.control_csv.empty())
      return Status::InvalidInput(path + " is missing, but " + std::to_string(with) +
                                  " chunk(s) were refined with --control: refine every chunk "
                                  "with the same control file");
    StatusOr<std::vector<ControlResidual>> rows = ParseControlCsv(c.control_csv, path);
    if (!rows.ok()) return rows.status();
    const Pose3 to_user(Eigen::Matrix3d::Identity(), origin.t_user_local);
    controls.push_back({std::move(*rows), c.job.span.core_begin_ns, c.job.span.core_end_ns,
                        to_user * merge.alignments[k].T_merged_chunk * to_user.Inverse()});
  }
  r->control = MergeChunkControl(controls);
  r->control_csv = ControlCsvText(r->control);
  return Status::Ok();
}

json MergedChunkJson(const MergedChunk& c) {
  return {{"chunk", c.chunk},
          {"dir", c.dir},
          {"scans", c.scans},
          {"shared_poses", c.shared_poses},
          {"translation_m", c.translation_m},
          {"rotation_deg", c.rotation_deg},
          {"residual_rms_m", c.residual_rms_m},
          {"residual_max_m", c.residual_max_m},
          {"residual_max_deg", c.residual_max_deg}};
}

StatusOr<MergeResult> MergeRefineChunks(const MergeArgs& args) {
  std::vector<ChunkFolder> chunks;
  for (const std::string& dir : args.chunk_dirs) {
    StatusOr<ChunkFolder> c = ReadChunkFolder(dir);
    if (!c.ok()) return c.status();
    chunks.push_back(std::move(*c));
  }
  if (Status s = CheckChunks(&chunks); !s.ok()) return s;
  StatusOr<MapLasRequest> las = MergedLasRequest(chunks.front());
  if (!las.ok()) return las.status();
  std::vector<std::string> map_warnings;
  StatusOr<MergeReference> reference = LoadMergeReference(args.map, chunks.front(), &map_warnings);
  if (!reference.ok()) return reference.status();
  OutputFolder out_folder(args.out_dir);  // removed again when nothing gets written
  if (!args.out_dir.empty())
    if (Status s = out_folder.Prepare(); !s.ok()) return s;
  // The chunks are merged in a local frame: the reference's (the frame
  // refine --map used), else one chosen from chunk 1's trajectory; the
  // outputs go out in the chunks' frame.
  const LocalOrigin origin = reference->surface != nullptr
                                 ? reference->origin
                                 : ChooseLocalOrigin(chunks.front().job.trajectory);
  std::vector<RefineJobTrajectory> jobs;
  for (const ChunkFolder& c : chunks) {
    jobs.push_back(c.job);
    origin.ToLocal(&jobs.back().trajectory);
  }
  StatusOr<RefineJobMerge> merge = MergeRefineJobs(jobs);
  if (!merge.ok()) return merge.status();
  MergeResult r;
  r.trajectory = merge->trajectory;
  StatusOr<MapCloud> map = MergeMaps(chunks, *merge, origin);
  if (!map.ok()) return map.status();
  r.map = std::move(*map);
  for (const ChunkFolder& c : chunks) map_warnings.insert(map_warnings.end(), c.warnings.begin(), c.warnings.end());
  for (const std::string& w : map_warnings)  // each once
    if (std::find(r.warnings.begin(), r.warnings.end(), w) == r.warnings.end())
      r.warnings.push_back(w);
  const std::string chunk_map = chunks.front().manifest.value("map", std::string());
  if (args.map.empty() && !chunks.front().manifest.value("map_hash", std::string()).empty())
    r.warnings.push_back("the chunks were refined with --map " + chunk_map +
                         "; merge --map " + chunk_map + " writes the deviation from it");
  for (size_t k = 0; k < chunks.size(); ++k)
    r.chunks.push_back(Merged(chunks[k], merge->alignments[k]));
  std::optional<MapDeviation> deviation;  // in the local frame, as the reference
  if (reference->surface != nullptr)
    deviation = ComputeMapDeviation(r.map.p, *reference->surface, r.trajectory,
                                    reference->options);
  if (Status s = MergeImuTrajectories(chunks, *merge, origin, &r); !s.ok()) return s;
  origin.ToUser(&r.trajectory);
  origin.ToUser(&r.imu_trajectory);
  origin.ToUser(&r.map.p);
  if (Status s = MergeControl(chunks, *merge, origin, &r); !s.ok()) return s;
  json summary = Summary(chunks, r);
  summary["local_origin"] = LocalOriginJson(origin);
  if (!r.control_csv.empty()) summary["control"] = ControlSummaryJson(r.control);
  if (deviation) {
    summary["map"] = args.map;
    summary["localization"]["deviation"] = DeviationSummaryJson(*deviation);
  }
  r.summary_json = JsonText(summary) + "\n";
  if (args.out_dir.empty()) return r;
  if (Status s = WriteOutputs(args.out_dir, r, deviation ? &*deviation : nullptr, *las); !s.ok())
    return s;
  out_folder.Keep();
  r.written = true;
  return r;
}

}  // namespace rvlio
