#pragma once
/// Indexed triangle meshes stored as 32-bit floats and 32-bit indices, the layout every
/// accelerator (and Embree's shared buffers) reads.
#include <array>
#include <cstdint>
#include <vector>

#include "geometry/bounds.h"

namespace raylab {

struct TriangleMesh {
  std::vector<Vec3f> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;

  std::size_t size() const { return triangles.size(); }
  const Vec3f& vertex(std::size_t tri, int corner) const { return vertices[triangles[tri][corner]]; }
  Bounds3f triangle_bounds(std::size_t tri) const {
    Bounds3f b(vertex(tri, 0));
    b.extend(vertex(tri, 1));
    b.extend(vertex(tri, 2));
    return b;
  }
  Bounds3f bounds() const {
    Bounds3f b;
    for (const auto& v : vertices) b.extend(v);
    return b;
  }
  /// Appends `other`, offsetting its indices.
  void append(const TriangleMesh& other) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    for (auto t : other.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
};

/// True when the triangle has zero area in exact arithmetic (repeated or collinear vertices).
/// Decided exactly (see exact_predicates.h); such triangles are never hit by any kernel.
bool is_degenerate_exact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);

}  // namespace raylab
