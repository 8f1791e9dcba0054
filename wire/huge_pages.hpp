// Sizes a vector that is about to be filled, on transparent huge pages where it spans any.
// A fresh 64 MiB texture takes 16 384 page faults in 4 KiB pages and 32 in 2 MiB ones: 36-44 ms
// against 9-11 ms on the 2-core reference machine (docs/benchmarks.md, "What a user waits for").
// Readback on the server and the client's assembly each touch a whole reply once.
#pragma once

#include <cstdint>
#include <vector>

#include <sys/mman.h>

namespace shadow {

inline constexpr uintptr_t kHugePageBytes = uintptr_t{2} << 20;

// Like v.resize(n) for an empty v; the values are zero. The kernel uses huge pages only for the
// 2 MiB-aligned part of the allocation, so buffers under 4 MiB stay as they are.
template <class T>
void resize_on_huge_pages(std::vector<T>& v, size_t n) {
  if (n * sizeof(T) >= 2 * kHugePageBytes && v.capacity() < n) {
    v.reserve(n);  // untouched: glibc serves blocks this large from a fresh mmap
    const uintptr_t begin = uintptr_t(v.data()), end = uintptr_t(v.data() + v.capacity());
    const uintptr_t first = (begin + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    const uintptr_t last = end & ~(kHugePageBytes - 1);
    // Advice only: where the kernel has no huge pages (or THP is off) the faults stay small.
    if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
  }
  v.resize(n);
}

}  // namespace shadow
