#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

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

/// Vectors of 8 lanes in the GCC/Clang vector extensions: one code path, which the compiler lowers
/// to the target's SIMD (two AVX2 or one AVX-512 register per vector with -march=native).
using V8i = std::int32_t __attribute__((vector_size(32)));
using V8u = std::uint32_t __attribute__((vector_size(32)));
using V8f = float __attribute__((vector_size(32)));
using V8d = double __attribute__((vector_size(64)));
using V8l = std::int64_t __attribute__((vector_size(64)));

/// Lanes moved up by K, lanes below K zero.
template <int K>
V8i lanes_up(V8i x) {
  const V8i z = {};
  if constexpr (K == 1) return __builtin_shufflevector(z, x, 0, 8, 9, 10, 11, 12, 13, 14);
  else if constexpr (K == 2) return __builtin_shufflevector(z, x, 0, 1, 8, 9, 10, 11, 12, 13);
  else return __builtin_shufflevector(z, x, 0, 1, 2, 3, 8, 9, 10, 11);
}
V8i inclusive_sum(V8i x) {
  x += lanes_up<1>(x);
  x += lanes_up<2>(x);
  return x + lanes_up<4>(x);
}
V8i inclusive_max(V8i x) {  // of non-negative lanes
  V8i y = lanes_up<1>(x);
  x = x > y ? x : y;
  y = lanes_up<2>(x);
  x = x > y ? x : y;
  y = lanes_up<4>(x);
  return x > y ? x : y;
}

struct RunBest {
  double cost = std::numeric_limits<double>::infinity();
  float pos = 0.0f;
};

/// The sweep proper over a node's sorted events along one axis. At the last event of each run of
/// equal positions p: N(L) = #{lo <= p}, the starts and planars so far, and N(R) = n - #{hi < p},
/// the ends and planars before the run. Its cost (only for lo < p < hi) is
///   trav + isect_per_area·(SA(L)·N(L) + SA(R)·N(R)),  SA(x) = area_at_zero + area_per_extent·x.
/// Returns the cheapest, the first in event order among equal costs.
///
/// Runs of equal positions are short and irregular on meshes (vertices are shared), which a
/// branch per event mispredicts; so eight events are taken at a time: their counts are prefix
/// sums across lanes, the count before each run a prefix maximum over the run starts, and every
/// event's cost is computed and kept only at run ends. Each lane keeps its first minimum; the
/// lanes are merged by cost, then by position (which is event order, as run ends have distinct
/// positions). Lane arithmetic is IEEE double like scalar arithmetic (no contraction: the build
/// uses -ffp-contract=off), so the result is bitwise that of a scalar sweep in event order with a
/// strict <, which sweep=sort and earlier versions of this loop computed.
struct RunSweep {
  float lo, hi;
  std::size_t n;
  double area_at_zero, area_per_extent, isect_per_area, trav;

  /// Below this many events the scalar loop is faster (bench on node-sized event lists).
  static constexpr std::size_t kMinVector = 16;

  RunBest run(const SplitEvent* e, std::size_t m) const { return m < kMinVector ? run_scalar(e, m) : run_vector(e, m); }

  RunBest run_scalar(const SplitEvent* e, std::size_t m) const {
    RunBest best;
    std::size_t starts_planars = 0, ends_planars = 0, ends_planars_before = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint32_t type = e[i].bits & 3u;
      starts_planars += type != SplitEvent::end;
      ends_planars += type != SplitEvent::start;
      const float p = e[i].pos;
      if (i + 1 < m && e[i + 1].pos == p) continue;
      if (p > lo && p < hi) {
        const double sa_l = area_at_zero + area_per_extent * (double(p) - double(lo));
        const double sa_r = area_at_zero + area_per_extent * (double(hi) - double(p));
        const double cost = trav + isect_per_area * (sa_l * static_cast<double>(starts_planars) +
                                                     sa_r * static_cast<double>(n - ends_planars_before));
        if (cost < best.cost) best = {cost, p};
      }
      ends_planars_before = ends_planars;
    }
    return best;
  }

  /// Requires m >= 9.
  RunBest run_vector(const SplitEvent* e, std::size_t m) const {
    // Counts fit in 32 bits: n < 2^30 (SplitEvent::kMaxPrims). The counts carried from one block
    // of eight to the next stay in vectors (every lane equal), off the scalar units.
    V8i starts_planars = {}, ends_planars = {}, ends_planars_before = {};
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();  // differs from every position
    float prev = kNaN;
    // Two sets of lanes, for even and odd blocks, so that a block's minimum does not wait for the
    // previous block's.
    V8d lane_cost[2] = {}, lane_pos[2] = {};
    lane_cost[0] += std::numeric_limits<double>::infinity();
    lane_cost[1] += std::numeric_limits<double>::infinity();
    const V8i one = {1, 1, 1, 1, 1, 1, 1, 1}, lane = {0, 1, 2, 3, 4, 5, 6, 7};
    // The eight events src[0, 8), preceded by a position `before` and followed by `after`; only
    // the lanes set in `fresh` are new (the others, already swept, count nothing and are no
    // candidates).
    auto block = [&](std::size_t k, const SplitEvent* src, float before_pos, float after_pos, V8i fresh) {
      V8u w0, w1;
      std::memcpy(&w0, src, sizeof w0);
      std::memcpy(&w1, src + 4, sizeof w1);
      const V8u pos_bits = __builtin_shufflevector(w0, w1, 0, 2, 4, 6, 8, 10, 12, 14);
      const V8u type = __builtin_shufflevector(w0, w1, 1, 3, 5, 7, 9, 11, 13, 15) & 3u;
      V8f pos;
      std::memcpy(&pos, &pos_bits, sizeof pos);
      V8f around = {};
      around[0] = before_pos;
      around[1] = after_pos;
      const V8f previous = __builtin_shufflevector(around, pos, 0, 8, 9, 10, 11, 12, 13, 14);
      const V8f next = __builtin_shufflevector(pos, around, 1, 2, 3, 4, 5, 6, 7, 9);
      const V8i counted = fresh & one;
      const V8i sp = inclusive_sum((type != std::uint32_t{SplitEvent::end}) & counted) + starts_planars;
      const V8i ep_inc = (type != std::uint32_t{SplitEvent::start}) & counted;
      const V8i ep = inclusive_sum(ep_inc) + ends_planars;
      // At each run start, the ends and planars before it; carried to the run's end by the maximum.
      const V8i before_run = (pos != previous) & fresh & (ep - ep_inc);
      V8i before = inclusive_max(before_run);
      before = before > ends_planars_before ? before : ends_planars_before;
      const V8i candidate = fresh & (pos != next) & (pos > lo) & (pos < hi);
      const V8d p = __builtin_convertvector(pos, V8d);
      const V8d n_l = __builtin_convertvector(sp, V8d);
      const V8d n_r = __builtin_convertvector(static_cast<std::int32_t>(n) - before, V8d);
      const V8d sa_l = area_at_zero + area_per_extent * (p - double(lo));
      const V8d sa_r = area_at_zero + area_per_extent * (double(hi) - p);
      const V8d cost = trav + isect_per_area * (sa_l * n_l + sa_r * n_r);
      const V8l better = __builtin_convertvector(candidate, V8l) & (cost < lane_cost[k]);
      lane_cost[k] = better ? cost : lane_cost[k];
      lane_pos[k] = better ? p : lane_pos[k];
      starts_planars = __builtin_shufflevector(sp, sp, 7, 7, 7, 7, 7, 7, 7, 7);
      ends_planars = __builtin_shufflevector(ep, ep, 7, 7, 7, 7, 7, 7, 7, 7);
      ends_planars_before = __builtin_shufflevector(before, before, 7, 7, 7, 7, 7, 7, 7, 7);
      prev = pos[7];
    };
    const V8i all = lane >= 0;
    std::size_t i = 0;
    for (; i + 16 < m; i += 16) {
      block(0, e + i, prev, e[i + 8].pos, all);
      block(1, e + i + 8, prev, e[i + 16].pos, all);
    }
    if (i + 8 < m) {
      block(0, e + i, prev, e[i + 8].pos, all);
      i += 8;
    }
    // The last one to eight events: the last eight of the list, of which those before i are
    // already swept; the last event ends its run.
    const std::size_t j = m - 8;
    block(1, e + j, e[j - 1].pos, kNaN, lane >= static_cast<std::int32_t>(i - j));
    // The lanes: the cheaper, at equal costs the lower position (the earlier event).
    const V8l second = (lane_cost[1] < lane_cost[0]) | ((lane_cost[1] == lane_cost[0]) & (lane_pos[1] < lane_pos[0]));
    const V8d cost = second ? lane_cost[1] : lane_cost[0], pos = second ? lane_pos[1] : lane_pos[0];
    RunBest best;
    for (int l = 0; l < 8; ++l)
      if (cost[l] < best.cost || (cost[l] == best.cost && pos[l] < best.pos))
        best = {cost[l], static_cast<float>(pos[l])};
    return best;
  }
};

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
  const RunSweep sweep{lo, hi, n, area_at_zero, area_per_extent, isect_per_area, trav};
  if (const RunBest b = sweep.run(e, m); b.cost < best.cost) best = {A, b.pos, b.cost};
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

/// Slots past a child's events that the splice of split_events may write.
constexpr std::size_t kSpliceSlack = 8;

/// Sorts by (position, type), as std::sort; the order among equal keys, which may differ from
/// std::sort's, is irrelevant (SplitEvent).
void sort_events(EventVector& v) {
  const std::size_t n = v.size();
  SplitEvent* e = v.data();
#if defined(__AVX512F__)
  constexpr std::size_t kRankMax = 64;
  if (n > 2 && n <= kRankMax) {
    // Stable, by rank: each event's key (position bits in an order-preserving integer, -0 as +0,
    // then type, then index: all distinct) is compared with eight keys at a time; the number
    // below it is its place. No branch on the data, where insertion sort mispredicts about once
    // per element; O(n²/8) comparisons, fewer instructions than std::sort's up to 64 events.
    alignas(64) std::uint64_t key[kRankMax];
    const std::size_t blocks = (n + 7) / 8;
    for (std::size_t i = 0; i < blocks * 8; ++i) {
      if (i >= n) {
        key[i] = ~std::uint64_t{0};
        continue;
      }
      std::uint32_t b = std::bit_cast<std::uint32_t>(e[i].pos);
      b = b == 0x80000000u ? 0u : b;
      const std::uint32_t ordered = (b & 0x80000000u) ? ~b : (b | 0x80000000u);
      key[i] = (std::uint64_t{ordered} << 8) | ((e[i].bits & 3u) << 6) | i;
    }
    SplitEvent sorted[kRankMax];
    for (std::size_t i = 0; i < n; ++i) {
      const __m512i x = _mm512_set1_epi64(static_cast<long long>(key[i]));
      int below = 0;
      for (std::size_t k = 0; k < blocks; ++k)
        below += std::popcount(static_cast<unsigned>(_mm512_cmplt_epu64_mask(_mm512_load_si512(key + 8 * k), x)));
      sorted[below] = e[i];
    }
    std::copy(sorted, sorted + n, e);
    return;
  }
#endif
  if (n > 16) {
    std::sort(v.begin(), v.end());
    return;
  }
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
    // Room for the child's events, plus the slots that the splice may write past the end.
    out_l.resize(kept_l[a] + new_l.size() + kSpliceSlack);
    out_r.resize(kept_r[a] + new_r.size() + kSpliceSlack);
    // One pass splices the kept events into both children, in order; then the new events are
    // merged in (as std::merge: at equal keys the parent's event first).
    SplitEvent* pl = out_l.data();
    SplitEvent* pr = out_r.data();
    const SplitEvent* src = in.data();
    const SplitEvent* const src_end = src + in.size();
#if defined(__AVX512F__) && defined(__AVX512VL__)
    // Eight events at a time: their KeptEvents gathered (four bytes from each primitive's, hence
    // kKeptPadding), each child's compressed into a full store whose tail the next store or the
    // merge overwrites (hence kSpliceSlack).
    static_assert(sizeof(SplitEvent) == 8 && kSpliceSlack >= 8 && kKeptPadding >= 3);
    const __m256i lower_mask = _mm256_set1_epi32(static_cast<int>(1u << lower_bit));
    const __m256i upper_mask = _mm256_set1_epi32(static_cast<int>(1u << upper_bit));
    for (; src + 8 <= src_end; src += 8) {
      const __m512i ev = _mm512_loadu_si512(src);
      const __m256i prim = _mm512_maskz_cvtepi64_epi32(0xff, _mm512_maskz_srli_epi64(0xff, ev, 34));
      const __m256i k = _mm256_i32gather_epi32(reinterpret_cast<const int*>(kp), prim, 1);
      const __mmask8 to_l = _mm256_test_epi32_mask(k, lower_mask), to_r = _mm256_test_epi32_mask(k, upper_mask);
      _mm512_storeu_si512(pl, _mm512_maskz_compress_epi64(to_l, ev));
      _mm512_storeu_si512(pr, _mm512_maskz_compress_epi64(to_r, ev));
      pl += std::popcount(static_cast<unsigned>(to_l));
      pr += std::popcount(static_cast<unsigned>(to_r));
    }
#endif
    for (; src != src_end; ++src) {
      const SplitEvent e = *src;
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
