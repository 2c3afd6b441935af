#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>

#include "accel/kdtree/sah_sweep_events.h"
#include "accel/kdtree/sah_sweep_sort.h"

namespace raylab {

void append_events(std::span<const PrimRef> refs, int axis, EventVector& out) {
  for (const PrimRef& r : refs) {
    const float lo = r.box.lo[axis], hi = r.box.hi[axis];
    if (lo == hi) {
      out.push_back(SplitEvent::make(lo, SplitEvent::planar, r.prim));
    } else {
      out.push_back(SplitEvent::make(lo, SplitEvent::start, r.prim));
      out.push_back(SplitEvent::make(hi, SplitEvent::end, r.prim));
    }
  }
}

namespace {

/// sweep_events for a fixed axis A.
template <int A>
void sweep_axis(std::span<const SplitEvent> events, const Bounds3f& box, std::size_t n, const SahCost& cost_in,
                SplitCandidate& best_io) {
  const SahCost cost = cost_in;  // local copies: stores to best_io could alias cost_in
  SplitCandidate best = best_io;
  const float lo = box.lo[A], hi = box.hi[A];
  if (!(lo < hi)) return;
  const double sa = surface_area_d(box);
  if (!(sa > 0.0)) return;
  // surface_area_d of the children with the split axis' extent substituted: linear in that
  // extent x, 2·(x·(b + c) + b·c) for the other two extents b and c.
  const double d0 = double(box.hi.x) - box.lo.x, d1 = double(box.hi.y) - box.lo.y, d2 = double(box.hi.z) - box.lo.z;
  const double other0 = A == 0 ? d1 : d0, other1 = A == 2 ? d1 : d2;
  const double area_at_zero = 2.0 * other0 * other1, area_per_extent = 2.0 * (other0 + other1);
  auto area_with = [&](double extent) { return area_at_zero + area_per_extent * extent; };
  // Inside the sweep both sides are non-empty (a primitive touching p counts on both), so the
  // cost is SahCost::split without the bonus, with the division by sa taken out of the loop.
  // Both children are leaves there, and SA(L) + SA(R) = 2·area_at_zero + area_per_extent·(hi - lo)
  // whatever p, so C_leaf adds a constant per axis.
  const double isect_per_area = cost.c_isect / sa;
  const double trav = cost.c_trav + cost.c_leaf * (2.0 * area_at_zero + area_per_extent * (double(hi) - lo)) / sa;
  const SplitEvent* e = events.data();
  const std::size_t m = events.size();
  if (m == 0) return;
  // Empty-space cut-offs (Wald and Havran 2006; Havran's thesis): every split at an
  // event's position has both sides non-empty, since a primitive touching the plane meets both
  // closed children. The planes one float below the first event and one above the last leave
  // one side empty (no primitive bound reaches it), and only there does the bonus apply.
  if (const float below = std::nextafter(e[0].pos, lo); e[0].pos > lo && below > lo) {
    const double cut_cost = cost.split(sa, area_with(double(below) - lo), area_with(double(hi) - below), 0, n);
    if (cut_cost < best.cost) best = {A, below, cut_cost, 0};
  }
  // At the last event of each run of equal positions p (p is the first event's position):
  // N(L) = #{lo <= p} = starts and planars so far, N(R) = n - #{hi < p}.
  std::size_t starts_planars = 0, ends_planars = 0, ends_planars_before = 0;
  float p = e[0].pos;
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t type = e[i].bits & 3u;
    starts_planars += type != SplitEvent::end;
    ends_planars += type != SplitEvent::start;
    if (i + 1 < m && e[i + 1].pos == p) continue;
    if (p > lo && p < hi) {
      const double sa_l = area_with(double(p) - lo), sa_r = area_with(double(hi) - p);
      const double split_cost = trav + isect_per_area * (sa_l * static_cast<double>(starts_planars) +
                                                                sa_r * static_cast<double>(n - ends_planars_before));
      if (split_cost < best.cost) best = {A, p, split_cost};
    }
    ends_planars_before = ends_planars;
    if (i + 1 < m) p = e[i + 1].pos;
  }
  if (const float above = std::nextafter(e[m - 1].pos, hi); e[m - 1].pos < hi && above < hi) {
    const double cut_cost = cost.split(sa, area_with(double(above) - lo), area_with(double(hi) - above), n, 0);
    if (cut_cost < best.cost) best = {A, above, cut_cost, 1};
  }
  best_io = best;
}

}  // namespace

void sweep_events(std::span<const SplitEvent> events, int axis, const Bounds3f& box, std::size_t n,
                  const SahCost& cost, SplitCandidate& best) {
  switch (axis) {
    case 0: sweep_axis<0>(events, box, n, cost, best); break;
    case 1: sweep_axis<1>(events, box, n, cost, best); break;
    default: sweep_axis<2>(events, box, n, cost, best); break;
  }
}

void sort_root_events(EventVector& events) {
  // Without -0 and NaN, equal keys have equal bits; then every correct sort yields an order that
  // the sweep, the splices and the merges (which see only keys, and keep relative orders) cannot
  // tell from std::sort's, so a radix sort is used. Otherwise std::sort, as before.
  bool plain = events.size() >= 4096;
  for (std::size_t i = 0; plain && i < events.size(); ++i) {
    const auto b = std::bit_cast<std::uint32_t>(events[i].pos);
    plain = b != 0x80000000u && (b & 0x7fffffffu) <= 0x7f800000u;
  }
  if (!plain) {
    std::sort(events.begin(), events.end());
    return;
  }
  // Key: the float's bits mapped to an unsigned order-preserving integer, then the type.
  auto key = [](const SplitEvent& e) {
    const auto b = std::bit_cast<std::uint32_t>(e.pos);
    const std::uint32_t ordered = (b & 0x80000000u) ? ~b : (b | 0x80000000u);
    return (static_cast<std::uint64_t>(ordered) << 2) | (e.bits & 3u);
  };
  constexpr int kBits = 12;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  EventVector tmp(events.size());
  std::vector<std::size_t> count(kBuckets);
  for (int shift = 0; shift < 34; shift += kBits) {  // stable LSD passes over the 34-bit key
    std::fill(count.begin(), count.end(), 0);
    for (const SplitEvent& e : events) ++count[(key(e) >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& c : count) {
      const std::size_t k = c;
      c = sum;
      sum += k;
    }
    for (const SplitEvent& e : events) tmp[count[(key(e) >> shift) & (kBuckets - 1)]++] = e;
    events.swap(tmp);
  }
}

SplitCandidate find_split_events(const NodeEvents& events, const Bounds3f& box, std::size_t n, const SahCost& cost) {
  SplitCandidate best;
  for (int a = 0; a < 3; ++a) sweep_events(events.axis[a], a, box, n, cost, best);
  return best;
}

SplitCandidate find_split_sort(std::span<const PrimRef> refs, const Bounds3f& box, const SahCost& cost) {
  SplitCandidate best;
  EventVector events;
  for (int a = 0; a < 3; ++a) {
    events.clear();
    append_events(refs, a, events);
    std::sort(events.begin(), events.end());
    sweep_events(events, a, box, refs.size(), cost, best);
  }
  return best;
}

namespace {

/// std::sort, with its result: up to 16 elements libstdc++'s std::sort is a plain insertion
/// sort, which is stable, as is this one.
void sort_events(EventVector& v) {
  const std::size_t n = v.size();
  if (n > 16) {
    std::sort(v.begin(), v.end());
    return;
  }
  SplitEvent* e = v.data();
  for (std::size_t i = 1; i < n; ++i) {
    const SplitEvent x = e[i];
    std::size_t j = i;
    for (; j > 0 && x < e[j - 1]; --j) e[j] = e[j - 1];
    e[j] = x;
  }
}

/// Merges the sorted `add` into the sorted out[0, k), in place (out has room for k + add.size()),
/// with the result of std::merge(out, add): at equal keys the elements of out come first.
void merge_into(SplitEvent* out, std::size_t k, const EventVector& add) {
  const SplitEvent* const b_first = add.data();
  const SplitEvent* b = b_first + add.size();
  SplitEvent* a = out + k;
  SplitEvent* dst = a + add.size();
  if (add.size() * 16 < k) {
    // Few new events: find each one's place by binary search and move the run after it.
    while (b != b_first) {
      const SplitEvent x = *--b;
      SplitEvent* p = std::upper_bound(out, a, x);  // out's unplaced elements that go after x
      const auto run = static_cast<std::size_t>(a - p);
      dst -= run;
      std::memmove(dst, p, run * sizeof(SplitEvent));
      a = p;
      *--dst = x;
    }
    return;
  }
  while (b != b_first) {
    if (a != out && *(b - 1) < *(a - 1))
      *--dst = *--a;
    else
      *--dst = *--b;
  }
}

}  // namespace

KeptEvents kept_events(const Bounds3f& in_parent, const Bounds3f& in_child, int child) {
  KeptEvents bits = 0;
  for (int a = 0; a < 3; ++a)
    if (std::bit_cast<std::uint32_t>(in_parent.lo[a]) == std::bit_cast<std::uint32_t>(in_child.lo[a]) &&
        std::bit_cast<std::uint32_t>(in_parent.hi[a]) == std::bit_cast<std::uint32_t>(in_child.hi[a]))
      bits |= static_cast<KeptEvents>(1u << (2 * a + child));
  return bits;
}

void split_events(const NodeEvents& parent, const std::vector<KeptEvents>& kept, std::span<const PrimRef> left_new,
                  std::span<const PrimRef> right_new, const std::size_t (&kept_l)[3], const std::size_t (&kept_r)[3],
                  NodeEvents& left, NodeEvents& right, SplitEventsScratch& scratch) {
  EventVector& new_l = scratch.new_l;
  EventVector& new_r = scratch.new_r;
  const KeptEvents* kp = kept.data();
  for (int a = 0; a < 3; ++a) {
    const unsigned lower_bit = 2u * static_cast<unsigned>(a), upper_bit = lower_bit + 1u;
    new_l.clear();
    new_r.clear();
    for (const PrimRef& r : left_new)
      if (!((kp[r.prim] >> lower_bit) & 1u)) append_events({&r, 1}, a, new_l);
    for (const PrimRef& r : right_new)
      if (!((kp[r.prim] >> upper_bit) & 1u)) append_events({&r, 1}, a, new_r);
    sort_events(new_l);
    sort_events(new_r);
    const EventVector& in = parent.axis[a];
    EventVector& out_l = left.axis[a];
    EventVector& out_r = right.axis[a];
    // Room for the child's events, plus one slot that the branchless splice may write past the end.
    out_l.resize(kept_l[a] + new_l.size() + 1);
    out_r.resize(kept_r[a] + new_r.size() + 1);
    // One pass splices the kept events into both children, in order; then the new events are
    // merged in (as std::merge: at equal keys the parent's event first).
    SplitEvent* pl = out_l.data();
    SplitEvent* pr = out_r.data();
    for (const SplitEvent& e : in) {
      const unsigned k = kp[e.prim()];
      *pl = e;
      *pr = e;
      pl += (k >> lower_bit) & 1u;
      pr += (k >> upper_bit) & 1u;
    }
    const auto k_l = static_cast<std::size_t>(pl - out_l.data());
    const auto k_r = static_cast<std::size_t>(pr - out_r.data());
    assert(k_l == kept_l[a] && k_r == kept_r[a]);
    merge_into(out_l.data(), k_l, new_l);
    merge_into(out_r.data(), k_r, new_r);
    out_l.resize(k_l + new_l.size());
    out_r.resize(k_r + new_r.size());
  }
}

}  // namespace raylab
