#pragma once
/// Building a BSP tree with arbitrary planes: at each node the candidates are supporting planes
/// of the node's triangles (auto-partition; Fuchs, Kedem and Naylor 1980; de Berg et al.,
/// "Computational Geometry" ch. 12) and axis-aligned planes, ranked by the kd-tree's SAH on the
/// surface areas of the convex cells they cut (bsp_cell.h); the primitives are placed by exact
/// classification (bsp_plane.h), straddlers referenced on both sides.
#include <cstdint>
#include <vector>

#include "accel/bsp/bsp_config.h"
#include "accel/bsp/bsp_node.h"
#include "scene/scene.h"

namespace raylab {

struct BspTreeData {
  std::vector<BspNode> nodes;        ///< depth first; node 0 is the root
  std::vector<std::uint32_t> prims;  ///< leaf primitive lists, each sorted by id
  Bounds3f bounds;                   ///< the root cell: the scene's bounds
  double sah_cost = 0.0;
  std::size_t leaves = 0;
  std::size_t triangle_planes = 0;  ///< interior nodes split by a triangle's supporting plane
  int depth = 0;
};

/// Builds the tree. `scene` must not be instanced. Deterministic.
BspTreeData build_bsp(const Scene& scene, const BspConfig& config);

}  // namespace raylab
