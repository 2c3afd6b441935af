#include "accel/bsp/bsp_build.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "accel/bsp/bsp_cell.h"
#include "accel/bsp/bsp_plane.h"
#include "accel/kdtree/split_clipping.h"

namespace raylab {

int bsp_max_depth(const BspConfig& config, std::size_t n) {
  if (config.max_depth > 0) return std::min(config.max_depth, 48);
  const double d = 6.0 + 1.3 * std::log2(static_cast<double>(std::max<std::size_t>(n, 1)));
  return std::min(48, static_cast<int>(std::lround(d)));
}

namespace {

constexpr std::size_t kCountSample = 1024;
constexpr float kMinEmptySlab = 1e-5f;

class BspBuilder {
 public:
  BspBuilder(const Scene& scene, const BspConfig& config, BspTreeData& out) : scene_(scene), config_(config), out_(out) {
    bounds_.resize(scene.primitive_count());
    for (std::uint32_t i = 0; i < bounds_.size(); ++i) bounds_[i] = scene.primitive_bounds(i);
  }

  void build_root() {
    std::vector<std::uint32_t> refs(scene_.primitive_count());
    for (std::uint32_t i = 0; i < refs.size(); ++i) refs[i] = i;
    max_depth_ = bsp_max_depth(config_, refs.size());
    const ConvexCell root(out_.bounds);
    root_sa_ = root.surface_area();
    build(refs, root, 0);
  }

 private:
  double weight(double sa) const { return root_sa_ > 0.0 ? sa / root_sa_ : 1.0; }

  void make_leaf(std::vector<std::uint32_t>& refs, double sa, int depth) {
    const auto first = static_cast<std::uint32_t>(out_.prims.size());
    out_.prims.insert(out_.prims.end(), refs.begin(), refs.end());
    std::sort(out_.prims.begin() + first, out_.prims.end());
    BspNode n{};
    n.index = first;
    n.count = static_cast<std::uint32_t>(refs.size());
    out_.nodes.push_back(n);
    out_.sah_cost += config_.cost.leaf(refs.size()) * weight(sa);
    ++out_.leaves;
    out_.depth = std::max(out_.depth, depth);
  }

  /// Approximate side counts for ranking (double-precision distances, and overlap of the
  /// primitive's bounds with the child cells' boxes).
  void count(const std::vector<std::uint32_t>& refs, const BspPlane& plane, const Bounds3f& neg_box,
             const Bounds3f& pos_box, std::size_t& n_neg, std::size_t& n_pos) const {
    n_neg = n_pos = 0;
    for (std::uint32_t p : refs) {
      const Bounds3f& b = bounds_[p];
      if (!b.overlaps(pos_box) && !b.overlaps(neg_box)) continue;
      bool pos = false, neg = false;
      if (scene_.is_sphere(p)) {
        const BspSide s = classify(scene_, p, plane);
        pos = s != BspSide::negative;
        neg = s != BspSide::positive;
      } else {
        const auto& t = scene_.mesh.triangles[p];
        int sp = 0, sn = 0;
        for (int i = 0; i < 3; ++i) {
          const double d = plane.signed_distance(Vec3d(scene_.mesh.vertices[t[i]]));
          sp += d > 0.0;
          sn += d < 0.0;
        }
        pos = sp > 0 || sn == 0;
        neg = sn > 0 || sp == 0;
      }
      n_pos += pos && b.overlaps(pos_box);
      n_neg += neg && b.overlaps(neg_box);
    }
  }

  std::vector<BspPlane> candidates(const std::vector<std::uint32_t>& refs) const {
    std::vector<BspPlane> planes;
    const std::size_t n = refs.size();
    const std::size_t k = static_cast<std::size_t>(std::max(config_.triangle_candidates, 0));
    if (k > 0) {
      const std::size_t step = std::max<std::size_t>(1, n / k);
      for (std::size_t i = 0; i < n && planes.size() < k; i += step) {
        BspPlane p;
        if (triangle_plane(scene_, refs[i], p)) planes.push_back(p);
      }
    }
    const int q = std::max(config_.axis_candidates, 0);
    std::vector<float> centres(n);
    for (int a = 0; a < 3 && q > 0; ++a) {
      for (std::size_t i = 0; i < n; ++i) centres[i] = bounds_[refs[i]].center()[a];
      for (int j = 1; j <= q; ++j) {
        const std::size_t k = std::min(n - 1, n * static_cast<std::size_t>(j) / static_cast<std::size_t>(q + 1));
        std::nth_element(centres.begin(), centres.begin() + static_cast<std::ptrdiff_t>(k), centres.end());
        planes.push_back(axis_plane(a, centres[k]));
      }
    }
    return planes;
  }

  static BspPlane axis_plane(int axis, float pos) {
    BspPlane p;
    p.axis = axis;
    p.pos = pos;
    p.normal = Vec3d(0.0);
    p.normal[axis] = 1.0;
    p.origin = Vec3d(0.0);
    p.origin[axis] = pos;
    p.offset = pos;
    p.scale = 1.0;
    return p;
  }

  struct EmptySpaceCut {
    BspPlane plane;
    bool negative_empty;  ///< which side holds no primitive
  };

  /// Axis planes one float outside the bounds of all the node's primitives: one side holds none
  /// of them, and only such a split earns SahCost's empty-space bonus (the centre candidates
  /// always leave primitives on both sides). The empty slab must be wider than kMinEmptySlab
  /// relative to its coordinates: cell boxes are rounded outward, and a slab of a few ulps
  /// could otherwise be cut off again and again.
  std::vector<EmptySpaceCut> empty_space_cuts(const std::vector<std::uint32_t>& refs, const Bounds3f& cell_box) const {
    Bounds3f used;
    for (std::uint32_t p : refs) used.extend(bounds_[p]);
    std::vector<EmptySpaceCut> cuts;
    constexpr float kInf = std::numeric_limits<float>::infinity();
    auto wide = [](float from, float to) {
      return to - from > kMinEmptySlab * (std::abs(from) + std::abs(to));
    };
    for (int a = 0; a < 3; ++a) {
      if (const float below = std::nextafter(used.lo[a], -kInf); wide(cell_box.lo[a], below) && below < cell_box.hi[a])
        cuts.push_back({axis_plane(a, below), true});
      if (const float above = std::nextafter(used.hi[a], kInf); wide(above, cell_box.hi[a]) && above > cell_box.lo[a])
        cuts.push_back({axis_plane(a, above), false});
    }
    return cuts;
  }

  void build(std::vector<std::uint32_t>& refs, const ConvexCell& cell, int depth) {
    const std::size_t n = refs.size();
    const double sa = cell.surface_area();
    if (n <= static_cast<std::size_t>(std::max(config_.leaf_size, 1)) || depth >= max_depth_ || !(sa > 0.0)) {
      make_leaf(refs, sa, depth);
      return;
    }
    double best_cost = std::numeric_limits<double>::infinity();
    BspPlane best;
    ConvexCell::SplitEstimate est;
    // Large nodes rank candidates on an evenly spaced sample of their primitives, counts scaled
    // up: the ranking needs estimates, the placement below is exact.
    const std::vector<std::uint32_t>* sample = &refs;
    std::vector<std::uint32_t> sampled;
    if (n > kCountSample) {
      for (std::size_t i = 0; i < kCountSample; ++i) sampled.push_back(refs[i * n / kCountSample]);
      sample = &sampled;
    }
    const double scale = static_cast<double>(n) / static_cast<double>(sample->size());
    // Keeps `p` when its split of `cell` costs less, ranked on estimated parts (estimate_split:
    // no part is built); the counts are a function of the estimate.
    auto consider = [&](const BspPlane& p, auto&& side_counts) {
      if (!cell.estimate_split(p, est)) return;
      const auto [n_neg, n_pos] = side_counts();
      const double c = config_.cost.split(sa, est.negative_area, est.positive_area, n_neg, n_pos);
      if (c < best_cost) {
        best_cost = c;
        best = p;
      }
    };
    for (const BspPlane& p : candidates(refs))
      consider(p, [&] {
        std::size_t s_neg, s_pos;
        count(*sample, p, est.negative_box, est.positive_box, s_neg, s_pos);
        return std::pair{static_cast<std::size_t>(std::llround(static_cast<double>(s_neg) * scale)),
                         static_cast<std::size_t>(std::llround(static_cast<double>(s_pos) * scale))};
      });
    // No primitive reaches a cut's empty side: its counts are known, not estimated.
    for (const EmptySpaceCut& cut : empty_space_cuts(refs, cell.bounds()))
      consider(cut.plane, [&] { return cut.negative_empty ? std::pair{std::size_t{0}, n} : std::pair{n, std::size_t{0}}; });
    ConvexCell best_neg, best_pos;
    if (best_cost < config_.cost.leaf(n)) cell.split(best, best_neg, best_pos);
    if (!(best_cost < config_.cost.leaf(n)) || best_neg.empty() || best_pos.empty()) {
      make_leaf(refs, sa, depth);
      return;
    }
    // A primitive goes to a side when it meets the side's closed half-space (exact) and the
    // closed box of the side's cell (exact for triangles, split_clipping.h): both are
    // conservative, so a primitive meeting the closed cell is never dropped.
    std::vector<std::uint32_t> left, right;
    const Bounds3f neg_box = best_neg.bounds(), pos_box = best_pos.bounds();
    for (std::uint32_t p : refs) {
      const BspSide s = classify(scene_, p, best);
      const PrimRef ref{bounds_[p], p};
      if (s != BspSide::positive && ref_meets_box(scene_, ref, neg_box, ClipMode::exact)) left.push_back(p);
      if (s != BspSide::negative && ref_meets_box(scene_, ref, pos_box, ClipMode::exact)) right.push_back(p);
    }
    if (left.size() == n && right.size() == n) {
      make_leaf(refs, sa, depth);
      return;
    }
    std::vector<std::uint32_t>().swap(refs);
    out_.sah_cost += config_.cost.c_trav * weight(sa);
    if (best.axis < 0) ++out_.triangle_planes;
    const auto index = static_cast<std::uint32_t>(out_.nodes.size());
    BspNode node{{best.normal.x, best.normal.y, best.normal.z},
                 {best.origin.x, best.origin.y, best.origin.z},
                 best.scale,
                 0,
                 best.axis >= 0 ? BspNode::kAxisInterior + static_cast<std::uint32_t>(best.axis) : BspNode::kInterior};
    out_.nodes.push_back(node);
    build(left, best_neg, depth + 1);
    out_.nodes[index].index = static_cast<std::uint32_t>(out_.nodes.size());
    build(right, best_pos, depth + 1);
  }

  const Scene& scene_;
  const BspConfig& config_;
  BspTreeData& out_;
  std::vector<Bounds3f> bounds_;
  int max_depth_ = 0;
  double root_sa_ = 0.0;
};

}  // namespace

BspTreeData build_bsp(const Scene& scene, const BspConfig& config) {
  BspTreeData data;
  data.bounds = scene.bounds();
  BspBuilder builder(scene, config, data);
  builder.build_root();
  return data;
}

}  // namespace raylab
