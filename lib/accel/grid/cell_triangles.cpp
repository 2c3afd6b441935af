#include "accel/grid/cell_triangles.h"

#include "geometry/ray.h"

namespace raylab {

CellTriangles copy_cell_triangles(const Scene& scene, BuildArray<std::uint32_t> prim_of) {
  CellTriangles out;
  out.prim_of = std::move(prim_of);
  out.tris.reserve(out.prim_of.size());
  const auto& v = scene.mesh.vertices;
  for (const std::uint32_t p : out.prim_of) {
    const auto& t = scene.mesh.triangles[p];
    out.tris.push_back({v[t[0]], v[t[1]], v[t[2]]});
  }
  return out;
}

CellTriangles renumber_cell_triangles(const Scene& scene, std::uint32_t* refs, std::size_t n) {
  if (!scene.spheres.empty()) return {};
  std::vector<std::uint32_t> local_of(scene.primitive_count(), kInvalidId);
  BuildArray<std::uint32_t> prim_of;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t& r = refs[i];
    std::uint32_t& local = local_of[r];
    if (local == kInvalidId) {
      local = static_cast<std::uint32_t>(prim_of.size());
      prim_of.push_back(r);
    }
    r = local;
  }
  return copy_cell_triangles(scene, std::move(prim_of));
}

}  // namespace raylab
