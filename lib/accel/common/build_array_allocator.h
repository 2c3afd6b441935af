#pragma once
/// An allocator for the large arrays a build writes in full (grid references, sort buffers):
/// `resize` default-initialises the elements, so a trivially constructible array is not zeroed
/// (a pass over memory that also takes the page faults) before the build overwrites it.
/// Elements constructed with arguments (`assign(n, 0)`, `push_back`) are initialised as usual.
/// Every allocation is advised to transparent huge pages (huge_pages.h; arrays from 4 MiB on)
/// before anything touches it: on this VM a 4 KiB page fault costs ~3.5 ms per MB first
/// written, a 2 MiB one a small fraction of that (exp_grids, "Performance goals").
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include "accel/common/huge_pages.h"

namespace raylab {

template <class T>
struct BuildArrayAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = BuildArrayAllocator<U>;
  };
  BuildArrayAllocator() = default;
  template <class U>
  BuildArrayAllocator(const BuildArrayAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    T* p = std::allocator<T>::allocate(n);
    advise_huge_pages(p, n * sizeof(T));
    return p;
  }

  template <class U>
  void construct(U* p) noexcept(noexcept(U())) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// A vector whose `resize` leaves trivially constructible elements unwritten.
template <class T>
using BuildArray = std::vector<T, BuildArrayAllocator<T>>;

}  // namespace raylab
