#include "rvlio/api/refine_checkpoint.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "rvlio/common/fnv1a.h"
#include "rvlio/config/config_json.h"
#include "rvlio/formats/atomic_file.h"

namespace rvlio {
namespace {

using nlohmann::json;
constexpr int kFormat = 1;

std::string CheckpointPath(const std::string& dir) {
  return (std::filesystem::path(dir) / kCheckpointFile).string();
}

json Vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

Eigen::Vector3d Vec3From(const json& j) {
  return Eigen::Vector3d(j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>());
}

RefineRound RoundFrom(const json& j) {
  RefineRound r;
  r.round = j.at("round").get<int>();
  r.chunks = j.at("chunks").get<int>();
  r.cost_before = j.at("cost_before").get<double>();
  r.cost_after = j.at("cost_after").get<double>();
  r.iterations = j.at("iterations").get<int>();
  r.max_translation_change_m = j.at("max_translation_change_m").get<double>();
  r.max_rotation_change_deg = j.at("max_rotation_change_deg").get<double>();
  r.points = j.at("points").get<int64_t>();
  r.constraints = j.at("constraints").get<int64_t>();
  r.rv_active_scans = j.at("rv_active_scans").get<int>();
  r.degenerate_scans = j.value("degenerate_scans", 0);  // absent in older checkpoints
  r.solve_failures = j.at("solve_failures").get<int>();
  const json& t = j.at("time_s");
  r.deskew_s = t.at("deskew").get<double>();
  r.map_s = t.at("map").get<double>();
  r.associate_s = t.at("associate").get<double>();
  r.solve_s = t.at("solve").get<double>();
  r.total_s = t.at("total").get<double>();
  return r;
}

json StateJson(const RefineRoundState& s, uint64_t fingerprint) {
  json states = json::array();
  for (const RefineState& x : s.states)
    states.push_back({{"t_ns", x.t_ns}, {"pose", x.pose}, {"speed_bias", x.speed_bias}});
  json rounds = json::array();
  for (const RefineRound& r : s.rounds) rounds.push_back(RoundJson(r));
  return {{"format", kFormat},
          {"fingerprint", fingerprint},
          {"rounds_done", s.rounds_done},
          {"converged", s.converged},
          {"g_world", Vec3(s.g_world)},
          {"init_solve_s", s.init_solve_s},
          {"map_entries", s.map_entries},
          {"chunks", s.chunks},
          {"warnings", s.warnings},
          {"rounds", rounds},
          {"states", states}};
}

RefineRoundState StateFrom(const json& j) {
  RefineRoundState s;
  s.rounds_done = j.at("rounds_done").get<int>();
  s.converged = j.at("converged").get<bool>();
  s.g_world = Vec3From(j.at("g_world"));
  s.init_solve_s = j.at("init_solve_s").get<double>();
  s.map_entries = j.at("map_entries").get<int64_t>();
  s.chunks = j.at("chunks").get<int>();
  s.warnings = j.at("warnings").get<std::vector<std::string>>();
  for (const json& r : j.at("rounds")) s.rounds.push_back(RoundFrom(r));
  for (const json& x : j.at("states")) {
    RefineState state;
    state.t_ns = x.at("t_ns").get<TimeNs>();
    state.pose = x.at("pose").get<std::array<double, 7>>();
    state.speed_bias = x.at("speed_bias").get<std::array<double, 9>>();
    s.states.push_back(state);
  }
  return s;
}

}  // namespace

json RoundJson(const RefineRound& r) {
  return {{"round", r.round},
          {"chunks", r.chunks},
          {"cost_before", r.cost_before},
          {"cost_after", r.cost_after},
          {"iterations", r.iterations},
          {"max_translation_change_m", r.max_translation_change_m},
          {"max_rotation_change_deg", r.max_rotation_change_deg},
          {"points", r.points},
          {"constraints", r.constraints},
          {"rv_active_scans", r.rv_active_scans},
          {"degenerate_scans", r.degenerate_scans},
          {"solve_failures", r.solve_failures},
          {"time_s",
           {{"deskew", r.deskew_s},
            {"map", r.map_s},
            {"associate", r.associate_s},
            {"solve", r.solve_s},
            {"total", r.total_s}}}};
}

uint64_t RefineOptionsHash(const Configuration& options) {
  Configuration config = options;
  config.refine.threads = 0;
  nlohmann::json json = ToJson(config);
  json.erase("output");  // which files are written, not what is computed
  Fnv1a h;
  h.AddText(json.dump());
  return h.value();
}

uint64_t TrajectoryHash(const Trajectory& trajectory) {
  Fnv1a h;
  for (const StampedPose& p : trajectory) {
    h.Add(p.t_ns);
    for (int i = 0; i < 3; ++i) h.Add(p.p_world_imu[i]);
    for (double q : {p.q_world_imu.x(), p.q_world_imu.y(), p.q_world_imu.z(), p.q_world_imu.w()})
      h.Add(q);
  }
  return h.value();
}

std::string HashText(uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

StatusOr<uint64_t> FileContentHash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::InvalidInput(path + ": cannot be read (" + std::strerror(errno) + ")");
  Fnv1a h;
  std::vector<char> block(1 << 20);
  uint64_t size = 0;
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const std::streamsize n = in.gcount();
    h.AddBytes(block.data(), static_cast<size_t>(n));
    size += static_cast<uint64_t>(n);
  }
  if (in.bad()) return Status::InvalidInput(path + ": read error after " + std::to_string(size) + " bytes");
  h.Add(size);
  return h.value();
}

uint64_t RefineFingerprint(const Configuration& options, const RefineInput& input,
                           uint64_t reference_hash) {
  Configuration config = options;
  config.refine.rounds = 0;  // resuming may go on for more rounds
  Fnv1a h;
  h.Add(kFormat);
  h.AddText(ToJson(config).dump());
  h.Add(reference_hash);
  for (const StampedPose& p : input.init) {
    h.Add(p.t_ns);
    for (int i = 0; i < 3; ++i) h.Add(p.p_world_imu[i]);
    for (double q : {p.q_world_imu.x(), p.q_world_imu.y(), p.q_world_imu.z(), p.q_world_imu.w()})
      h.Add(q);
  }
  for (const ImuSample& m : input.imu) {
    h.Add(m.t_ns);
    for (int i = 0; i < 3; ++i) h.Add(m.acc_imu[i]), h.Add(m.gyro_imu[i]);
  }
  for (const Scan& s : input.scans) {
    h.Add(s.t_start_ns);
    h.Add(s.t_end_ns);
    h.Add(s.points.size());
    for (const LidarPoint& p : s.points) {
      for (int i = 0; i < 3; ++i) h.Add(p.p_lidar[i]);
      h.Add(p.intensity);
      h.Add(p.t_ns);
      h.Add(p.ring);
    }
  }
  return h.value();
}

Status WriteRefineCheckpoint(const std::string& dir, uint64_t fingerprint,
                             const RefineRoundState& state) {
  const std::vector<uint8_t> bytes = json::to_cbor(StateJson(state, fingerprint));
  return WriteFileAtomically(CheckpointPath(dir),
                             std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

Status CheckpointExists(const std::string& dir) {
  const std::string path = CheckpointPath(dir);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    return Status::InvalidInput("--resume " + dir + ": no checkpoint " + path + " (" +
                                std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode))
    return Status::InvalidInput("--resume " + dir + ": " + path + " is not a file");
  return Status::Ok();
}

StatusOr<RefineRoundState> ReadRefineCheckpoint(const std::string& dir, uint64_t fingerprint) {
  if (Status s = CheckpointExists(dir); !s.ok()) return s;
  const std::string path = CheckpointPath(dir);
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  const json j = json::from_cbor(bytes, true, false);
  const std::string what = "--resume " + dir + ": " + path;
  if (j.is_discarded() || !j.is_object() || j.value("format", 0) != kFormat)
    return Status::InvalidInput(what + " is not an rvlio refine checkpoint (format " +
                                std::to_string(kFormat) + ")");
  if (j.value("fingerprint", uint64_t{0}) != fingerprint)
    return Status::InvalidInput(what + " was written for another bag, initial trajectory, --map or "
                                "configuration (only refine.rounds may differ)");
  try {
    return StateFrom(j);
  } catch (const json::exception& e) {
    return Status::InvalidInput(what + " is damaged: " + e.what());
  }
}

}  // namespace rvlio
