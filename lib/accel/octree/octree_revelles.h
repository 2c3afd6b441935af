#pragma once
/// Octree traversal in ray order by the parametric algorithm of Revelles, Ureña and Lastra, "An
/// Efficient Parametric Algorithm for Octree Traversal" (WSCG 2000).
///
/// Each node carries the ray's parameters at its six faces, t0[a] (entry) and t1[a] (exit); the
/// centre planes' tm[a] = (mid[a] - o[a]) / d[a] are computed at the node, and a child's
/// parameters are selections of t0, tm, t1 (§3). Mirroring (§4): along each axis with d[a] < 0
/// the ray is reflected so that all direction components are positive, and child i of the
/// mirrored node is child i ^ mask of the real node (mask bit a set iff d[a] < 0, with
/// d[a] = -0 counting as negative, as inv[a] = -inf). The reflection is applied to the
/// parameters, never to coordinates: t0 and t1 are swapped on mirrored axes, so every t is
/// computed from the real planes exactly as the builder placed them (octree_mid).
///
/// In the mirrored frame the ray visits children in increasing bit order. The first child is
/// selected from the entry plane (the axis of max t0, the paper's Table 1): bit a is set when
/// tm[a] < max t0. The next child follows from the exit plane of the current one (the axis of
/// min exit, the paper's Table 2: from child c through the face of axis a, to c | bit a, or out
/// of the node when bit a is already set).
///
/// Robustness (as the kd-tree's, kdtree_traversal.h and tree_ray.h): every t carries a relative
/// error below 3 ulps, so comparisons use t widened by kPlaneSlack·|t|. A comparison that the widening
/// cannot decide (an entry or exit within the slack of a centre plane: the ray passes near a
/// cell edge or corner) takes both branches: both first-child candidates and every face whose
/// exit ties the minimum become successors. A child is then visited iff its widened interval
/// meets the ray's, so no child the exact ray crosses is skipped; children are taken in order
/// of their entry t (ties: the one with fewer bits, which the other's entry cannot precede).
/// A ray with d[a] = ±0 has t = ±inf at the planes of axis a; one lying in a plane (0·inf = NaN)
/// takes tm[a] = -inf and t0/t1 = ∓inf, i.e. it visits one closed side, which suffices because
/// placement is closed.
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "accel/common/tree_ray.h"
#include "accel/octree/octree_node.h"

namespace raylab {

/// The parameter t widened by its rounding error, downward and upward (widened_plane_t; t is
/// never NaN here).
inline float oct_t_below(float t) { return widened_plane_t(t).lo; }
inline float oct_t_above(float t) { return widened_plane_t(t).hi; }

/// The mirrored-frame walk over the leaves a ray crosses, front to back.
///
///   leaf(index, box, t_enter, t_exit) -> bool: called for each stored (non-empty) leaf whose
///     widened interval meets [tmin, min(tmax, cut())]; returning true ends the walk (an answered
///     any-hit query).
///   cut() -> float: the closest hit so far; cells entered after it are skipped.
/// Returns true iff a leaf call returned true.
template <class Leaf, class Cut, class Counters>
class OctreeRevellesWalk {
 public:
  OctreeRevellesWalk(const OctNode* nodes, const Ray& ray, const Vec3f& inv, float tmin, float tmax, Leaf& leaf,
                     Cut& cut, Counters& counters)
      : nodes_(nodes), ray_(ray), inv_(inv), tmin_(tmin), tmax_(tmax), leaf_(leaf), cut_(cut), counters_(counters) {
    for (int a = 0; a < 3; ++a)
      if (inv[a] < 0.0f) mask_ |= 1u << a;
  }

  bool run(const Bounds3f& root) {
    float t0[3], t1[3];
    for (int a = 0; a < 3; ++a) {
      const bool m = mask_ & (1u << a);
      t0[a] = plane_t(m ? root.hi[a] : root.lo[a], a, -std::numeric_limits<float>::infinity());
      t1[a] = plane_t(m ? root.lo[a] : root.hi[a], a, std::numeric_limits<float>::infinity());
    }
    return visit(0, root, t0, t1);
  }

 private:
  /// (p - o[a]) / d[a]; `if_in_plane` when the ray lies in the plane (0·inf).
  float plane_t(float p, int a, float if_in_plane) const {
    const float t = (p - ray_.org[a]) * inv_[a];
    return std::isnan(t) ? if_in_plane : t;
  }

  bool visit(std::uint32_t index, const Bounds3f& box, const float t0[3], const float t1[3]) {
    const OctNode& node = nodes_[index];
    if (node.is_leaf())
      return leaf_(index, box, std::max(std::max(t0[0], t0[1]), t0[2]), std::min(std::min(t1[0], t1[1]), t1[2]));
    counters_.node();
    // An axis that is not split (octree_split_axes) keeps the real lower child: the mirrored bit
    // is fixed at the mirror's, by a centre plane at -inf (crossed before entry) or +inf (never).
    float tm[3];
    const unsigned split = octree_split_axes(box);
    for (int a = 0; a < 3; ++a)
      tm[a] = split & (1u << a) ? plane_t(octree_mid(box, a), a, -std::numeric_limits<float>::infinity())
              : mask_ & (1u << a) ? -std::numeric_limits<float>::infinity()
                                  : std::numeric_limits<float>::infinity();

    // First child (Table 1): the entry plane is the axis of max t0; bit a is set where the ray
    // has crossed the centre plane a before entering, left open where that is undecided.
    const float t_entry = std::max(std::max(t0[0], t0[1]), t0[2]);
    unsigned sure = 0, open = 0;
    for (int a = 0; a < 3; ++a) {
      if (oct_t_above(tm[a]) < oct_t_below(t_entry)) sure |= 1u << a;
      else if (!(oct_t_below(tm[a]) > oct_t_above(t_entry))) open |= 1u << a;
    }
    unsigned pending = 0;  // bit c: mirrored child c is a candidate
    for (unsigned s = open;; s = (s - 1) & open) {  // every subset of the undecided bits
      pending |= 1u << (sure | s);
      if (s == 0) break;
    }

    auto enter = [&](unsigned c) {
      return std::max(std::max(c & 1u ? tm[0] : t0[0], c & 2u ? tm[1] : t0[1]), c & 4u ? tm[2] : t0[2]);
    };
    auto exit = [&](unsigned c) {
      return std::min(std::min(c & 1u ? t1[0] : tm[0], c & 2u ? t1[1] : tm[1]), c & 4u ? t1[2] : tm[2]);
    };
    unsigned done = 0;
    while (pending) {
      unsigned c = static_cast<unsigned>(__builtin_ctz(pending));
      float c_enter = enter(c);
      for (unsigned p = pending & (pending - 1); p; p &= p - 1) {
        const unsigned i = static_cast<unsigned>(__builtin_ctz(p));
        const float e = enter(i);
        if (e < c_enter) c = i, c_enter = e;
      }
      pending &= ~(1u << c);
      done |= 1u << c;
      const float in_lo = oct_t_below(c_enter), out_hi = oct_t_above(exit(c));
      if (in_lo > std::min(tmax_, cut_())) break;  // this and every later child lies beyond
      // A child the widened ray misses is not visited, but its successors are: the exact ray may
      // pass from c through a cell edge or corner straight into c | bit a | bit b.
      if (in_lo <= out_hi && out_hi >= tmin_) {
        float ct0[3], ct1[3];
        for (int a = 0; a < 3; ++a) {
          const bool is_split = split & (1u << a);
          ct0[a] = c & (1u << a) && is_split ? tm[a] : t0[a];
          ct1[a] = c & (1u << a) || !is_split ? t1[a] : tm[a];
        }
        const unsigned child = c ^ mask_;
        if (node.has_child(child) && visit(node.child(child), octree_child_box(box, child), ct0, ct1)) return true;
      }
      // Next child (Table 2): through the face of the axis of min exit, and of any axis whose
      // exit ties it within the slack; leaving through a face of the node adds nothing.
      for (int a = 0; a < 3; ++a) {
        const unsigned next = c | (1u << a);
        if (next != c && !(done & (1u << next)) && !(oct_t_below(tm[a]) > out_hi)) pending |= 1u << next;
      }
    }
    return false;
  }

  const OctNode* nodes_;
  const Ray& ray_;
  Vec3f inv_;
  float tmin_, tmax_;
  Leaf& leaf_;
  Cut& cut_;
  Counters& counters_;
  unsigned mask_ = 0;
};

/// Calls leaf(index, box, t_enter, t_exit) for the leaves `ray` crosses, front to back (see
/// OctreeRevellesWalk); `cut()` bounds the walk by the closest hit so far.
template <class Leaf, class Cut, class Counters>
bool octree_walk_revelles(const OctNode* nodes, const Bounds3f& root, const Ray& ray, Leaf&& leaf, Cut&& cut,
                          Counters& counters) {
  const Vec3f inv = safe_inverse(ray.dir);
  float t0, t1;
  if (!tree_root_interval(root, ray, inv, t0, t1)) return false;
  OctreeRevellesWalk<std::remove_reference_t<Leaf>, std::remove_reference_t<Cut>, Counters> walk(
      nodes, ray, inv, t0, t1, leaf, cut, counters);
  return walk.run(root);
}

}  // namespace raylab
