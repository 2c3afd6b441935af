#pragma once
/// An allocator for the large arrays a build writes in full (grid references, sort buffers):
/// `resize` default-initialises the elements, so a trivially constructible array is not zeroed
/// (a pass over memory that also takes the page faults) before the build overwrites it.
/// Elements constructed with arguments (`assign(n, 0)`, `push_back`) are initialised as usual.
#include <memory>
#include <utility>
#include <vector>

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
