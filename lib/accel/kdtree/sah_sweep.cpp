#include <algorithm>

#include "accel/kdtree/sah_sweep_events.h"
#include "accel/kdtree/sah_sweep_sort.h"

namespace raylab {

void append_events(const std::vector<PrimRef>& refs, int axis, std::vector<SplitEvent>& out) {
  for (const PrimRef& r : refs) {
    const float lo = r.box.lo[axis], hi = r.box.hi[axis];
    if (lo == hi) {
      out.push_back({lo, SplitEvent::planar, r.prim});
    } else {
      out.push_back({lo, SplitEvent::start, r.prim});
      out.push_back({hi, SplitEvent::end, r.prim});
    }
  }
}

void sweep_events(const std::vector<SplitEvent>& events, int axis, const Bounds3f& box, std::size_t n,
                  const SahCost& cost, SplitCandidate& best) {
  const float lo = box.lo[axis], hi = box.hi[axis];
  if (!(lo < hi)) return;
  const double sa = surface_area_d(box);
  if (!(sa > 0.0)) return;
  std::size_t left_before = 0;  // #{lo < p}
  std::size_t right_from = n;   // #{hi >= p}
  for (std::size_t i = 0; i < events.size();) {
    const float p = events[i].pos;
    std::size_t ends = 0, planars = 0, starts = 0;
    for (; i < events.size() && events[i].pos == p; ++i) {
      switch (events[i].type) {
        case SplitEvent::end: ++ends; break;
        case SplitEvent::planar: ++planars; break;
        case SplitEvent::start: ++starts; break;
      }
    }
    const std::size_t n_l = left_before + starts + planars;
    const std::size_t n_r = right_from;
    if (p > lo && p < hi) {
      Bounds3f l = box, r = box;
      l.hi[axis] = p;
      r.lo[axis] = p;
      const double c = cost.split(sa, surface_area_d(l), surface_area_d(r), n_l, n_r);
      if (c < best.cost) best = {axis, p, c};
    }
    left_before += starts + planars;
    right_from -= ends + planars;
  }
}

SplitCandidate find_split_events(const NodeEvents& events, const Bounds3f& box, std::size_t n, const SahCost& cost) {
  SplitCandidate best;
  for (int a = 0; a < 3; ++a) sweep_events(events.axis[a], a, box, n, cost, best);
  return best;
}

SplitCandidate find_split_sort(const std::vector<PrimRef>& refs, const Bounds3f& box, const SahCost& cost) {
  SplitCandidate best;
  std::vector<SplitEvent> events;
  for (int a = 0; a < 3; ++a) {
    events.clear();
    append_events(refs, a, events);
    std::sort(events.begin(), events.end());
    sweep_events(events, a, box, refs.size(), cost, best);
  }
  return best;
}

void split_events(const NodeEvents& parent, const std::vector<Side>& side, const std::vector<PrimRef>& left_straddlers,
                  const std::vector<PrimRef>& right_straddlers, NodeEvents& left, NodeEvents& right) {
  std::vector<SplitEvent> new_l, new_r, only_l, only_r;
  for (int a = 0; a < 3; ++a) {
    // One pass splices the events of one-sided primitives into both children, in order.
    only_l.clear();
    only_r.clear();
    for (const SplitEvent& e : parent.axis[a]) {
      const Side s = side[e.prim];
      if (s == Side::left_only) only_l.push_back(e);
      else if (s == Side::right_only) only_r.push_back(e);
    }
    new_l.clear();
    new_r.clear();
    append_events(left_straddlers, a, new_l);
    append_events(right_straddlers, a, new_r);
    std::sort(new_l.begin(), new_l.end());
    std::sort(new_r.begin(), new_r.end());
    left.axis[a].clear();
    right.axis[a].clear();
    left.axis[a].reserve(only_l.size() + new_l.size());
    right.axis[a].reserve(only_r.size() + new_r.size());
    std::merge(only_l.begin(), only_l.end(), new_l.begin(), new_l.end(), std::back_inserter(left.axis[a]));
    std::merge(only_r.begin(), only_r.end(), new_r.begin(), new_r.end(), std::back_inserter(right.axis[a]));
  }
}

}  // namespace raylab
