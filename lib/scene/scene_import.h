#pragma once
/// Scenes from glTF 2.0 (.gltf, .glb), FBX, COLLADA (.dae) and 3DS files, read by Assimp
/// (Debian's libassimp-dev; its headers stay inside scene_import.cpp). The node tree becomes
/// the scene (scene.h), as pbrt-v3 §4.1.2 places shared geometry:
/// - the meshes one node lists form one mesh of the scene (for glTF: the primitives of one glTF
///   mesh, which Assimp splits into one aiMesh each);
/// - a mesh that several nodes list is one base, placed by one instance under each node's world
///   transform (the product of the node transforms from the root down, in double), instances in
///   depth-first node order, bases in order of first use;
/// - a mesh listed by one node only is transformed into world space (in double, rounded to
///   float) and joins the flat geometry.
/// Polygons are fanned into triangles (v0, vi, vi+1). Only faces of three or more indices are
/// triangles: Assimp gives a glTF LINES / LINE_STRIP / LINE_LOOP primitive's segments as faces of
/// two indices and a POINTS primitive's points as faces of one (with or without
/// aiProcess_Triangulate, which keeps them; aiProcess_SortByPType would only move them into meshes
/// of their own). Those are left out of the scene and counted apart (SceneImportReport,
/// Scene::left_out_lines / left_out_points), once per mesh the node tree uses, like unique
/// triangles. Degenerate triangles stay triangles: raylab runs no aiProcess_FindDegenerates, which
/// would turn a triangle with a repeated corner into a line (as the `assimp info` tool reports it).
///
/// Before Assimp sees a file: a size cap (kMaxSceneFileBytes, for every file it opens, buffers
/// included), the format's magic (binary glTF header, FBX header, COLLADA root element, 3DS main
/// chunk), and the checks of gltf_check.h, collada_check.h and fbx_check.h (nesting and counts
/// Assimp trusts). After: every
/// count, index, vertex and node transform Assimp returns is validated (a node tree without
/// cycles, at most kMaxImportNodeDepth deep; affine, finite, invertible transforms; finite
/// vertices, also after transforming and rounding to float; indices in range), and counts are
/// capped before anything is allocated (kMaxImportTriangles stored triangles, 2^24 instances).
/// Assimp runs in a child process (child_process.h): a crash or abort inside Assimp on a file that
/// passed these checks ends the child, and raylab reports it (`FILE: Assimp crashed (signal 11,
/// Segmentation fault)`), and one that runs longer than 10 s plus 1 s per MiB of the file is
/// stopped. Any fault, Assimp's own errors, crashes and time-outs included, throws InputError
/// naming the file.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/scene.h"

namespace raylab {

inline constexpr std::uint64_t kMaxSceneFileBytes = std::uint64_t{1} << 30;
inline constexpr std::size_t kMaxImportNodeDepth = 256;
inline constexpr std::size_t kMaxImportNodes = std::size_t{1} << 20;
inline constexpr std::uint64_t kMaxImportTriangles = std::uint64_t{1} << 27;
inline constexpr std::uint64_t kMaxImportInstances = std::uint64_t{1} << 24;

/// What import_scene found.
struct SceneImportReport {
  std::size_t nodes = 0;             ///< nodes of the tree
  std::size_t meshes = 0;            ///< distinct node mesh lists with triangles (scene meshes)
  std::size_t flattened_meshes = 0;  ///< of those, used by one node and merged into the flat geometry
  std::size_t instances = 0;         ///< placements of the others
  std::size_t lines = 0;             ///< line segments left out (faces of two indices)
  std::size_t points = 0;            ///< points left out (faces of one index)
};

/// Reads the scene file at `path` (format by extension, or by content without one:
/// file_format.h) through Assimp. Throws InputError for a format Assimp does not read here
/// (OFF/OBJ/PLY/STL are mesh_io.h's), any fault listed above, and a scene without triangles
/// (`FILE: no triangles (N lines, M points left out)`). Left-out lines and points are also
/// printed as one warning (input_warning.h).
Scene import_scene(const std::string& path, SceneImportReport* report = nullptr);

}  // namespace raylab
