#pragma once
/// A scene: world-space triangles and spheres (the flat geometry), beside any number of base
/// scenes placed under affine transforms (instances; pbrt-v3 §4.1.2's TransformedPrimitive).
///
/// Naming a hit (Hit::prim, Hit::instance):
/// - instance = kInvalidId: a primitive of the flat geometry. Primitive ids are triangles
///   0 .. T-1 then spheres T .. T+S-1, where T = mesh.size() and S = spheres.size().
/// - instance = i < instances.size(): the instance instances[i], which places the base
///   bases[instances[i].base] by instances[i].transform; prim is that base's own primitive id
///   (its triangles first, then its spheres).
/// There is one instance level: a base holds flat geometry only.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "geometry/sphere.h"
#include "geometry/transform.h"
#include "geometry/triangle_mesh.h"

namespace raylab {

struct Scene;

/// One placement of a base scene: object-to-world transform and the index into Scene::bases.
struct SceneInstance {
  AffineTransform transform;
  std::uint32_t base = 0;
};

struct Scene {
  std::string spec;  ///< the spec string the scene was made from (for reports)
  TriangleMesh mesh;  ///< flat geometry, in world space
  std::vector<Sphere> spheres;
  /// How many meshes of the source were merged into `mesh` and `spheres` (`raylab info`'s
  /// meshes: counts them when the flat geometry is not empty).
  std::size_t flat_mesh_count = 1;
  /// Line segments and points of the source file, left out of the scene (raylab traces
  /// triangles and spheres only; scene_import.h, mesh_io.h): counted, never stored.
  std::size_t left_out_lines = 0, left_out_points = 0;

  /// Base scenes (flat geometry only, non-empty), each placed by one or more instances.
  std::vector<std::shared_ptr<const Scene>> bases;
  std::vector<SceneInstance> instances;

  // The members below assume a valid instancing (require_valid_instances).
  bool instanced() const { return !instances.empty(); }
  /// The base an instance places.
  const Scene& base_of(std::size_t instance) const { return *bases[instances[instance].base]; }
  /// Triangles of the flat geometry (not of the bases).
  std::size_t triangle_count() const { return mesh.size(); }
  /// Primitives of the flat geometry (not of the bases): the id range of hits without instance.
  std::size_t primitive_count() const { return mesh.size() + spheres.size(); }
  /// Triangles plus spheres over the flat geometry and all instances (what a flat copy holds).
  double total_primitive_count() const;
  bool is_sphere(unsigned prim) const { return prim >= mesh.size(); }
  const Sphere& sphere(unsigned prim) const { return spheres[prim - mesh.size()]; }
  Bounds3f primitive_bounds(unsigned prim) const {
    return is_sphere(prim) ? sphere(prim).bounds() : mesh.triangle_bounds(prim);
  }
  /// Bounds of the flat geometry and of every instance (the transformed box of its base).
  Bounds3f bounds() const;
  /// The flat geometry alone, as a scene without instances (a copy).
  std::shared_ptr<const Scene> flat_part() const;
};

/// Throws InputError (naming the scene's spec) unless every instance names an existing base,
/// every base is non-null, non-empty and holds no instances itself, and every instance transform
/// is_invertible (geometry/transform.h).
void require_valid_instances(const Scene& scene);

/// Statistics `raylab info` prints.
struct SceneInfo {
  double primitives = 0;                 ///< triangles + spheres over all instances
  std::size_t meshes = 0;                ///< bases plus the meshes merged into the flat geometry
  std::size_t triangles = 0;             ///< over all instances (what a flat copy would hold)
  std::size_t unique_triangles = 0;      ///< stored: flat geometry plus each base once
  std::size_t spheres = 0, instances = 0;
  std::size_t degenerate_triangles = 0;  ///< zero-area, decided exactly, over all instances
  std::size_t lines = 0, points = 0;     ///< of the source file, left out of the triangles (Scene::left_out_lines, left_out_points)
  bool closed = false;  ///< every part (flat geometry, each base): every edge shared by exactly two triangles, consistently oriented
  Bounds3f bounds;
};

SceneInfo describe(const Scene& scene);

}  // namespace raylab
