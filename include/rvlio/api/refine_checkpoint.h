#pragma once
// `rvlio refine --checkpoint DIR` / `--resume DIR`: the state after each
// round (refine/refine.h RefineRoundState) in DIR/refine.checkpoint, CBOR
// with every double bit for bit, written atomically. A checkpoint carries the
// fingerprint of what the refinement depends on (the input read from the bag,
// the initial trajectory, the --map file's content and the configuration
// except refine.rounds,
// so a resumed run may also go on for more rounds); resuming with another
// input is refused.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "rvlio/common/status.h"
#include "rvlio/config/config.h"
#include "rvlio/refine/refine.h"

namespace rvlio {

constexpr const char* kCheckpointFile = "refine.checkpoint";

// reference_hash: FileContentHash of the --map file (0 without one).
uint64_t RefineFingerprint(const Configuration& options, const RefineInput& input,
                           uint64_t reference_hash);
// FNV-1a 64 over a file's bytes and its size: the --map file's identity in a
// checkpoint and in chunk.json (the content, so a map rewritten in place, or
// another map at the same path, is another map). InvalidInput naming the file.
StatusOr<uint64_t> FileContentHash(const std::string& path);
// The same hash (FNV-1a 64) over the configuration alone (its JSON, except
// refine.threads: refine's result is bit-identical on any thread
// count) and over a trajectory's stamps and poses: what chunk.json records so
// that `rvlio merge` only merges chunks of one refinement (refine/jobs.h).
uint64_t RefineOptionsHash(const Configuration& options);
uint64_t TrajectoryHash(const Trajectory& trajectory);
// A hash as chunk.json writes it: 16 lower-case hex digits.
std::string HashText(uint64_t hash);

Status WriteRefineCheckpoint(const std::string& dir, uint64_t fingerprint,
                             const RefineRoundState& state);
// InvalidInput naming DIR when there is no checkpoint, it cannot be read or it
// belongs to another input (fingerprint).
StatusOr<RefineRoundState> ReadRefineCheckpoint(const std::string& dir, uint64_t fingerprint);
// InvalidInput naming the file when DIR holds no checkpoint (checked before the bag is read).
Status CheckpointExists(const std::string& dir);

// One round's report as in summary.json "rounds".
nlohmann::json RoundJson(const RefineRound& r);

}  // namespace rvlio
