#include "scene/scene.h"

#include <algorithm>
#include <cstdint>

#include "geometry/input_error.h"

namespace raylab {
namespace {

/// Closed and consistently oriented: every directed edge (a, b) occurs exactly once and its
/// reverse (b, a) occurs too, so each undirected edge is used by exactly two triangles that
/// traverse it in opposite directions. Decided on vertex indices.
bool closed_mesh(const TriangleMesh& mesh) {
  if (mesh.size() == 0) return false;
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.size());
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)];
      if (a == b) return false;
      edges.push_back(a << 32 | b);
    }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  for (const std::uint64_t e : edges) {
    const std::uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), reverse)) return false;
  }
  return true;
}

/// The statistics of a scene's flat geometry alone.
SceneInfo describe_flat(const Scene& scene) {
  SceneInfo info;
  info.triangles = info.unique_triangles = scene.mesh.size();
  info.spheres = scene.spheres.size();
  for (std::size_t t = 0; t < scene.mesh.size(); ++t)
    if (is_degenerate_exact(scene.mesh.vertex(t, 0), scene.mesh.vertex(t, 1), scene.mesh.vertex(t, 2))) ++info.degenerate_triangles;
  info.closed = scene.mesh.size() > 0 ? closed_mesh(scene.mesh) : !scene.spheres.empty();
  info.meshes = scene.primitive_count() > 0 ? scene.flat_mesh_count : 0;
  return info;
}

std::string quoted_spec(const Scene& scene) { return "scene '" + scene.spec + "'"; }

}  // namespace

double Scene::total_primitive_count() const {
  double n = static_cast<double>(primitive_count());
  for (const auto& inst : instances) n += bases[inst.base]->total_primitive_count();
  return n;
}

Bounds3f Scene::bounds() const {
  Bounds3f b = mesh.bounds();
  for (const auto& s : spheres) b.extend(s.bounds());
  std::vector<Bounds3f> base_bounds;
  base_bounds.reserve(bases.size());
  for (const auto& base : bases) base_bounds.push_back(base->bounds());
  for (const auto& inst : instances) b.extend(inst.transform.apply(base_bounds[inst.base]));
  return b;
}

std::shared_ptr<const Scene> Scene::flat_part() const {
  auto flat = std::make_shared<Scene>();
  flat->spec = spec + " (flat geometry)";
  flat->mesh = mesh;
  flat->spheres = spheres;
  flat->flat_mesh_count = flat_mesh_count;
  return flat;
}

void require_valid_instances(const Scene& scene) {
  // The message is built on failure only: scenes hold up to 2^24 instances.
  auto fail = [&](const char* what, std::size_t i, const std::string& fault) {
    throw InputError(quoted_spec(scene) + ": " + what + " " + std::to_string(i) + " " + fault);
  };
  for (std::size_t b = 0; b < scene.bases.size(); ++b) {
    if (!scene.bases[b]) fail("base", b, "is missing");
    if (scene.bases[b]->instanced()) fail("base", b, "is itself instanced (one instance level)");
    if (scene.bases[b]->primitive_count() == 0) fail("base", b, "is empty");
  }
  for (std::size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& inst = scene.instances[i];
    if (inst.base >= scene.bases.size())
      fail("instance", i, "names base " + std::to_string(inst.base) + " of " + std::to_string(scene.bases.size()));
    if (!is_finite(inst.transform)) fail("instance", i, "has a non-finite transform");
    if (!is_invertible(inst.transform)) fail("instance", i, "has a singular transform");
  }
}

SceneInfo describe(const Scene& scene) {
  SceneInfo info = describe_flat(scene);
  if (scene.primitive_count() == 0) info.closed = true;  // decided by the bases below
  std::vector<SceneInfo> base_info;
  base_info.reserve(scene.bases.size());
  for (const auto& base : scene.bases) {
    base_info.push_back(describe_flat(*base));
    info.unique_triangles += base_info.back().triangles;
    info.closed = info.closed && base_info.back().closed;
  }
  for (const auto& inst : scene.instances) {
    const SceneInfo& b = base_info[inst.base];
    info.triangles += b.triangles;
    info.spheres += b.spheres;
    info.degenerate_triangles += b.degenerate_triangles;
  }
  info.meshes += scene.bases.size();
  info.instances = scene.instances.size();
  info.lines = scene.left_out_lines;
  info.points = scene.left_out_points;
  if (scene.primitive_count() == 0 && scene.bases.empty()) info.closed = false;
  info.primitives = scene.total_primitive_count();
  info.bounds = scene.bounds();
  return info;
}

}  // namespace raylab
