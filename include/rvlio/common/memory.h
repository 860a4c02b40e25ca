#pragma once
// Large buffers backed by transparent huge pages. Filling a buffer of
// hundreds of megabytes (a 10 M point reference map: its file, its points,
// its voxel storage) faults in one 4 KiB page at a time, and on a virtual
// machine each fault is expensive: with 2 MiB pages the loading of such a map
// took about half the CPU time (docs/survey.md). A hint only: where the
// kernel gives no huge pages (transparent_hugepage "never", other systems)
// nothing changes.
#include <cstddef>

namespace rvlio {

// Buffers smaller than this are left alone (a huge page is 2 MiB).
constexpr size_t kHugePageMinBytes = size_t{8} << 20;

// Asks the kernel to back the 2 MiB-aligned interior of [data, data + bytes)
// with huge pages when its pages are first touched (Linux madvise
// MADV_HUGEPAGE); no-op below kHugePageMinBytes, elsewhere, or on failure.
void AdviseHugePages(void* data, size_t bytes);

// c->reserve(n), then the hint on the whole reserved storage, before any of
// it is written (a vector or string about to be filled).
template <class Container>
void ReserveWithHugePages(Container* c, size_t n) {
  c->reserve(n);
  AdviseHugePages(c->data(), c->capacity() * sizeof(*c->data()));
}

}  // namespace rvlio
