#pragma once
/// Page-fault cost of the builders' large arrays. A build writes every reference, node and leaf
/// packet into memory it has just allocated, and the kernel maps that memory one 4 KiB page per
/// fault; on a virtual machine a fault costs microseconds (measured here: ~3.5 ms per MB first
/// touched), which can exceed the build's own work. Transparent huge pages map 2 MiB per fault.
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>

namespace raylab {

/// Asks the kernel (madvise MADV_HUGEPAGE) to back the 2 MiB-aligned part of [p, p + bytes)
/// with transparent huge pages when it is first touched. Advice only: contents are unchanged,
/// and it does nothing where transparent huge pages are off or unsupported.
inline void bvh_advise_huge_pages(const void* p, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHugePage = std::uintptr_t{1} << 21;
  const auto start = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t begin = (start + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t end = (start + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

}  // namespace raylab
