#pragma once
// Batch refinement, chunking (refine/refine.h, "Long sequences"): the scan
// ranges solved one after the other in a round. Each chunk after the first
// starts `overlap` scans before the previous one ends and holds its first
// pose at the previous chunk's result; the map always spans the sequence.
// A chunk is the unit a solve works on (refine/problem.h) and the unit a
// bounded-memory or distributed refine would hand out.
#include <vector>

namespace rvlio {

// Overlap of consecutive chunks as a fraction of refine.chunk_scans
// (at least kRefineMinChunkOverlap scans): enough shared scans for the next
// chunk's held first pose to sit inside well-constrained states.
constexpr double kRefineChunkOverlap = 0.1;
constexpr int kRefineMinChunkOverlap = 2;

// Refined scans [begin, end).
struct ScanRange {
  int begin = 0;
  int end = 0;

  int size() const { return end - begin; }
  bool Contains(int k) const { return k >= begin && k < end; }
  bool operator==(const ScanRange& o) const { return begin == o.begin && end == o.end; }
};

// The chunks of n scans (n >= 1), each chunk_scans long (the last one may be
// shorter), covering [0, n) in order.
std::vector<ScanRange> MakeRefineChunks(int n, int chunk_scans);

}  // namespace rvlio
