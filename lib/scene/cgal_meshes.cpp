#include "scene/cgal_meshes.h"

#include <stdlib.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "geometry/input_error.h"

#ifndef RAYLAB_CGAL_DATA_ARCHIVE
#define RAYLAB_CGAL_DATA_ARCHIVE "/usr/share/doc/libcgal-dev/data.tar.gz"
#endif
#ifndef RAYLAB_MESH_CACHE
#define RAYLAB_MESH_CACHE "/tmp/raylab-mesh-cache"
#endif

namespace raylab {
namespace {

namespace fs = std::filesystem;

const char* const kExtensions[] = {".off", ".ply", ".stl", ".obj"};  // preference order

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

fs::path cache_root() {
  const char* env = std::getenv("RAYLAB_MESH_CACHE");
  return fs::path(env && *env ? env : RAYLAB_MESH_CACHE);
}

/// Unpacks data/meshes into `target` via a private temporary directory and one rename.
void unpack(const fs::path& root, const fs::path& target) {
  const std::string archive = RAYLAB_CGAL_DATA_ARCHIVE;
  std::error_code ec;
  if (!fs::is_regular_file(archive, ec))
    throw InputError("cgal: the CGAL demo data archive " + archive + " is missing (install libcgal-demo)");
  fs::create_directories(root, ec);
  if (ec) throw InputError("cgal: cannot create the mesh cache directory " + root.string() + ": " + ec.message());
  std::string tmpl = (root / ".cgal-meshes-tmp-XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw InputError("cgal: cannot create a temporary directory in " + root.string());
  const fs::path tmp = tmpl;
  const std::string cmd = "tar -xzf " + shell_quote(archive) + " -C " + shell_quote(tmp.string()) + " data/meshes >/dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 || !fs::is_directory(tmp / "data" / "meshes", ec)) {
    fs::remove_all(tmp, ec);
    throw InputError("cgal: unpacking data/meshes from " + archive + " into " + root.string() + " failed");
  }
  fs::rename(tmp / "data" / "meshes", target, ec);  // fails harmlessly when another process won
  const bool ok = fs::is_directory(target);
  fs::remove_all(tmp, ec);
  if (!ok) throw InputError("cgal: cannot move the unpacked meshes to " + target.string());
}

}  // namespace

std::string cgal_mesh_dir() {
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  const fs::path root = cache_root();
  const fs::path target = root / "cgal-meshes";
  std::error_code ec;
  if (!fs::is_directory(target, ec)) unpack(root, target);
  return target.string();
}

std::vector<std::string> cgal_mesh_names() {
  const fs::path dir = cgal_mesh_dir();
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string ext = lower(entry.path().extension().string());
    if (std::find(std::begin(kExtensions), std::end(kExtensions), ext) != std::end(kExtensions))
      names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

std::string cgal_mesh_path(const std::string& name) {
  const fs::path dir = cgal_mesh_dir();
  std::error_code ec;
  if (!name.empty() && name.find('/') == std::string::npos && name != "." && name != "..") {
    const fs::path exact = dir / name;
    const std::string ext = lower(exact.extension().string());
    if (std::find(std::begin(kExtensions), std::end(kExtensions), ext) != std::end(kExtensions) && fs::is_regular_file(exact, ec))
      return exact.string();
    for (const char* e : kExtensions) {
      const fs::path p = dir / (name + e);
      if (fs::is_regular_file(p, ec)) return p.string();
    }
  }
  const auto names = cgal_mesh_names();
  std::vector<std::string> similar;
  for (const auto& n : names)
    if (!name.empty() && (n.find(name.substr(0, 3)) == 0)) similar.push_back(n);
  for (const auto& n : cgal_reference_meshes())
    if (similar.size() < 8 && std::find(similar.begin(), similar.end(), n) == similar.end()) similar.push_back(n);
  std::string list;
  for (std::size_t i = 0; i < similar.size() && i < 8; ++i) list += (i ? ", " : "") + similar[i];
  throw InputError("cgal:" + name + ": unknown CGAL mesh (" + std::to_string(names.size()) + " known, e.g. " + list +
                   "; see the files in " + dir.string() + ")");
}

std::vector<std::string> cgal_reference_meshes() {
  static const char* const kReference[] = {"bunny00", "armadillo", "refined_elephant", "diplodocus", "fandisk_large", "bear",
                                           "elephant", "camel", "cow", "man", "lion", "knot1"};
  const fs::path dir = cgal_mesh_dir();
  std::vector<std::string> out;
  std::error_code ec;
  for (const char* n : kReference)
    for (const char* e : kExtensions)
      if (fs::is_regular_file(dir / (std::string(n) + e), ec)) {
        out.push_back(n);
        break;
      }
  return out;
}

}  // namespace raylab
