#include "cost/structure_cells.h"

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "accel/bsp/bsp.h"
#include "accel/bsp/bsp_cell.h"
#include "accel/bvh/bvh.h"
#include "accel/kdtree/kdtree.h"
#include "accel/octree/octree.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

using Visit = std::function<bool(const StructureCell&)>;

StructureCell box_cell(const Bounds3f& box, int depth) {
  StructureCell c;
  c.box = box;
  c.surface_area = surface_area_d(box);
  c.depth = depth;
  return c;
}

StructureCell leaf_cell(const Bounds3f& box, std::size_t primitives, int depth, std::size_t groups = 0) {
  StructureCell c = box_cell(box, depth);
  c.leaf = true;
  c.primitives = primitives;
  c.test_groups = groups;
  return c;
}

/// Depth-first, with an explicit stack: `step(item, stack)` visits one item and pushes the items
/// of its children (the first popped is the last pushed).
template <class Item, class Step>
void depth_first(Item root, const Step& step) {
  std::vector<Item> stack;
  stack.push_back(std::move(root));
  while (!stack.empty()) {
    Item it = std::move(stack.back());
    stack.pop_back();
    step(it, stack);
  }
}

/// A node of a tree whose cells are boxes, as the walk carries it.
struct BoxItem {
  std::uint32_t node;
  Bounds3f box;
  int depth;
};

void walk_kdtree(const KdTree& tree, const Visit& visit) {
  const KdTreeData& d = tree.data();
  depth_first(BoxItem{0, d.bounds, 0}, [&](const BoxItem& it, std::vector<BoxItem>& stack) {
    const KdNode& n = d.nodes[it.node];
    if (n.is_leaf()) {
      visit(leaf_cell(it.box, n.count(), it.depth));
      return;
    }
    if (!visit(box_cell(it.box, it.depth))) return;
    stack.push_back({n.above_child(), it.box.above(n.axis(), n.split), it.depth + 1});
    stack.push_back({it.node + 1, it.box.below(n.axis(), n.split), it.depth + 1});
  });
}

void walk_octree(const Octree& tree, const Visit& visit) {
  const OctreeData& d = tree.data();
  depth_first(BoxItem{0, d.bounds, 0}, [&](const BoxItem& it, std::vector<BoxItem>& stack) {
    const OctNode& n = d.nodes[it.node];
    if (n.is_leaf()) {
      visit(leaf_cell(it.box, n.count, it.depth));
      return;
    }
    if (!visit(box_cell(it.box, it.depth))) return;
    for (unsigned i = 0; i < 8; ++i)
      if (!octree_child_exists(it.box, i)) continue;  // a flat box has four or two children
      else if (n.has_child(i)) stack.push_back({n.child(i), octree_child_box(it.box, i), it.depth + 1});
      else visit(leaf_cell(octree_child_box(it.box, i), 0, it.depth + 1));  // an empty child is not stored
  });
}

void walk_bsp(const BspTree& tree, const Visit& visit) {
  const BspTreeData& d = tree.data();
  struct Item {
    std::uint32_t node;
    ConvexCell cell;
    int depth;
  };
  depth_first(Item{0, ConvexCell(d.bounds), 0}, [&](Item& it, std::vector<Item>& stack) {
    const BspNode& n = d.nodes[it.node];
    StructureCell c;
    c.polytope = &it.cell;
    c.surface_area = it.cell.surface_area();
    c.depth = it.depth;
    c.leaf = n.is_leaf();
    c.primitives = c.leaf ? n.count : 0;
    if (!visit(c) || c.leaf) return;
    BspPlane plane;
    plane.normal = {n.normal[0], n.normal[1], n.normal[2]};
    plane.origin = {n.origin[0], n.origin[1], n.origin[2]};
    plane.offset = dot(plane.normal, plane.origin);
    plane.scale = n.scale;
    ConvexCell negative, positive;
    it.cell.split(plane, negative, positive);
    stack.push_back({n.index, std::move(positive), it.depth + 1});
    stack.push_back({it.node + 1, std::move(negative), it.depth + 1});
  });
}

void walk_bvh2(const Bvh2& tree, const Visit& visit) {
  struct Item {
    std::uint32_t node;
    int depth;
  };
  depth_first(Item{0, 0}, [&](const Item& it, std::vector<Item>& stack) {
    const Bvh2Node& n = tree.nodes[it.node];
    if (n.is_leaf()) {
      visit(leaf_cell(n.box, n.count, it.depth));
      return;
    }
    if (!visit(box_cell(n.box, it.depth))) return;
    stack.push_back({n.first, it.depth + 1});
    stack.push_back({n.first + 1, it.depth + 1});
  });
}

/// The nodes of a wide BVH are references (WideRef): a leaf's names its packets in `leaves`
/// (wide.packets, or the BVH's IndexedLeaves::packets when its leaves are indexed).
template <int N, class Node, class Leaf>
void walk_wide_bvh(const WideBvh<N, Node>& wide, std::span<const Leaf> leaves, const Visit& visit) {
  depth_first(BoxItem{0, wide.root_box, 0}, [&](const BoxItem& it, std::vector<BoxItem>& stack) {
    if (WideRef::is_leaf(it.node)) {
      std::size_t prims = 0;
      const std::uint32_t first = WideRef::first(it.node);
      for (std::uint32_t p = first; p < first + WideRef::count(it.node); ++p) prims += leaves[p].size();
      visit(leaf_cell(it.box, prims, it.depth, WideRef::count(it.node)));  // one group per packet
      return;
    }
    const Node& node = wide.nodes[it.node];
    if (!visit(box_cell(it.box, it.depth))) return;
    for (std::uint32_t i = 0; i < node.used; ++i) stack.push_back({node.child[i], node.box(static_cast<int>(i)), it.depth + 1});
  });
}

void walk_bvh(const Bvh& bvh, const Visit& visit) {
  if (bvh.tree().nodes.empty()) throw InputError("structure cells: the BVH is empty");
  const bool quantized = bvh.config().nodes == BvhNodes::quantized;
  const auto walk = [&](const auto& wide) {
    if (bvh.config().leaves == BvhLeaves::indexed) return walk_wide_bvh(wide, std::span(bvh.indexed().packets), visit);
    walk_wide_bvh(wide, std::span(wide.packets), visit);
  };
  if (bvh.config().width == 4) return quantized ? walk(bvh.quantized4()) : walk(bvh.wide4());
  if (bvh.config().width == 8) return quantized ? walk(bvh.quantized8()) : walk(bvh.wide8());
  walk_bvh2(bvh.tree(), visit);
}

/// The slab test of the whole line in double: true when the closed box meets it.
bool line_meets_box(const Bounds3f& box, const Vec3d& o, const Vec3d& d) {
  double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double lo = box.lo[a], hi = box.hi[a];
    if (d[a] == 0.0) {
      if (o[a] < lo || o[a] > hi) return false;
      continue;
    }
    double tn = (lo - o[a]) / d[a], tf = (hi - o[a]) / d[a];
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

bool StructureCell::meets_line(const Vec3d& origin, const Vec3d& direction) const {
  return polytope ? polytope->meets_line(origin, direction) : line_meets_box(box, origin, direction);
}

bool has_structure_cells(const Aggregate& accel) {
  const std::string n = accel.name();
  return n == "kdtree" || n == "octree" || n == "bsp" || n == "bvh";
}

void walk_structure_cells(const Aggregate& accel, const Visit& visit) {
  const std::string n = accel.name();
  if (n == "kdtree") return walk_kdtree(dynamic_cast<const KdTree&>(accel), visit);
  if (n == "octree") return walk_octree(dynamic_cast<const Octree&>(accel), visit);
  if (n == "bsp") return walk_bsp(dynamic_cast<const BspTree&>(accel), visit);
  if (n == "bvh") return walk_bvh(dynamic_cast<const Bvh&>(accel), visit);
  throw InputError("structure cells: accelerator '" + n + "' is not a tree raylab can walk");
}

}  // namespace raylab
