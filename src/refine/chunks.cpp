#include "rvlio/refine/chunks.h"

#include <algorithm>
#include <cmath>

namespace rvlio {

std::vector<ScanRange> MakeRefineChunks(int n, int chunk_scans) {
  const int overlap = std::max(kRefineMinChunkOverlap,
                               static_cast<int>(std::lround(kRefineChunkOverlap * chunk_scans)));
  std::vector<ScanRange> chunks;
  for (int begin = 0;;) {
    const int end = std::min(n, begin + chunk_scans);
    chunks.push_back(ScanRange{begin, end});
    if (end == n) break;
    begin = end - overlap;
  }
  return chunks;
}

}  // namespace rvlio
