#pragma once
/// Front-to-back BSP traversal by the side of the plane the ray origin lies on (the kd-tree's
/// three cases, kdtree_traversal.h, with arbitrary planes), in double precision with error
/// bounds: the plane's t* = -(n·o - offset)/(n·d) is computed once and widened by a bound on the
/// rounding of both dot products and on the rounding of the plane itself; a ray that may lie in a
/// plane (n·d within its error bound of 0 and the origin within its error bound of the plane)
/// visits both children over its whole interval, and a ray exactly parallel to a plane visits the
/// side of its origin only when the origin is surely off the plane. Axis-aligned planes are taken
/// in float as the kd-tree's splits. A leaf's triangles are tested 8 at a time when the tree's
/// leaves are packed (bsp_pack_leaves), bit-identically to the scalar kernel (kd_test_packed_leaf).
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "accel/bsp/bsp_node.h"
#include "accel/bsp/bsp_plane.h"
#include "accel/common/packed_tree_leaves.h"
#include "accel/kdtree/kdtree_traversal.h"

namespace raylab {

struct BspTreeView {
  const BspNode* nodes;
  const std::uint32_t* prims;
  const Scene* scene;
  Bounds3f bounds;
  /// The leaves packed 4-wide (bsp_pack_leaves), or null: a leaf's `index` then is the offset of
  /// its primitive ids in `prims`.
  const TrianglePacket* packets = nullptr;
};

/// The leaves of `nodes` packed 4-wide (pack_tree_leaves): `packed_nodes` is a copy of `nodes`
/// whose leaves index `packets`; both stay empty when the scene holds a sphere.
inline void bsp_pack_leaves(const Scene& scene, const std::vector<BspNode>& nodes,
                            const std::vector<std::uint32_t>& prims, std::vector<BspNode>& packed_nodes,
                            std::vector<TrianglePacket>& packets) {
  pack_tree_leaves(
      scene, nodes, prims,
      [](BspNode& n) -> std::pair<std::uint32_t*, std::uint32_t> {
        if (!n.is_leaf()) return {nullptr, 0u};
        return {&n.index, n.count};
      },
      packed_nodes, packets);
}

template <class Kernel, bool kAnyHit, class Counters>
bool bsp_traverse(const BspTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  TreeRay<Kernel> r;
  if (!r.enter(ray, tree.bounds)) return false;
  float tmin = r.tmin, tmax = r.tmax;
  const Vec3f& inv = r.inv;
  const Vec3d o(ray.org), d(ray.dir);
  struct Entry {
    std::uint32_t node;
    float tmin, tmax;
  };
  Entry stack[64];
  int top = 0;
  bool found = false;
  std::uint32_t index = 0;
  for (;;) {
    const BspNode* node = &tree.nodes[index];
    while (!node->is_leaf()) {
      counters.node();
      const std::uint32_t negative = index + 1, positive = node->index;
      if (const int a = node->axis(); a >= 0) {
        // An axis-aligned plane, exactly as a kd-tree split (kd_cross): t* in float, widened by
        // its rounding error; NaN (the ray lies in the plane) visits both sides over the whole
        // interval; d[a] = ±0 gives inv = +inf and t* = ±inf, which keeps the origin's side.
        const float t = (static_cast<float>(node->origin[a]) - ray.org[a]) * inv[a];
        const auto [t_lo, t_hi] = widened_plane_t(t);
        const std::uint32_t near = inv[a] > 0.0f ? negative : positive, far = inv[a] > 0.0f ? positive : negative;
        if (t_lo > std::min(tmax, Kernel::closest(r.ctx))) {
          index = near;
        } else if (t_hi < tmin) {
          index = far;
        } else {
          stack[top++] = {far, t_lo > tmin ? t_lo : tmin, tmax};
          index = near;
          tmax = t_hi < tmax ? t_hi : tmax;
        }
        node = &tree.nodes[index];
        continue;
      }
      const double* n = node->normal;
      const double qx = o.x - node->origin[0], qy = o.y - node->origin[1], qz = o.z - node->origin[2];
      const double s = n[0] * qx + n[1] * qy + n[2] * qz;
      const double nd = n[0] * d.x + n[1] * d.y + n[2] * d.z;
      // |normal_i| <= scale and its rounding is a few ulps of scale, so these bound the error of
      // s and nd against the exact plane through the triangle's vertices.
      const double err_s = kBspRelError * node->scale * (std::abs(qx) + std::abs(qy) + std::abs(qz));
      const double err_nd = (n[0] == 0.0 || d.x == 0.0) && (n[1] == 0.0 || d.y == 0.0) && (n[2] == 0.0 || d.z == 0.0)
                                ? 0.0
                                : kBspRelError * node->scale * (std::abs(d.x) + std::abs(d.y) + std::abs(d.z));
      if (std::abs(nd) <= err_nd) {
        if (err_nd == 0.0 && s > err_s) {
          index = positive;
        } else if (err_nd == 0.0 && s < -err_s) {
          index = negative;
        } else {  // in the plane, or too close to parallel to tell: both sides, whole interval
          stack[top++] = {positive, tmin, tmax};
          index = negative;
        }
      } else {
        const double t = -s / nd;
        const double slack = (err_s + std::abs(t) * err_nd) / std::abs(nd) + 1e-6 * std::abs(t);
        const float t_lo = static_cast<float>(t - slack), t_hi = static_cast<float>(t + slack);
        const std::uint32_t near = nd > 0.0 ? negative : positive, far = nd > 0.0 ? positive : negative;
        if (t_lo > std::min(tmax, Kernel::closest(r.ctx))) {
          index = near;
        } else if (t_hi < tmin) {
          index = far;
        } else {
          stack[top++] = {far, std::max(t_lo, tmin), tmax};
          index = near;
          tmax = std::min(t_hi, tmax);
        }
      }
      node = &tree.nodes[index];
    }
    bool h;
    if (tree.packets != nullptr) {
      h = kd_test_packed_leaf<kAnyHit>(tree.packets + node->index, node->count, r, hit, counters);
    } else {
      counters.leaf();
      h = kd_test_primitives<kAnyHit>(*tree.scene, tree.prims + node->index, node->count, r, hit, counters);
    }
    if (h) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
    do {
      if (top == 0) return found;
      --top;
    } while (Kernel::closest(r.ctx) < stack[top].tmin);
    index = stack[top].node;
    tmin = stack[top].tmin;
    tmax = stack[top].tmax;
  }
}

}  // namespace raylab
