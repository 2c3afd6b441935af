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
  // surface_area_d of the children with the split axis' extent substituted, term for term.
  double d[3] = {double(box.hi.x) - box.lo.x, double(box.hi.y) - box.lo.y, double(box.hi.z) - box.lo.z};
  auto area_with = [&](double extent) {
    d[axis] = extent;
    return 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
  };
  std::size_t left_before = 0;  // #{lo < p}
  std::size_t right_from = n;   // #{hi >= p}
  const SplitEvent* e = events.data();
  const std::size_t m = events.size();
  for (std::size_t i = 0; i < m;) {
    const float p = e[i].pos;
    std::size_t ends = 0, planars = 0, starts = 0;
    for (; i < m && e[i].pos == p; ++i) {
      switch (e[i].type) {
        case SplitEvent::end: ++ends; break;
        case SplitEvent::planar: ++planars; break;
        case SplitEvent::start: ++starts; break;
      }
    }
    const std::size_t n_l = left_before + starts + planars;
    const std::size_t n_r = right_from;
    if (p > lo && p < hi) {
      const double sa_l = area_with(double(p) - lo), sa_r = area_with(double(hi) - p);
      const double c = cost.split(sa, sa_l, sa_r, n_l, n_r);
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
  std::vector<SplitEvent> new_l, new_r;
  std::vector<Side> event_side;  // side[e.prim] in event order: one random lookup per event
  for (int a = 0; a < 3; ++a) {
    new_l.clear();
    new_r.clear();
    append_events(left_straddlers, a, new_l);
    append_events(right_straddlers, a, new_r);
    std::sort(new_l.begin(), new_l.end());
    std::sort(new_r.begin(), new_r.end());
    const std::vector<SplitEvent>& in = parent.axis[a];
    std::size_t n_l = new_l.size(), n_r = new_r.size();
    event_side.resize(in.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
      const Side s = side[in[i].prim];
      event_side[i] = s;
      n_l += s == Side::left_only;
      n_r += s == Side::right_only;
    }
    std::vector<SplitEvent>& out_l = left.axis[a];
    std::vector<SplitEvent>& out_r = right.axis[a];
    out_l.resize(n_l);
    out_r.resize(n_r);
    // One pass splices the events of one-sided primitives into both children, in order, merging
    // the straddlers' new events in (as std::merge: at equal keys the parent's event first).
    SplitEvent* pl = out_l.data();
    SplitEvent* pr = out_r.data();
    const SplitEvent *nl = new_l.data(), *nl_end = nl + new_l.size();
    const SplitEvent *nr = new_r.data(), *nr_end = nr + new_r.size();
    for (std::size_t i = 0; i < in.size(); ++i) {
      const SplitEvent& e = in[i];
      const Side s = event_side[i];
      if (s == Side::left_only) {
        while (nl != nl_end && *nl < e) *pl++ = *nl++;
        *pl++ = e;
      } else if (s == Side::right_only) {
        while (nr != nr_end && *nr < e) *pr++ = *nr++;
        *pr++ = e;
      }
    }
    pl = std::copy(nl, nl_end, pl);
    pr = std::copy(nr, nr_end, pr);
  }
}

}  // namespace raylab
