#pragma once
/// The double-precision half of the ill-conditioning test of contact_classes.h, items (b) and
/// (c): given the triangles and spheres near a ray (the oracle's tube query), does the ray pass
/// within a few ulps of a contour of the surface, or start within a few ulps of it?
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

/// Welded vertices (equal positions) and the triangles around each welded vertex and edge, so
/// that a contour can be told from an edge shared by two faces.
class MeshAdjacency {
 public:
  explicit MeshAdjacency(const TriangleMesh& mesh);

  std::uint32_t weld(std::uint32_t vertex) const { return weld_[vertex]; }
  /// The triangles with welded vertex `w` (a welded id).
  const std::vector<std::uint32_t>& around_vertex(std::uint32_t w) const;
  /// The triangles with the welded edge {a, b}.
  const std::vector<std::uint32_t>& around_edge(std::uint32_t a, std::uint32_t b) const;

 private:
  std::vector<std::uint32_t> weld_;
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> vertex_tris_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> edge_tris_;
  std::vector<std::uint32_t> none_;
};

/// Δ(t) of contact_classes.h: 32u·(|o|∞ + |t|·|d|∞).
double ulp_displacement(const Ray& ray, double t);

/// Items (b) and (c) of contact_classes.h for the segment [tmin, t_end] of `ray`: `triangles`
/// and `spheres` (scene primitive ids) are the primitives near it (a superset is fine).
bool near_contour_or_surface(const Scene& scene, const MeshAdjacency& adjacency, const Ray& ray, double t_end,
                             const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& spheres);

}  // namespace raylab
