#include "accel/octree/octree_build.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace raylab {

int octree_max_depth(const OctreeConfig& config, std::size_t n) {
  if (config.max_depth > 0) return std::min(config.max_depth, 20);
  const double d = 3.0 + std::ceil(std::log2(static_cast<double>(std::max<std::size_t>(n, 1))) / 3.0);
  return std::min(20, static_cast<int>(d));
}

namespace {

class OctreeBuilder {
 public:
  OctreeBuilder(const Scene& scene, const OctreeConfig& config, OctreeData& out)
      : scene_(scene), config_(config), out_(out) {}

  void build_root(std::vector<PrimRef> refs) {
    max_depth_ = octree_max_depth(config_, refs.size());
    root_sa_ = surface_area_d(out_.bounds);
    out_.nodes.emplace_back();
    build(refs, out_.bounds, 0, 0);
  }

 private:
  double weight(const Bounds3f& b) const { return root_sa_ > 0.0 ? surface_area_d(b) / root_sa_ : 1.0; }

  void make_leaf(std::uint32_t index, const std::vector<PrimRef>& refs, const Bounds3f& box, int depth) {
    const auto first = static_cast<std::uint32_t>(out_.prims.size());
    for (const PrimRef& r : refs) out_.prims.push_back(r.prim);
    std::sort(out_.prims.begin() + first, out_.prims.end());
    out_.nodes[index] = {first, static_cast<std::uint32_t>(refs.size())};
    out_.sah_cost += config_.cost.leaf(refs.size()) * weight(box);
    ++out_.leaves;
    out_.depth = std::max(out_.depth, depth);
  }

  /// An empty child is not stored; it counts as a leaf of the tree all the same.
  void count_empty_leaf(const Bounds3f& box, int depth) {
    out_.sah_cost += config_.cost.leaf(0) * weight(box);
    ++out_.leaves;
    out_.depth = std::max(out_.depth, depth);
  }

  void build(std::vector<PrimRef>& refs, const Bounds3f& box, int depth, std::uint32_t index) {
    const std::size_t n = refs.size();
    const double sa = surface_area_d(box);
    if (n == 0 || depth >= max_depth_ || !(sa > 0.0)) {
      make_leaf(index, refs, box, depth);
      return;
    }
    std::vector<PrimRef> child_refs[8];
    Bounds3f child_box[8];
    double cost = config_.cost.c_trav;
    for (unsigned i = 0; i < 8; ++i) {
      if (!octree_child_exists(box, i)) continue;
      child_box[i] = octree_child_box(box, i);
      for (const PrimRef& r : refs)
        if (ref_meets_box(scene_, r, child_box[i], config_.clip))
          child_refs[i].push_back({ref_bounds_in(scene_, r, child_box[i], config_.clip), r.prim});
      cost += config_.cost.c_isect * surface_area_d(child_box[i]) / sa * static_cast<double>(child_refs[i].size());
      if (!child_refs[i].empty()) cost += config_.cost.c_leaf * surface_area_d(child_box[i]) / sa;
    }
    if (!(cost < config_.cost.leaf(n))) {
      make_leaf(index, refs, box, depth);
      return;
    }
    std::vector<PrimRef>().swap(refs);
    out_.sah_cost += config_.cost.c_trav * weight(box);
    const auto first = static_cast<std::uint32_t>(out_.nodes.size());
    std::uint32_t mask = 0;
    for (unsigned i = 0; i < 8; ++i)
      if (!child_refs[i].empty()) mask |= 1u << i;
    out_.nodes[index] = {first, OctNode::kInterior | mask};
    out_.nodes.resize(out_.nodes.size() + static_cast<std::size_t>(std::popcount(mask)));
    for (unsigned i = 0; i < 8; ++i) {
      if (!octree_child_exists(box, i)) continue;
      if (child_refs[i].empty()) {
        count_empty_leaf(child_box[i], depth + 1);
        continue;
      }
      build(child_refs[i], child_box[i], depth + 1, out_.nodes[index].child(i));
    }
  }

  const Scene& scene_;
  const OctreeConfig& config_;
  OctreeData& out_;
  int max_depth_ = 0;
  double root_sa_ = 0.0;
};

}  // namespace

OctreeData build_octree(const Scene& scene, const OctreeConfig& config) {
  OctreeData data;
  Bounds3f b = scene.bounds();
  // A flat axis would make every centre split duplicate the node along it: pad it.
  const float extent = max_component(b.diagonal());
  for (int a = 0; a < 3; ++a)
    if (!(b.hi[a] > b.lo[a])) {
      const float pad = extent > 0.0f ? 1e-3f * extent : 1.0f;
      b.lo[a] -= pad;
      b.hi[a] += pad;
    }
  data.bounds = b;
  OctreeBuilder builder(scene, config, data);
  builder.build_root(make_root_refs(scene));
  return data;
}

}  // namespace raylab
