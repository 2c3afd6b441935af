#pragma once
/// Triangle meshes from and to files: OFF, OBJ, PLY (ASCII and binary) and STL (ASCII and binary),
/// chosen by the file extension (case-insensitive), read and written through OpenMesh's IO.
///
/// Every file is validated by a strict scanner of our own before OpenMesh sees it (OpenMesh's
/// readers trust header counts, print to stderr and drop faces they cannot use), so bad input
/// fails fast, with bounded memory, as one InputError line of the form `FILE:LINE: fault` (text
/// formats) or `FILE: fault` (binary formats).
#include <cstddef>
#include <string>

#include "geometry/triangle_mesh.h"

namespace raylab {

/// What `load_mesh` found in a file.
struct MeshLoadReport {
  std::size_t faces_read = 0;             ///< faces (polygons or triangles) the file declares
  std::size_t polygons_triangulated = 0;  ///< faces with more than three corners, fanned into triangles
  std::size_t zero_area_triangles = 0;    ///< triangles of the result with zero area, decided exactly
  std::size_t faces_skipped = 0;          ///< faces OpenMesh rejects: a corner repeated, or STL corners merged
};

/// Loads the triangles of a mesh file. Polygons are triangulated as fans (v0, vi, vi+1).
/// Throws InputError naming the file (and line or element) on: an unknown extension, an
/// unreadable file, malformed syntax, header counts the file cannot hold, indices out of range,
/// non-finite coordinates (also after rounding to float), and a result without triangles.
TriangleMesh load_mesh(const std::string& path, MeshLoadReport* report = nullptr);

/// Writes a mesh through OpenMesh, format by extension; `binary` selects binary PLY/STL.
/// Throws InputError when the format is unknown or the file cannot be written.
void save_mesh(const TriangleMesh& mesh, const std::string& path, bool binary = false);

/// True when `path` ends in .off, .obj, .ply or .stl (any case).
bool has_mesh_extension(const std::string& path);

}  // namespace raylab
