#pragma once
/// The SAH sweep over split events (Wald and Havran 2006, "On building fast kd-trees for ray
/// tracing, and on doing that in O(N log N)", §4). A primitive with bounds [lo, hi] along an
/// axis contributes a start event at lo and an end event at hi, or one planar event when
/// lo = hi. Sweeping the events sorted by (position, type) yields at every candidate plane p
///   N(L) = #{lo <= p},  N(R) = #{hi >= p}
/// (a primitive touching p belongs to both closed children), and the SAH cost of each p strictly
/// inside the node.
///
/// `sweep=sort` (sah_sweep_sort.h) builds and sorts these events anew at every node; `sweep=events`
/// sorts them once and keeps each child's lists sorted through the splits (splice and merge,
/// Wald and Havran §4.3), so both see identical event sequences and choose the same split.
#include <cstdint>
#include <limits>
#include <vector>

#include "accel/kdtree/sah_cost.h"
#include "accel/kdtree/split_clipping.h"

namespace raylab {

struct SplitEvent {
  enum Type : std::uint8_t { end = 0, planar = 1, start = 2 };
  float pos;
  Type type;
  std::uint32_t prim;

  friend bool operator<(const SplitEvent& a, const SplitEvent& b) {
    return a.pos < b.pos || (a.pos == b.pos && a.type < b.type);
  }
};

/// The best split found so far. Ties keep the earlier candidate (lower axis, then lower
/// position), so the choice does not depend on how the events were produced.
struct SplitCandidate {
  int axis = -1;
  float pos = 0.0f;
  double cost = std::numeric_limits<double>::infinity();
  bool valid() const { return axis >= 0; }
};

/// Appends the events of `refs` along `axis` (unsorted).
void append_events(const std::vector<PrimRef>& refs, int axis, std::vector<SplitEvent>& out);

/// Sweeps the sorted `events` of a node with `n` primitives along `axis`, updating `best` with
/// every candidate strictly inside `box` that costs less.
void sweep_events(const std::vector<SplitEvent>& events, int axis, const Bounds3f& box, std::size_t n,
                  const SahCost& cost, SplitCandidate& best);

/// The node's three sorted event lists (`sweep=events`).
struct NodeEvents {
  std::vector<SplitEvent> axis[3];
};

/// The best split of a node from its presorted events.
SplitCandidate find_split_events(const NodeEvents& events, const Bounds3f& box, std::size_t n, const SahCost& cost);

/// Which children a primitive of the node being split went to.
enum class Side : std::uint8_t { left_only, right_only, both, none };

/// The children's sorted event lists: events of primitives on one side only are spliced in
/// order; primitives in both children got new (clipped) bounds in `left_straddlers` and
/// `right_straddlers`, whose events are sorted and merged in. `side` is indexed by primitive id.
void split_events(const NodeEvents& parent, const std::vector<Side>& side, const std::vector<PrimRef>& left_straddlers,
                  const std::vector<PrimRef>& right_straddlers, NodeEvents& left, NodeEvents& right);

}  // namespace raylab
