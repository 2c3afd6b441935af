#pragma once
/// Triangle meshes from and to files: OFF, OBJ, PLY (ASCII and binary) and STL (ASCII and binary),
/// chosen by the file extension (case-insensitive) or, for a file without one, by its content
/// (file_format.h), read and written through OpenMesh's IO.
///
/// Real-world quirks that are read, not rejected: an ASCII STL of several `solid ... endsolid`
/// blocks (some of them empty) is one mesh; a PLY header line that is no PLY keyword (an
/// exporter's "Created by ..." line) is skipped with a warning (input_warning.h). UTF-16 text is
/// rejected with a message that says so.
///
/// Every file is validated by a strict scanner of our own before OpenMesh sees it (OpenMesh's
/// readers trust header counts, print to stderr and drop faces they cannot use), so bad input
/// fails fast, with bounded memory, as one InputError line of the form `FILE:LINE: fault` (text
/// formats) or `FILE: fault` (binary formats).
#include <cstddef>
#include <string>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace raylab {

/// What `load_mesh` found in a file.
struct MeshLoadReport {
  std::size_t faces_read = 0;             ///< faces (polygons or triangles) the file declares
  std::size_t polygons_triangulated = 0;  ///< faces with more than three corners, fanned into triangles
  std::size_t zero_area_triangles = 0;    ///< triangles of the result with zero area, decided exactly
  std::size_t faces_skipped = 0;          ///< faces OpenMesh rejects: a corner repeated, or STL corners merged
  std::size_t lines = 0, points = 0;      ///< OBJ `l` segments and `p` points, left out (raylab traces triangles)
  std::vector<std::string> warnings;      ///< what was read anyway (also printed by warn_input), e.g. unknown PLY header lines
};

/// Loads the triangles of a mesh file. Polygons are triangulated as fans (v0, vi, vi+1).
/// Throws InputError naming the file (and line or element) on: an unknown extension or (no
/// extension) unrecognised content, a scene format Assimp reads (scene_import.h), an
/// unreadable file, malformed syntax, header counts the file cannot hold, indices out of range,
/// non-finite coordinates (also after rounding to float), and a result without triangles.
TriangleMesh load_mesh(const std::string& path, MeshLoadReport* report = nullptr);

/// Writes a mesh through OpenMesh, format by extension; `binary` selects binary PLY/STL.
/// Throws InputError when the format is unknown or the file cannot be written.
void save_mesh(const TriangleMesh& mesh, const std::string& path, bool binary = false);

/// True when `path` ends in .off, .obj, .ply or .stl (any case).
bool has_mesh_extension(const std::string& path);

}  // namespace raylab
