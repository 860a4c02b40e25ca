// `rvlio merge`: MergeRefineChunks (rvlio/api.h) with the command's arguments
// and lines: the output folders of `rvlio refine --chunk K --of N` (K = 1..N)
// into one trajectory.tum, map.pcd and summary.json (refine/jobs.h:
// each chunk aligned to the previous one on their shared scans and blended
// across them).
#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "rvlio/api.h"

namespace rvlio::cli {

int CmdMerge(int argc, char** argv) {
  CommandSpec spec{"merge",
                   "Merges the output folders of `rvlio refine --chunk K --of N` (all N of them, "
                   "any order) into one trajectory.tum, map.pcd and summary.json: each chunk is "
                   "aligned to the previous one by a rigid transform over their shared scans and "
                   "blended across them. Exit 2 naming the folder or chunk when a chunk is "
                   "missing or the chunks come from different refinements.",
                   {{"chunks", "DIR", "output folder of one chunk job", true, true},
                    {"out", "DIR", "output folder", true},
                    {"map", "REF", "the reference map the chunks were refined with "
                                   "(refine --map): map.pcd gains deviation_m, and "
                                   "deviation.csv is written"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  MergeArgs req;
  req.chunk_dirs = args.GetAll("chunks");
  req.out_dir = args.Get("out");
  req.map = args.Get("map");
  StatusOr<MergeResult> result = MergeRefineChunks(req);
  if (!result.ok()) return Fail("merge", result.status());
  for (const auto& w : result->warnings) std::fprintf(stderr, "rvlio merge: warning: %s\n", w.c_str());
  for (const MergedChunk& c : result->chunks)
    std::printf("rvlio merge: chunk %d: %d scans, %d shared with the previous, moved %.4f m %.4f deg, "
                "residual RMS %.4f m\n",
                c.chunk, static_cast<int>(c.scans), c.shared_poses, c.translation_m,
                c.rotation_deg, c.residual_rms_m);
  std::printf("rvlio merge: %zu chunks, %zu scans, %zu map points -> %s\n", req.chunk_dirs.size(),
              result->trajectory.size(), result->map.size(), req.out_dir.c_str());
  return 0;
}

}  // namespace rvlio::cli
