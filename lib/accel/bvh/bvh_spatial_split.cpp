/// SBVH builder (Stich, Friedrich and Dietrich, "Spatial splits in bounding volume
/// hierarchies", HPG 2009): at each node the binned SAH object split (bvh_object_binning.h)
/// competes with a binned spatial split, tried only where the object split's children overlap
/// by more than alpha·SA(root) (§4.3). A spatial split cuts the node at a bin plane; references
/// straddling it are clipped to both sides or, where the SAH prefers, kept whole on one side
/// ("reference unsplitting", §4.4). This refines the bounding boxes of long, rotated triangles
/// (the lecture's rotated walls).
///
/// Clipping is conservative: a part's box is clipped_triangle_bounds (geometry/
/// triangle_clipping.h; floating point rounded outward) of the triangle against the reference's
/// box restricted to that side, so it contains the triangle's intersection with the side; a part
/// whose clipped box is empty does not meet the side and is dropped. Spheres are clipped by
/// their bounds and never split otherwise.
///
/// Duplication bound: every node owns a reference capacity, the root (1 + max_duplication)·N.
/// A split needs n_L + n_R <= capacity, and the spare capacity goes to the children in
/// proportion to their counts, so every subtree stays within its capacity and the tree holds at
/// most (1 + max_duplication)·N references. Spatial splits stop in a subtree once its capacity
/// is used. The split depends only on the node's references, so the tree is the same with any
/// number of build threads.
#include <tbb/task_arena.h>

#include <cstring>
#include <memory>
#include <stdexcept>

#include "accel/common/huge_pages.h"
#include "accel/bvh/bvh_builders.h"
#include "accel/bvh/bvh_object_binning.h"
#include "accel/bvh/bvh_subtree.h"
#include "accel/common/tracer.h"
#include "geometry/triangle_clipping.h"

namespace raylab {
namespace {


struct SpatialSplit {
  int axis = -1;
  float plane = 0.0f;
  float cost = std::numeric_limits<float>::infinity();  ///< N_A·S_A + N_B·S_B, half areas
  Bounds3f left, right;
  std::size_t left_count = 0, right_count = 0;
};

class SpatialBuilder {
 public:
  SpatialBuilder(const Scene& scene, const BvhConfig& config, BvhBuildRef* refs, float root_half_area)
      : scene_(scene), config_(config), refs_(refs), min_overlap_(static_cast<float>(config.spatial_alpha) * root_half_area) {}

  /// The node holds refs_[begin, begin + n) and owns refs_[begin, begin + capacity).
  void build(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n, std::size_t capacity,
             const BvhRangeBounds& bounds, int depth) const {
    const Bounds3f box = bounds.box();
    out.nodes[slot].box = box;
    if (n == 1) return make_leaf(out, slot, begin, n);
    const bool small = n <= static_cast<std::size_t>(config_.max_leaf_size);
    BvhRangeBounds left, right;
    std::size_t n_left = 0, n_right = 0;
    const int centroid_axis = bounds.centroid_axis();
    BvhBuildRef* refs = refs_ + begin;
    if (depth >= kBvhMaxDepth - 32 || centroid_axis < 0) {
      if (small) return make_leaf(out, slot, begin, n);
      n_left = bvh_partition_median(refs, n, centroid_axis, left, right);
      n_right = n - n_left;
    } else {
      const BvhBinMapping map(bounds, bvh_object_bins(config_.bins, n));
      BvhObjectSplit object;
      BvhSweepSplit sweep;
      BvhRangeBounds small_left, small_right;
      if (n <= kBvhSmallSweepMax) {
        sweep = bvh_best_small_split(refs, n, config_.cost.leaf_block);
        object.cost = sweep.cost;
        if (sweep.axis >= 0) {  // partitioned now; a spatial split or a leaf may still follow
          bvh_partition_small(refs, n, sweep, small_left, small_right);
          object.left = small_left.box();
          object.right = small_right.box();
        }
      } else {
        BvhObjectBins bins;
        bins.reset(map.bins);
        bins.add(refs, n, map);
        object = bvh_best_object_split(bins, config_.cost.leaf_block);
      }
      SpatialSplit spatial;
      if (capacity > n && (object.left.empty() || bvh_half_area(intersect(object.left, object.right)) > min_overlap_))
        spatial = find_spatial_split(refs, n, box, capacity - n);
      const double half_area = bvh_half_area(box);
      const double best = std::min(object.cost, spatial.cost);
      const double split_cost = half_area > 0.0 && best < std::numeric_limits<float>::infinity()
                                    ? bvh_split_cost(config_.cost, best, half_area)
                                    : std::numeric_limits<double>::infinity();
      if (small && !(split_cost < bvh_leaf_cost(config_.cost, n))) return make_leaf(out, slot, begin, n);
      const bool spatial_applied =
          spatial.cost < object.cost && apply_spatial_split(refs, n, capacity, spatial, left, right, n_left, n_right);
      if (!spatial_applied) {
        if (sweep.axis >= 0) {
          n_left = sweep.left_count;
          left = small_left;
          right = small_right;
        } else if (object.axis >= 0) {
          n_left = bvh_partition_object(refs, n, map, object.axis, object.bin, left, right);
        } else {
          n_left = bvh_partition_median(refs, n, centroid_axis, left, right);
        }
        if (n_left == 0 || n_left == n) n_left = bvh_partition_median(refs, n, -1, left, right);
        n_right = n - n_left;
      }
    }
    // Spare capacity goes to the children in proportion to their reference counts.
    const std::size_t spare = capacity - n_left - n_right;
    const std::size_t cap_left = n_left + static_cast<std::size_t>(static_cast<unsigned __int128>(spare) * n_left /
                                                                     (n_left + n_right));
    const std::size_t cap_right = capacity - cap_left;
    if (cap_left != n_left) std::memmove(refs + cap_left, refs + n_left, n_right * sizeof(BvhBuildRef));

    bvh_split_node(out, slot, n, [&](BvhSubtree& sub, std::uint32_t child, int side) {
      if (side == 0) build(sub, child, begin, n_left, cap_left, left, depth + 1);
      else build(sub, child, begin + cap_left, n_right, cap_right, right, depth + 1);
    });
  }

 private:
  static void make_leaf(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n) {
    out.nodes[slot].first = static_cast<std::uint32_t>(begin);
    out.nodes[slot].count = static_cast<std::uint32_t>(n);
  }

  /// A box containing the part of ref's primitive inside `part` (a sub-box of ref's box);
  /// empty when the primitive does not meet `part`.
  Bounds3f clip(const BvhBuildRef& ref, const Bounds3f& part) const {
    if (scene_.is_sphere(ref.id)) return part;
    const auto& t = scene_.mesh.triangles[ref.id];
    const auto& v = scene_.mesh.vertices;
    return clipped_triangle_bounds(v[t[0]], v[t[1]], v[t[2]], part);
  }

  /// The primitive's corners, (x, y, z, 0) each; a sphere has none (count 0), and split_estimate
  /// then cuts its box.
  struct Corners {
    alignas(16) float p[3][4];
    int count;
  };
  Corners corners(const BvhBuildRef& ref) const {
    Corners c;
    if (scene_.is_sphere(ref.id)) {
      c.count = 0;
      return c;
    }
    const auto& t = scene_.mesh.triangles[ref.id];
    for (int i = 0; i < 3; ++i) {
      const Vec3f& v = scene_.mesh.vertices[t[i]];
      c.p[i][0] = v.x;
      c.p[i][1] = v.y;
      c.p[i][2] = v.z;
      c.p[i][3] = 0.0f;
    }
    c.count = 3;
    return c;
  }

  /// A box in two SSE registers, lane 3 zero; empty as Bounds3f::empty (not lo <= hi on some axis).
  struct SseBox {
    __m128 lo, hi;
    bool empty() const { return (_mm_movemask_ps(_mm_cmpnle_ps(lo, hi)) & 7) != 0; }
  };

  /// The parts of a primitive (its corners) inside `box` on either side of the plane
  /// x[axis] = pos, for estimating spatial bins (Stich et al. §4.2: split the triangle's edges
  /// at the plane, bound the pieces, intersect with the reference's box). Float arithmetic: an
  /// estimate, not a conservative bound; the applied split clips conservatively (clip()).
  /// `axis_mask` has all bits set in lane `axis` only.
  static void split_estimate(const Corners& c, const SseBox& box, int axis, __m128 axis_mask, float pos, SseBox& left,
                             SseBox& right) {
    const __m128 at = _mm_set1_ps(pos);
    if (c.count == 0) {  // a sphere: its box, cut
      left = right = box;
    } else {
      const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), ninf = _mm_sub_ps(_mm_setzero_ps(), inf);
      __m128 llo = inf, lhi = ninf, rlo = inf, rhi = ninf;
      for (int e = 0; e < 3; ++e) {
        const float* pa = c.p[e];
        const float* pb = c.p[e == 2 ? 0 : e + 1];
        const __m128 a = _mm_load_ps(pa);
        const float da = pa[axis] - pos, db = pb[axis] - pos;
        if (da <= 0.0f) {
          llo = _mm_min_ps(llo, a);
          lhi = _mm_max_ps(lhi, a);
        }
        if (da >= 0.0f) {
          rlo = _mm_min_ps(rlo, a);
          rhi = _mm_max_ps(rhi, a);
        }
        if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
          const __m128 t = _mm_set1_ps(da / (da - db));
          __m128 q = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(_mm_load_ps(pb), a), t));
          q = _mm_blendv_ps(q, at, axis_mask);
          llo = _mm_min_ps(llo, q);
          lhi = _mm_max_ps(lhi, q);
          rlo = _mm_min_ps(rlo, q);
          rhi = _mm_max_ps(rhi, q);
        }
      }
      // Empty stays empty: lo = +inf, hi = -inf.
      left = {_mm_max_ps(llo, box.lo), _mm_min_ps(lhi, box.hi)};
      right = {_mm_max_ps(rlo, box.lo), _mm_min_ps(rhi, box.hi)};
    }
    left.hi = _mm_blendv_ps(left.hi, _mm_min_ps(left.hi, at), axis_mask);
    right.lo = _mm_blendv_ps(right.lo, _mm_max_ps(right.lo, at), axis_mask);
  }

  /// Binned spatial split (Stich et al. §4.2): spatial_bins(n) equal slabs of the node box per
  /// axis, all three axes in one pass; a reference spanning several slabs is chopped into them
  /// (split_estimate). Candidates adding more than `budget` references are skipped.
  SpatialSplit find_spatial_split(const BvhBuildRef* refs, std::size_t n, const Bounds3f& box,
                                  std::size_t budget) const {
    const int nb = spatial_bins(n);
    struct Bin {
      __m128 lo, hi;
    };
    Bin bin[3][kBvhMaxBins];
    std::uint32_t entry[3][kBvhMaxBins], exit[3][kBvhMaxBins];
    const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), ninf = _mm_sub_ps(_mm_setzero_ps(), inf);
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < nb; ++k) {
        bin[a][k] = {inf, ninf};
        entry[a][k] = exit[a][k] = 0;
      }
    float width[3], inv[3];
    bool valid[3];
    for (int a = 0; a < 3; ++a) {
      const float extent = box.hi[a] - box.lo[a];
      valid[a] = extent > 0.0f;
      width[a] = extent / static_cast<float>(nb);
      inv[a] = valid[a] ? static_cast<float>(nb) / extent : 0.0f;
    }
    auto plane = [&](int a, int k) { return k >= nb ? box.hi[a] : box.lo[a] + width[a] * static_cast<float>(k); };
    const __m128 origin = _mm_setr_ps(box.lo.x, box.lo.y, box.lo.z, 0.0f);
    const __m128 scale = _mm_setr_ps(inv[0], inv[1], inv[2], 0.0f);
    const __m128 top = _mm_set1_ps(static_cast<float>(nb - 1));
    auto bins_of = [&](__m128 x) {
      const __m128 f = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(x, origin), scale), _mm_setzero_ps()), top);
      return _mm_cvttps_epi32(f);
    };
    for (std::size_t i = 0; i < n; ++i) {
      const __m128 l = bvh_ref_lo(refs[i].lo), h = _mm_load_ps(refs[i].hi);
      alignas(16) int first[4], last[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(first), bins_of(l));
      _mm_store_si128(reinterpret_cast<__m128i*>(last), bins_of(h));
      bool corners_loaded = false;
      Corners c;
      for (int a = 0; a < 3; ++a) {
        if (!valid[a]) continue;
        ++entry[a][first[a]];
        ++exit[a][last[a]];
        if (first[a] == last[a]) {
          Bin& b = bin[a][first[a]];
          b.lo = _mm_min_ps(b.lo, l);
          b.hi = _mm_max_ps(b.hi, h);
          continue;
        }
        if (!corners_loaded) {
          c = corners(refs[i]);
          corners_loaded = true;
        }
        SseBox rest{l, h};  // chop the reference into the bins it spans
        const __m128 axis_mask = _mm_castsi128_ps(_mm_setr_epi32(-(a == 0), -(a == 1), -(a == 2), 0));
        for (int k = first[a]; k <= last[a]; ++k) {
          SseBox part = rest;
          if (k < last[a]) split_estimate(c, SseBox(rest), a, axis_mask, plane(a, k + 1), part, rest);
          if (part.empty()) continue;
          Bin& b = bin[a][k];
          b.lo = _mm_min_ps(b.lo, part.lo);
          b.hi = _mm_max_ps(b.hi, part.hi);
        }
      }
    }
    SpatialSplit best;
    float right_area[kBvhMaxBins];
    std::uint32_t right_count[kBvhMaxBins];
    for (int a = 0; a < 3; ++a) {
      if (!valid[a]) continue;
      __m128 lo = inf, hi = ninf;
      std::uint32_t count = 0;
      for (int k = nb - 1; k > 0; --k) {
        lo = _mm_min_ps(lo, bin[a][k].lo);
        hi = _mm_max_ps(hi, bin[a][k].hi);
        count += exit[a][k];
        right_area[k] = bvh_half_area(lo, hi);
        right_count[k] = count;
      }
      lo = inf;
      hi = ninf;
      count = 0;
      int best_k = -1;
      for (int k = 1; k < nb; ++k) {
        lo = _mm_min_ps(lo, bin[a][k - 1].lo);
        hi = _mm_max_ps(hi, bin[a][k - 1].hi);
        count += entry[a][k - 1];
        const std::size_t nl = count, nr = right_count[k];
        if (nl == 0 || nr == 0 || nl + nr > n + budget) continue;
        const float cost = bvh_half_area(lo, hi) * static_cast<float>(bvh_leaf_units(nl, config_.cost.leaf_block)) +
                           right_area[k] * static_cast<float>(bvh_leaf_units(nr, config_.cost.leaf_block));
        if (cost < best.cost) {
          best.cost = cost;
          best.axis = a;
          best.plane = plane(a, k);
          best.left_count = nl;
          best.right_count = nr;
          best_k = k;
        }
      }
      if (best_k >= 0) {
        BvhRangeBounds l, r;
        for (int k = 0; k < nb; ++k) {
          BvhRangeBounds& side = k < best_k ? l : r;
          side.lo = _mm_min_ps(side.lo, bin[a][k].lo);
          side.hi = _mm_max_ps(side.hi, bin[a][k].hi);
        }
        best.left = l.box();
        best.right = r.box();
      }
    }
    return best;
  }

  /// Splits refs[0, n) at split.plane, clipping straddling references or keeping them whole on
  /// the side the SAH prefers (Stich et al. §4.4), within capacity. Writes the left references
  /// to refs[0, n_left) and the right ones after them. False (refs unchanged) when a side would
  /// be empty.
  bool apply_spatial_split(BvhBuildRef* refs, std::size_t n, std::size_t capacity, const SpatialSplit& split,
                           BvhRangeBounds& left, BvhRangeBounds& right, std::size_t& n_left,
                           std::size_t& n_right) const {
    const int a = split.axis;
    const float p = split.plane;
    std::vector<BvhBuildRef> lrefs, rrefs;
    lrefs.reserve(split.left_count);
    rrefs.reserve(split.right_count);
    Bounds3f lbox = split.left, rbox = split.right;
    double nl = static_cast<double>(split.left_count), nr = static_cast<double>(split.right_count);
    std::size_t spare = capacity - n;
    for (std::size_t i = 0; i < n; ++i) {
      const BvhBuildRef& ref = refs[i];
      if (ref.hi[a] <= p) {
        lrefs.push_back(ref);
        continue;
      }
      if (ref.lo[a] >= p) {
        rrefs.push_back(ref);
        continue;
      }
      const Bounds3f rb = ref.box();
      Bounds3f lpart = rb, rpart = rb;
      lpart.hi[a] = p;
      rpart.lo[a] = p;
      lpart = clip(ref, lpart);
      rpart = clip(ref, rpart);
      if (lpart.empty() && rpart.empty()) lpart = rb;  // rounding: keep the whole reference
      if (rpart.empty()) {
        lrefs.push_back(BvhBuildRef::make(lpart, ref.id));
        continue;
      }
      if (lpart.empty()) {
        rrefs.push_back(BvhBuildRef::make(rpart, ref.id));
        continue;
      }
      const double al = bvh_half_area(lbox), ar = bvh_half_area(rbox);
      const double c_split = al * nl + ar * nr;
      const double c_left = bvh_half_area(join(lbox, rb)) * nl + ar * (nr - 1.0);
      const double c_right = al * (nl - 1.0) + bvh_half_area(join(rbox, rb)) * nr;
      if (spare > 0 && c_split <= c_left && c_split <= c_right) {
        --spare;
        lrefs.push_back(BvhBuildRef::make(lpart, ref.id));
        rrefs.push_back(BvhBuildRef::make(rpart, ref.id));
      } else if (c_left <= c_right) {
        lrefs.push_back(ref);
        lbox.extend(rb);
        nr -= 1.0;
      } else {
        rrefs.push_back(ref);
        rbox.extend(rb);
        nl -= 1.0;
      }
    }
    if (lrefs.empty() || rrefs.empty()) return false;
    n_left = lrefs.size();
    n_right = rrefs.size();
    std::copy(lrefs.begin(), lrefs.end(), refs);
    std::copy(rrefs.begin(), rrefs.end(), refs + n_left);
    left = bvh_range_bounds(refs, n_left);
    right = bvh_range_bounds(refs + n_left, n_right);
    return true;
  }

  /// Half the object bins (at least 2; Embree's SBVH bins 32 object and 16 spatial slabs), and
  /// like the object bins (bvh_object_bins) fewer for small nodes: chopping a reference costs one
  /// split per slab it spans, and the 3·bins sweep dominates small nodes.
  int spatial_bins(std::size_t n) const { return std::max(2, bvh_object_bins(config_.bins, n) / 2); }

  const Scene& scene_;
  const BvhConfig& config_;
  BvhBuildRef* refs_;
  float min_overlap_;  ///< alpha·SA(root), half areas
};

}  // namespace

Bvh2 build_bvh_spatial(const Scene& scene, const BvhConfig& config) {
  const std::size_t n = scene.primitive_count();
  if (n == 0) return Bvh2{};
  const double extra = std::max(0.0, config.max_duplication) * static_cast<double>(n);
  const std::size_t capacity = n + static_cast<std::size_t>(std::min(extra, 4294967294.0));
  if (capacity >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("build_bvh: SBVH reference capacity exceeds 2^32 - 1");
  // Uninitialised: the pages past N are touched only where spatial splits use them.
  std::unique_ptr<BvhBuildRef[]> refs(new BvhBuildRef[capacity]);
  advise_huge_pages(refs.get(), capacity * sizeof(BvhBuildRef));
  BvhRangeBounds bounds;
  for (std::size_t i = 0; i < n; ++i) {
    refs[i] = BvhBuildRef::make(bvh_build_box(scene.primitive_bounds(static_cast<unsigned>(i))),
                                static_cast<std::uint32_t>(i));
    bounds.extend(refs[i]);
  }
  BvhSubtree root;
  tbb::task_arena arena(resolve_thread_count(config.threads));
  arena.execute([&] {
    SpatialBuilder(scene, config, refs.get(), bvh_half_area(bounds.box())).build(root, 0, 0, n, capacity, bounds, 0);
  });
  return bvh_concatenate(root, n, [&](std::size_t k) { return refs[k].id; });
}

}  // namespace raylab
