#pragma once
/// A scene: triangles and spheres, or instances of a base scene under affine transforms.
///
/// Primitive ids: triangles are 0 .. T-1 and spheres T .. T+S-1, where T = mesh.size() and
/// S = spheres.size(). In an instanced scene a hit names the base scene's primitive id and the
/// instance index (Hit::instance).
#include <memory>
#include <string>
#include <vector>

#include "geometry/sphere.h"
#include "geometry/transform.h"
#include "geometry/triangle_mesh.h"

namespace raylab {

struct Scene {
  std::string spec;  ///< the spec string the scene was made from (for reports)
  TriangleMesh mesh;
  std::vector<Sphere> spheres;

  /// Instancing: when `base` is set, the scene is one copy of *base per transform (object to
  /// world) and `mesh`/`spheres` are empty.
  std::shared_ptr<const Scene> base;
  std::vector<AffineTransform> instances;

  bool instanced() const { return base != nullptr; }
  std::size_t triangle_count() const { return mesh.size(); }
  /// Primitives of this level (for an instanced scene, of the base scene).
  std::size_t primitive_count() const {
    return instanced() ? base->primitive_count() : mesh.size() + spheres.size();
  }
  /// Triangles plus spheres over all instances (what a flat copy would hold).
  double total_primitive_count() const {
    return instanced() ? static_cast<double>(instances.size()) * base->total_primitive_count()
                       : static_cast<double>(mesh.size() + spheres.size());
  }
  bool is_sphere(unsigned prim) const { return prim >= mesh.size(); }
  const Sphere& sphere(unsigned prim) const { return spheres[prim - mesh.size()]; }
  Bounds3f primitive_bounds(unsigned prim) const {
    return is_sphere(prim) ? sphere(prim).bounds() : mesh.triangle_bounds(prim);
  }
  Bounds3f bounds() const {
    Bounds3f b;
    if (instanced()) {
      const Bounds3f inner = base->bounds();
      for (const auto& xf : instances) b.extend(xf.apply(inner));
      return b;
    }
    b = mesh.bounds();
    for (const auto& s : spheres) b.extend(s.bounds());
    return b;
  }
};

/// Statistics `raylab info` prints.
struct SceneInfo {
  double primitives = 0;
  std::size_t triangles = 0, spheres = 0, instances = 0;
  std::size_t degenerate_triangles = 0;  ///< zero-area, decided exactly
  bool closed = false;                   ///< every edge shared by exactly two triangles, consistently oriented
  Bounds3f bounds;
};

SceneInfo describe(const Scene& scene);

}  // namespace raylab
