#include "accel/bvh/bvh_build.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "accel/bvh/bvh_builders.h"
#include "accel/bvh/bvh_optimize.h"
#include "accel/kdtree/sah_cost.h"

namespace raylab {
namespace {

/// The references of a subtree: ids[begin, end) with their boxes and centroids.
struct BuildRefs {
  const std::vector<Bounds3f>& boxes;
  std::vector<Vec3f> centroids;
  std::vector<std::uint32_t> ids;
};

Bounds3f bounds_of(const BuildRefs& r, std::size_t begin, std::size_t end, Bounds3f* centroid_bounds) {
  Bounds3f b, c;
  for (std::size_t i = begin; i < end; ++i) {
    b.extend(r.boxes[r.ids[i]]);
    c.extend(r.centroids[r.ids[i]]);
  }
  *centroid_bounds = c;
  return b;
}

/// The lecture's midpoint and median splits along the centroid bounds' longest axis.
class MidpointMedianBuilder {
 public:
  MidpointMedianBuilder(const std::vector<Bounds3f>& boxes, const BvhConfig& config) : refs_{boxes, {}, {}}, config_(config) {
    refs_.centroids.resize(boxes.size());
    for (std::size_t i = 0; i < boxes.size(); ++i)
      refs_.centroids[i] = boxes[i].empty() ? Vec3f(0.0f) : boxes[i].center();
    refs_.ids.resize(boxes.size());
    std::iota(refs_.ids.begin(), refs_.ids.end(), 0u);
  }

  Bvh2 build() {
    Bvh2 bvh;
    bvh.primitive_count = refs_.boxes.size();
    if (refs_.ids.empty()) return bvh;
    nodes_.emplace_back();
    build_node(0, 0, refs_.ids.size(), 0);
    bvh.nodes = std::move(nodes_);
    bvh.prims = std::move(refs_.ids);
    return bvh;
  }

 private:
  void make_leaf(std::uint32_t node, std::size_t begin, std::size_t end) {
    nodes_[node].first = static_cast<std::uint32_t>(begin);
    nodes_[node].count = static_cast<std::uint32_t>(end - begin);
  }

  void build_node(std::uint32_t node, std::size_t begin, std::size_t end, int depth) {
    Bounds3f cb;
    nodes_[node].box = bounds_of(refs_, begin, end, &cb);
    const std::size_t n = end - begin;
    if (n == 1) return make_leaf(node, begin, end);
    std::size_t mid = begin + n / 2;
    const int axis = cb.largest_axis();
    auto by_axis = [&](int a) {
      return [this, a](std::uint32_t x, std::uint32_t y) {
        const float cx = refs_.centroids[x][a], cy = refs_.centroids[y][a];
        return cx < cy || (cx == cy && x < y);
      };
    };
    auto* first = refs_.ids.data() + begin;
    auto* last = refs_.ids.data() + end;
    const BvhBuilder builder = depth >= kBvhMaxDepth - 32 ? BvhBuilder::median : config_.builder;
    switch (builder) {
      case BvhBuilder::midpoint: {
        if (n <= static_cast<std::size_t>(config_.max_leaf_size)) return make_leaf(node, begin, end);
        const float m = cb.center()[axis];
        auto* it = std::partition(first, last, [&](std::uint32_t id) { return refs_.centroids[id][axis] < m; });
        if (it == first || it == last) {
          std::nth_element(first, first + n / 2, last, by_axis(axis));
        } else {
          mid = static_cast<std::size_t>(it - refs_.ids.data());
        }
        break;
      }
      default:  // median (the SAH builders live in bvh_*_sah.cpp and bvh_spatial_split.cpp)
        if (n <= static_cast<std::size_t>(config_.max_leaf_size)) return make_leaf(node, begin, end);
        std::nth_element(first, first + n / 2, last, by_axis(axis));
        break;
    }
    const auto left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    nodes_.emplace_back();
    nodes_[node].first = left;
    nodes_[node].count = 0;
    build_node(left, begin, mid, depth + 1);
    build_node(left + 1, mid, end, depth + 1);
  }

  BuildRefs refs_;
  const BvhConfig& config_;
  std::vector<Bvh2Node> nodes_;
};

Bvh2 optimized(Bvh2 bvh, const BvhConfig& config) {
  if (config.optimize == BvhOptimize::reinsert)
    optimize_bvh_reinsertion(bvh, config.cost, config.optimize_passes, config.optimize_budget, config.threads);
  return bvh;
}

void check_reference_count(std::size_t n) {
  if (n >= std::numeric_limits<std::uint32_t>::max()) throw std::length_error("build_bvh: more than 2^32 - 1 primitives");
}

}  // namespace

Bvh2 build_bvh_over_boxes(const std::vector<Bounds3f>& boxes, const BvhConfig& config) {
  check_reference_count(boxes.size());
  switch (config.builder) {
    case BvhBuilder::midpoint:
    case BvhBuilder::median: return optimized(MidpointMedianBuilder(boxes, config).build(), config);
    case BvhBuilder::sweep: return optimized(build_bvh_sweep_sah(boxes, config), config);
    case BvhBuilder::binned:
    case BvhBuilder::spatial: break;
  }
  return optimized(build_bvh_binned_sah(boxes, config), config);
}

Bvh2 build_bvh(const Scene& scene, const BvhConfig& config) {
  if (config.builder == BvhBuilder::spatial) return optimized(build_bvh_spatial(scene, config), config);
  if (config.builder == BvhBuilder::binned) {
    check_reference_count(scene.primitive_count());
    return optimized(build_bvh_binned_sah(scene, config), config);
  }
  std::vector<Bounds3f> boxes(scene.primitive_count());
  for (std::size_t i = 0; i < boxes.size(); ++i) boxes[i] = scene.primitive_bounds(static_cast<unsigned>(i));
  return build_bvh_over_boxes(boxes, config);
}

double bvh_sah_cost(const Bvh2& bvh, const BvhSahCost& cost) {
  if (bvh.nodes.empty()) return 0.0;
  const double root = surface_area_d(bvh.nodes[0].box);
  if (!(root > 0.0)) return 0.0;
  double total = 0.0;
  for (const Bvh2Node& n : bvh.nodes) {
    const double a = surface_area_d(n.box) / root;
    total += n.is_leaf() ? cost.c_isect * bvh_leaf_units(n.count, cost.leaf_block) * a : cost.c_trav * a;
  }
  return total;
}

int bvh_depth(const Bvh2& bvh) {
  if (bvh.nodes.empty()) return 0;
  int deepest = 0;
  std::vector<std::pair<std::uint32_t, int>> todo = {{0u, 0}};
  while (!todo.empty()) {
    const auto [i, d] = todo.back();
    todo.pop_back();
    const Bvh2Node& n = bvh.nodes[i];
    if (n.is_leaf()) {
      deepest = std::max(deepest, d);
    } else {
      todo.push_back({n.first, d + 1});
      todo.push_back({n.first + 1, d + 1});
    }
  }
  return deepest;
}

}  // namespace raylab
