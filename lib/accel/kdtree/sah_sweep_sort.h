#pragma once
/// `sweep=sort`: the lecture's SAH sweep. At every node the candidate events of each axis are
/// generated from the primitives' current bounds and sorted, O(N log N) per node and
/// O(N log² N) for the tree; the sweep itself is the one of sah_sweep_events.h.
#include <span>
#include <vector>

#include "accel/kdtree/sah_sweep_events.h"

namespace raylab {

SplitCandidate find_split_sort(std::span<const PrimRef> refs, const Bounds3f& box, const SahCost& cost);

}  // namespace raylab
