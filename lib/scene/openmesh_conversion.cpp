#include "scene/openmesh_conversion.h"

#include <vector>

namespace raylab {

OpenMeshTriMesh to_openmesh(const TriangleMesh& mesh) {
  OpenMeshTriMesh m;
  m.reserve(mesh.vertices.size(), mesh.size() * 3 / 2, mesh.size());
  std::vector<OpenMeshTriMesh::VertexHandle> vh;
  vh.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) vh.push_back(m.add_vertex(OpenMeshTriMesh::Point(v.x, v.y, v.z)));
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    if (!m.add_face(vh[t[0]], vh[t[1]], vh[t[2]]).is_valid()) {
      const OpenMeshTriMesh::Point p0 = m.point(vh[t[0]]), p1 = m.point(vh[t[1]]), p2 = m.point(vh[t[2]]);  // copies: add_vertex may reallocate
      m.add_face(m.add_vertex(p0), m.add_vertex(p1), m.add_vertex(p2));
    }
  }
  return m;
}

}  // namespace raylab
