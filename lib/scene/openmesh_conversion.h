#pragma once
/// Conversion of raylab meshes to OpenMesh, shared by mesh output (mesh_io.cpp) and the
/// OpenMesh-based scenes (procedural.cpp: subdivision, decimation). Internal: this header
/// includes OpenMesh and is not installed.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "geometry/triangle_mesh.h"

namespace raylab {

using OpenMeshTriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

/// OpenMesh copy of a triangle mesh. A triangle OpenMesh cannot attach (a non-manifold edge)
/// gets its own copies of its corners, as OpenMesh's importer does; triangles naming a vertex
/// twice are left out.
OpenMeshTriMesh to_openmesh(const TriangleMesh& mesh);

}  // namespace raylab
