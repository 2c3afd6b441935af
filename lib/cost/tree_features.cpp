#include "cost/tree_features.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_invoke.h>

#include "accel/bsp/bsp.h"
#include "accel/common/ray_sets.h"
#include "accel/bsp/bsp_cell.h"
#include "accel/bvh/bvh.h"
#include "accel/common/accel_factory.h"
#include "accel/grid/uniform_grid.h"
#include "accel/kdtree/kdtree.h"
#include "accel/kdtree/sah_cost.h"
#include "accel/nested_grid/nested_grid.h"
#include "accel/octree/octree.h"
#include "cost/provenance.h"
#include "cost/structure_cells.h"
#include "geometry/input_error.h"
#include "geometry/triangle_clipping.h"

namespace raylab {
namespace {

/// Accumulates the surface-area expectations of tree_features.h, given SA(root).
class SurfaceSums {
 public:
  SurfaceSums(double root_area, std::size_t bytes) : inv_root_(root_area > 0 ? 1.0 / root_area : 0.0) {
    f_.bytes = bytes;
  }
  void inner(double area, int depth) {
    f_.batch_cells += batch_visit_probability(area * inv_root_);
    f_.expected_inner += area * inv_root_;
    ++f_.inner_nodes;
    f_.depth = std::max(f_.depth, depth);
  }
  /// A leaf whose tests run in `groups` SIMD groups (default ⌈prims/4⌉).
  void leaf(double area, std::size_t prims, int depth, std::size_t groups = 0) {
    f_.depth = std::max(f_.depth, depth);
    if (prims == 0) return;  // empty leaves cost no test and are skipped by the traversals
    const double p = area * inv_root_;
    f_.batch_cells += batch_visit_probability(p);
    f_.expected_leaves += p;
    f_.expected_tests += p * static_cast<double>(prims);
    f_.expected_test_groups += p * static_cast<double>(groups > 0 ? groups : (prims + 3) / 4);
    ++f_.leaves;
    f_.references += prims;
  }
  TreeFeatures& features() { return f_; }

 private:
  /// 1 − (1 − p)^B: the chance that at least one of a batch of B random lines visits a cell of
  /// visit probability p.
  static double batch_visit_probability(double p) {
    p = std::clamp(p, 0.0, 1.0);
    return p >= 1.0 ? 1.0 : -std::expm1(kWorkingSetBatch * std::log1p(-p));
  }

  double inv_root_;
  TreeFeatures f_;
};

/// The surface-area sums over the cells of a tree (structure_cells.h).
TreeFeatures cell_features(const Aggregate& accel) {
  std::optional<SurfaceSums> sums;
  walk_structure_cells(accel, [&](const StructureCell& c) {
    if (!sums) sums.emplace(c.surface_area, accel.stats().bytes);
    if (c.leaf) sums->leaf(c.surface_area, c.primitives, c.depth, c.test_groups);
    else sums->inner(c.surface_area, c.depth);
    return true;
  });
  return sums ? sums->features() : TreeFeatures{};
}

/// Triangle areas and boxes of a scene's triangles, for the EPO.
struct TriangleGeometry {
  std::vector<double> area;
  std::vector<Bounds3f> box;
  double total_area = 0;
};

TriangleGeometry triangle_geometry(const Scene& scene) {
  TriangleGeometry g;
  const std::size_t n = scene.mesh.size();
  g.area.resize(n);
  g.box.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    const Vec3d a(scene.mesh.vertex(t, 0)), b(scene.mesh.vertex(t, 1)), c(scene.mesh.vertex(t, 2));
    g.area[t] = 0.5 * length(cross(b - a, c - a));
    g.box[t] = scene.mesh.triangle_bounds(t);
    g.total_area += g.area[t];
  }
  return g;
}

/// The end-point overlap of a binary BVH (tree_features.h). Top-down: the foreign primitives
/// overlapping a child's box are among the parent's foreign primitives and the sibling's, less
/// the child's own (SBVH references a primitive on both sides). O(N·depth) box tests, and one
/// clip per foreign triangle whose box is not inside the node's. The subtrees of the top
/// kParallelDepth levels run in parallel; each node's term is summed in node order, so the
/// result does not depend on the thread count.
class EndPointOverlap {
 public:
  EndPointOverlap(const Bvh2& tree, const Scene& scene)
      : tree_(tree), scene_(scene), g_(triangle_geometry(scene)), term_(tree.nodes.size(), 0.0),
        marks_([&scene] { return Marks{std::vector<std::uint32_t>(scene.primitive_count(), 0), 0}; }) {}

  double operator()() {
    if (g_.total_area <= 0 || tree_.nodes.empty()) return 0.0;
    walk({0, {}}, 0);
    double epo = 0;
    for (double t : term_) epo += t;
    return epo / g_.total_area;
  }

 private:
  static constexpr int kParallelDepth = 8;
  /// mark[p] == stamp for the primitives seen in the current pass; one per thread.
  struct Marks {
    std::vector<std::uint32_t> mark;
    std::uint32_t stamp;
  };
  struct Item {
    std::uint32_t node;
    std::vector<std::uint32_t> foreign;  ///< triangles outside the subtree overlapping the box
  };

  template <class F>
  void for_subtree_prims(std::uint32_t node, F&& f) const {
    std::vector<std::uint32_t> stack = {node};
    while (!stack.empty()) {
      const Bvh2Node& n = tree_.nodes[stack.back()];
      stack.pop_back();
      if (n.is_leaf()) {
        for (std::uint32_t i = n.first; i < n.first + n.count; ++i) f(tree_.prims[i]);
      } else {
        stack.push_back(n.first);
        stack.push_back(n.first + 1);
      }
    }
  }

  /// The area of the foreign triangles inside `box` (a triangle whose box lies inside needs no clip).
  double foreign_area(const std::vector<std::uint32_t>& foreign, const Bounds3f& box) const {
    double a = 0;
    for (std::uint32_t t : foreign) {
      if (box.contains(g_.box[t].lo) && box.contains(g_.box[t].hi)) {
        a += g_.area[t];
        continue;
      }
      const auto& tri = scene_.mesh.triangles[t];
      const auto& v = scene_.mesh.vertices;
      a += clipped_triangle_area(v[tri[0]], v[tri[1]], v[tri[2]], box);
    }
    return a;
  }

  /// Sets the node's term; returns its children's items (none for a leaf).
  std::vector<Item> visit(const Item& it) {
    const Bvh2Node& n = tree_.nodes[it.node];
    term_[it.node] = (n.is_leaf() ? static_cast<double>(n.count) : 1.0) * foreign_area(it.foreign, n.box);
    std::vector<Item> children;
    if (n.is_leaf()) return children;
    Marks& m = marks_.local();
    const std::size_t triangles = scene_.mesh.size();
    for (int side = 0; side < 2; ++side) {
      const std::uint32_t child = n.first + side, sibling = n.first + 1 - side;
      const Bounds3f& box = tree_.nodes[child].box;
      const std::uint32_t stamp = ++m.stamp;
      for_subtree_prims(child, [&](std::uint32_t p) { m.mark[p] = stamp; });
      std::vector<std::uint32_t> foreign;
      auto consider = [&](std::uint32_t p) {
        if (p < triangles && m.mark[p] != stamp && g_.box[p].overlaps(box)) {
          m.mark[p] = stamp;  // once, even if referenced twice
          foreign.push_back(p);
        }
      };
      for (std::uint32_t p : it.foreign) consider(p);
      for_subtree_prims(sibling, consider);
      children.push_back({child, std::move(foreign)});
    }
    return children;
  }

  void walk(Item item, int depth) {
    if (depth < kParallelDepth) {
      std::vector<Item> children = visit(item);
      if (children.size() == 2)
        tbb::parallel_invoke([&] { walk(std::move(children[0]), depth + 1); },
                             [&] { walk(std::move(children[1]), depth + 1); });
      return;
    }
    std::vector<Item> todo;
    todo.push_back(std::move(item));
    while (!todo.empty()) {
      const Item it = std::move(todo.back());
      todo.pop_back();
      for (Item& c : visit(it)) todo.push_back(std::move(c));
    }
  }

  const Bvh2& tree_;
  const Scene& scene_;
  const TriangleGeometry g_;
  std::vector<double> term_;
  tbb::enumerable_thread_specific<Marks> marks_;
};

TreeFeatures bvh_features(const Bvh& bvh, const Scene& scene) {
  if (bvh.tree().nodes.empty()) throw InputError("tree features: the BVH is empty");
  TreeFeatures f = cell_features(bvh);
  f.epo = EndPointOverlap(bvh.tree(), scene)();
  return f;
}

TreeFeatures grid_features(const UniformGrid& grid) {
  const GridGeometry& g = grid.geometry();
  SurfaceSums sums(surface_area_d(g.box), grid.stats().bytes);
  for (int k = 0; k < g.res[2]; ++k)
    for (int j = 0; j < g.res[1]; ++j)
      for (int i = 0; i < g.res[0]; ++i) {
        const double area = surface_area_d(g.cell_box(i, j, k));
        sums.inner(area, 0);
        sums.leaf(area, grid.cells().count(g.index(i, j, k)), 0);
      }
  return sums.features();
}

TreeFeatures nested_grid_features(const NestedGrid& grid) {
  SurfaceSums sums(surface_area_d(grid.bounds()), grid.stats().bytes);
  grid.for_each_cell([&](const Bounds3f& box, std::uint32_t count, bool) {
    const double area = surface_area_d(box);
    sums.inner(area, 0);
    sums.leaf(area, count, 0);
  });
  sums.features().depth = static_cast<int>(grid.level_count());
  return sums.features();
}

using Extractor = std::function<TreeFeatures(const Aggregate&, const Scene&)>;

/// One extractor per structure, by Aggregate::name(): a new structure adds its line here.
const std::map<std::string, Extractor>& extractors() {
  static const std::map<std::string, Extractor> table = {
      {"kdtree", [](const Aggregate& a, const Scene&) { return cell_features(a); }},
      {"octree", [](const Aggregate& a, const Scene&) { return cell_features(a); }},
      {"bsp", [](const Aggregate& a, const Scene&) { return cell_features(a); }},
      {"bvh", [](const Aggregate& a, const Scene& s) { return bvh_features(dynamic_cast<const Bvh&>(a), s); }},
      {"grid", [](const Aggregate& a, const Scene&) { return grid_features(dynamic_cast<const UniformGrid&>(a)); }},
      {"nested-grid",
       [](const Aggregate& a, const Scene&) { return nested_grid_features(dynamic_cast<const NestedGrid&>(a)); }},
      {"brute",
       [](const Aggregate&, const Scene& s) {
         TreeFeatures f;
         f.leaves = 1;
         f.references = s.primitive_count();
         f.expected_leaves = 1.0;
         f.expected_tests = static_cast<double>(s.primitive_count());
         f.expected_test_groups = static_cast<double>((s.primitive_count() + 3) / 4);
         f.batch_cells = 1.0;
         return f;
       }},
  };
  return table;
}

}  // namespace

std::string structure_family(const std::string& accel_spec) {
  SpecReader reader(parse_spec(accel_spec));
  const std::string name = reader.spec().name;
  find_accelerator_kind(name);
  if (name != "bvh") return name;
  const int width = read_bvh_config(reader).width;
  return width == 2 ? "bvh" : "bvh" + std::to_string(width);
}

const std::vector<std::string>& feature_families() {
  static const std::vector<std::string> families = {"bvh",    "bvh4", "bvh8",        "kdtree",
                                                    "octree", "bsp",  "grid",        "nested-grid", "brute"};
  return families;
}

TreeFeatures tree_features(const Aggregate& accel, const Scene& scene) {
  if (scene.instanced())
    throw InputError("tree features: instanced scene '" + scene.spec + "' (features describe one structure; use its base)");
  const auto it = extractors().find(accel.name());
  if (it == extractors().end())
    throw InputError("tree features: accelerator '" + accel.name() + "' has no structure raylab can read");
  return it->second(accel, scene);
}

void fill_tree_features(RunRecord& r, const TreeFeatures& f) {
  r.e_inner = f.expected_inner;
  r.e_leaves = f.expected_leaves;
  r.e_tests = f.expected_tests;
  r.e_test_groups = f.expected_test_groups;
  r.sah_1_1 = f.sah_1_1();
  r.epo = f.epo;
  r.inner_nodes = static_cast<std::int64_t>(f.inner_nodes);
  r.leaves = static_cast<std::int64_t>(f.leaves);
  r.references = static_cast<std::int64_t>(f.references);
  r.depth = f.depth;
  r.bytes = static_cast<std::int64_t>(f.bytes);
}

void fill_memory_features(RunRecord& r, const TreeFeatures& f) {
  const std::size_t cells = f.inner_nodes + f.leaves;
  const double bytes = static_cast<double>(f.bytes);
  const double cell_bytes = cells > 0 ? bytes / static_cast<double>(cells) : bytes;
  const double lines_per_cell = cell_bytes > 0 ? 1.0 + (cell_bytes - 1.0) / 64.0 : 0.0;
  r.lines_per_ray_est = (r.nodes_per_ray + r.leaves_per_ray) * lines_per_cell;
  r.working_set_bytes_est = std::min(bytes, cell_bytes * f.batch_cells);
  r.bytes_over_l2 = r.l2_bytes > 0 ? bytes / static_cast<double>(r.l2_bytes) : 0.0;
  r.bytes_over_llc = r.llc_bytes > 0 ? bytes / static_cast<double>(r.llc_bytes) : 0.0;
}

RunRecord record_for_prediction(const TreeFeatures& f, const std::string& ray_kind, double primitives) {
  RunRecord r;
  r.ray_kind = ray_kind;
  r.query = is_any_hit_ray_spec(ray_kind) ? "occluded" : "intersect";
  r.primitives = static_cast<std::int64_t>(primitives);
  const Provenance& p = provenance_of_this_process();
  r.l2_bytes = p.l2_bytes;
  r.llc_bytes = p.llc_bytes;
  r.l1d_bytes = p.l1d_bytes;
  r.cache_source = p.cache_source;
  fill_tree_features(r, f);
  fill_memory_features(r, f);
  return r;
}

}  // namespace raylab
