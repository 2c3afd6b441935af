#pragma once
/// The CGAL demo meshes (`cgal:NAME` scenes), from libcgal-demo's data archive.
///
/// On first use, `data/meshes/` of the archive (RAYLAB_CGAL_DATA_ARCHIVE, default
/// /usr/share/doc/libcgal-dev/data.tar.gz) is unpacked with `tar` into the mesh cache directory
/// (environment variable RAYLAB_MESH_CACHE, else the build-time RAYLAB_MESH_CACHE) as
/// `<cache>/cgal-meshes/`. Unpacking goes to a private temporary directory that is then renamed
/// into place, so concurrent processes never see a half-written cache.
#include <string>
#include <vector>

namespace raylab {

/// The directory holding the unpacked meshes; unpacks on first call. Throws InputError when
/// the archive is missing or cannot be unpacked.
std::string cgal_mesh_dir();

/// Stems of the meshes (files ending in .off, .obj, .ply or .stl), sorted, without duplicates.
std::vector<std::string> cgal_mesh_names();

/// The file of mesh `name` (a stem; when several formats share it, .off, then .ply, .stl, .obj;
/// a name with its extension picks that file). Throws InputError listing valid names when unknown.
std::string cgal_mesh_path(const std::string& name);

/// The well-known meshes used as reference scenes, in this order, keeping those present:
/// bunny00, armadillo, refined_elephant, diplodocus, fandisk_large, bear, elephant, camel, cow,
/// man, lion, knot1.
std::vector<std::string> cgal_reference_meshes();

}  // namespace raylab
