#pragma once
/// The SAH sweep over split events (Wald and Havran 2006, "On building fast kd-trees for ray
/// tracing, and on doing that in O(N log N)", §4). A primitive with bounds [lo, hi] along an
/// axis contributes a start event at lo and an end event at hi, or one planar event when
/// lo = hi. Sweeping the events sorted by (position, type) yields at every candidate plane p
///   N(L) = #{lo <= p},  N(R) = #{hi >= p}
/// (a primitive touching p belongs to both closed children), and the SAH cost of each p strictly
/// inside the node; and the two empty-space cut-offs, one float below the first event and one
/// above the last, whose empty side earns SahCost's bonus.
///
/// `sweep=sort` (sah_sweep_sort.h) builds and sorts these events anew at every node; `sweep=events`
/// sorts them once and keeps each child's lists sorted through the splits (splice and merge,
/// Wald and Havran §4.3), so both see identical event sequences and choose the same split.
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <span>
#include <vector>

#include "accel/common/huge_pages.h"
#include "accel/kdtree/sah_cost.h"
#include "accel/kdtree/split_clipping.h"

namespace raylab {

/// One event, 8 bytes: the primitive id and the type share one word.
struct SplitEvent {
  enum Type : std::uint32_t { end = 0, planar = 1, start = 2 };
  /// Primitive ids must be below this (checked by the builder).
  static constexpr std::uint32_t kMaxPrims = 1u << 30;

  float pos;
  std::uint32_t bits;  ///< prim << 2 | type

  static SplitEvent make(float pos, Type type, std::uint32_t prim) { return {pos, prim << 2 | type}; }
  Type type() const { return static_cast<Type>(bits & 3u); }
  std::uint32_t prim() const { return bits >> 2; }

  /// By position, then type (end < planar < start); the order among equal keys is irrelevant to
  /// the sweep.
  friend bool operator<(const SplitEvent& a, const SplitEvent& b) {
    return a.pos < b.pos || (a.pos == b.pos && (a.bits & 3u) < (b.bits & 3u));
  }
};
static_assert(sizeof(SplitEvent) == 8);

/// An allocator whose value-less construct leaves trivial types uninitialised, so that
/// resizing an event list before overwriting it costs nothing, and that asks for huge pages for
/// large lists (huge_pages.h), so that their first writes fault once per 2 MiB.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  T* allocate(std::size_t n) {
    T* p = std::allocator<T>::allocate(n);
    advise_huge_pages(p, n * sizeof(T));
    return p;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0)
      ::new (static_cast<void*>(p)) U;
    else
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

using EventVector = std::vector<SplitEvent, UninitAllocator<SplitEvent>>;

/// The best split found so far. Ties keep the earlier candidate (lower axis, then lower
/// position), so the choice does not depend on how the events were produced.
struct SplitCandidate {
  int axis = -1;
  float pos = 0.0f;
  double cost = std::numeric_limits<double>::infinity();
  /// For an empty-space cut-off, the child that no primitive bound reaches (0 lower, 1 upper):
  /// every reference of the node goes, unchanged, to the other child. -1 for other splits.
  int empty_child = -1;
  bool valid() const { return axis >= 0; }
};

/// Appends the events of `refs` along `axis` (unsorted).
void append_events(std::span<const PrimRef> refs, int axis, EventVector& out);

/// Sweeps the sorted `events` of a node with `n` primitives along `axis`, updating `best` with
/// every candidate strictly inside `box` that costs less.
void sweep_events(std::span<const SplitEvent> events, int axis, const Bounds3f& box, std::size_t n,
                  const SahCost& cost, SplitCandidate& best);

/// The node's three sorted event lists (`sweep=events`).
struct NodeEvents {
  EventVector axis[3];
};

/// Sorts the root's events of one axis into an order that builds the same tree as std::sort's.
void sort_root_events(EventVector& events);

/// The best split of a node from its presorted events.
SplitCandidate find_split_events(const NodeEvents& events, const Bounds3f& box, std::size_t n, const SahCost& cost);

/// Which of a primitive's events along each axis the children of a split node keep: bit 2·a for
/// the lower child, bit 2·a + 1 for the upper. A child keeps the parent's events along a when the
/// primitive is in that child with the same bounds along a (as when it lies on one side, or is
/// not clipped); otherwise the child gets the events of the primitive's new bounds, if it holds it.
using KeptEvents = std::uint8_t;
inline constexpr KeptEvents kKeepAllLower = 0x15, kKeepAllUpper = 0x2a;

/// The bits of KeptEvents for a primitive in a child (0 lower, 1 upper) with bounds `in_child`
/// there and `in_parent` in the parent: set along the axes where the two are bitwise equal.
KeptEvents kept_events(const Bounds3f& in_parent, const Bounds3f& in_child, int child);

/// Working storage of split_events, kept across calls so that nodes do not allocate.
struct SplitEventsScratch {
  EventVector new_l, new_r;
};

/// Bytes past the last primitive's entry that `kept` must have for split_events (it reads four
/// bytes at a time); their values are ignored.
inline constexpr std::size_t kKeptPadding = 3;

/// The children's sorted event lists: the parent's events that a child keeps (`kept`, indexed by
/// primitive id, kKeptPadding bytes longer) are spliced in order; the events of `left_new` and
/// `right_new` (the references of the primitives with new bounds in a child) along the axes their
/// child does not keep are sorted and merged in. `kept_l[a]` and `kept_r[a]` must be the numbers of parent events along
/// axis a that each child keeps. `left` and `right` are overwritten (their capacity is reused).
void split_events(const NodeEvents& parent, const std::vector<KeptEvents>& kept, std::span<const PrimRef> left_new,
                  std::span<const PrimRef> right_new, const std::size_t (&kept_l)[3], const std::size_t (&kept_r)[3],
                  NodeEvents& left, NodeEvents& right, SplitEventsScratch& scratch);

}  // namespace raylab
