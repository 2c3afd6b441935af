#pragma once
/// Transparent huge pages for a large array: asks the kernel (madvise MADV_HUGEPAGE, Linux) to
/// back the 2 MiB-aligned part of [data, data + bytes) with 2 MiB pages, before it is first
/// written. Writing then faults once per 2 MiB instead of once per 4 KiB, and random reads can
/// miss the TLB less. The builders write every reference, node and packet into memory they have
/// just allocated; on a virtual machine a fault costs microseconds (measured here: about 3.5 ms
/// per MB first touched in 4 KiB pages), which can exceed a build's own work. Only advice: with
/// THP disabled, or on another OS, nothing changes. Arrays under 4 MiB are left alone.
#include <cstddef>
#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace raylab {

inline void advise_huge_pages(const void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t{1} << 21;
  if (bytes < 2 * kHuge) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1), last = (begin + bytes) & ~(kHuge - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

}  // namespace raylab
