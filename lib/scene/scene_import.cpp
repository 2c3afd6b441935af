#include "scene/scene_import.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "geometry/input_error.h"
#include "geometry/input_warning.h"
#include "scene/child_process.h"
#include "scene/collada_check.h"
#include "scene/fbx_check.h"
#include "scene/file_format.h"
#include "scene/gltf_check.h"
#include "scene/little_endian.h"

namespace raylab {
namespace {

constexpr std::size_t kHeadBytes = 4096;
constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InputError(path + ": " + what); }

std::string read_bytes(const std::string& path, std::uint64_t count) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open for reading");
  std::string data(count, '\0');
  in.read(data.data(), static_cast<std::streamsize>(count));
  if (static_cast<std::uint64_t>(in.gcount()) != count) fail(path, "read error");
  return data;
}

/// What raylab checks before Assimp parses the file (scene_import.h).
void check_before_assimp(const std::string& path, FileFormat format, std::uint64_t size) {
  if (size == 0) fail(path, "empty file");
  if (size > kMaxSceneFileBytes)
    fail(path, "the file has " + std::to_string(size) + " bytes, more than the " + std::to_string(kMaxSceneFileBytes) + " raylab reads");
  switch (format) {
    case FileFormat::gltf:
    case FileFormat::glb: {
      const std::string data = read_bytes(path, size);
      if (format == FileFormat::gltf) reject_utf16_text(path, data);
      check_gltf(path, data, format == FileFormat::glb, kMaxSceneFileBytes);
      break;
    }
    case FileFormat::collada: {
      const std::string data = read_bytes(path, size);
      reject_utf16_text(path, data);
      if (std::string_view(data).substr(0, kHeadBytes).find("<COLLADA") == std::string_view::npos)
        fail(path, "not a COLLADA file (no <COLLADA> element at its start)");
      check_collada(path, data);
      break;
    }
    case FileFormat::fbx: {
      const std::string data = read_bytes(path, size);
      if (!data.starts_with("Kaydara FBX Binary")) {
        reject_utf16_text(path, data);
        if (std::string_view(data).substr(0, kHeadBytes).find('\0') != std::string_view::npos)
          fail(path, "neither binary FBX (no 'Kaydara FBX Binary' magic) nor ASCII FBX (NUL bytes)");
      }
      check_fbx(path, data);
      break;
    }
    case FileFormat::three_ds: {
      const std::string head = read_bytes(path, std::min<std::uint64_t>(size, 6));
      if (head.size() < 6 || head[0] != '\x4d' || head[1] != '\x4d') fail(path, "not a 3DS file (no main chunk 0x4D4D)");
      const std::uint64_t length = read_le(head, 2, 4);
      if (length < 6 || length > size)
        fail(path, "the 3DS main chunk declares " + std::to_string(length) + " bytes, the file has " + std::to_string(size));
      break;
    }
    default:
      fail(path, file_format_doc(format).name + " is read by OpenMesh as one mesh, not by Assimp");
  }
}

/// Assimp's file access for one import: `name` (the path Assimp is given) opens `real`, every
/// other path itself; only regular files of at most kMaxSceneFileBytes open, for reading.
class CappedIOSystem final : public Assimp::DefaultIOSystem {
 public:
  CappedIOSystem(std::string name, std::string real) : name_(std::move(name)), real_(std::move(real)) {}
  using DefaultIOSystem::Exists;
  using DefaultIOSystem::Open;
  bool Exists(const char* file) const override { return DefaultIOSystem::Exists(resolve(file).c_str()); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    const std::string p = resolve(file);
    if (std::strpbrk(mode, "wa+")) return refuse(p, "opened for writing");
    std::error_code ec;
    const auto status = std::filesystem::status(p, ec);
    if (ec || !std::filesystem::is_regular_file(status)) return refuse(p, "not found or not a regular file");
    const std::uint64_t size = std::filesystem::file_size(p, ec);
    if (ec || size > kMaxSceneFileBytes) return refuse(p, std::string("larger than ") + std::to_string(kMaxSceneFileBytes) + " bytes");
    return DefaultIOSystem::Open(p.c_str(), mode);
  }
  /// Why the last refused file was refused (empty when none was).
  const std::string& refusal() const { return refusal_; }

 private:
  std::string resolve(const char* file) const { return file && name_ == file ? real_ : std::string(file ? file : ""); }
  Assimp::IOStream* refuse(const std::string& p, const std::string& why) {
    refusal_ = std::string("'") + p.substr(0, 200) + "' " + why;
    return nullptr;
  }
  std::string name_, real_;
  std::string refusal_;
};

std::string node_name(const aiNode* node) {
  const aiString& s = node->mName;
  const std::size_t n = std::min<std::size_t>(s.length, MAXLEN - 1);
  std::string name(s.data, std::find(s.data, s.data + n, '\0'));
  return "node '" + (name.size() > 60 ? name.substr(0, 60) + "..." : name) + "'";
}

/// A node's transform as an affine transform; throws unless finite and affine (last row 0 0 0 1).
AffineTransform affine(const std::string& path, const aiNode* node) {
  const aiMatrix4x4& t = node->mTransformation;
  const ai_real rows[4][4] = {{t.a1, t.a2, t.a3, t.a4}, {t.b1, t.b2, t.b3, t.b4}, {t.c1, t.c2, t.c3, t.c4}, {t.d1, t.d2, t.d3, t.d4}};
  for (const auto& row : rows)
    for (const ai_real x : row)
      if (!std::isfinite(x)) fail(path, node_name(node) + " has a non-finite transform");
  constexpr double kTol = 1e-6;
  if (std::abs(rows[3][0]) > kTol || std::abs(rows[3][1]) > kTol || std::abs(rows[3][2]) > kTol || std::abs(rows[3][3] - 1) > kTol)
    fail(path, node_name(node) + " has a projective transform (last row not 0 0 0 1)");
  AffineTransform a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.m[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)] = rows[r][c];
  return a;
}

/// A node that places geometry must have a finite, invertible world transform.
void require_placeable(const std::string& path, const aiNode* node, const AffineTransform& world) {
  if (!is_finite(world)) fail(path, node_name(node) + ": its world transform is not finite");
  if (!is_invertible(world)) fail(path, node_name(node) + " has a singular transform");
}

/// One aiMesh, validated: its triangle count after fanning polygons, and the lines and points
/// left out.
struct MeshCounts {
  std::uint64_t triangles = 0;
  std::uint64_t lines = 0;
  std::uint64_t points = 0;
};

MeshCounts validate_mesh(const std::string& path, const aiScene& scene, unsigned index) {
  const aiMesh* m = scene.mMeshes[index];
  const std::string where = "mesh " + std::to_string(index);
  if (!m) fail(path, where + " is missing");
  if (m->mNumVertices > 0 && !m->mVertices) fail(path, where + " has no vertex array");
  if (m->mNumFaces > 0 && !m->mFaces) fail(path, where + " has no face array");
  for (unsigned v = 0; v < m->mNumVertices; ++v) {
    const aiVector3D& p = m->mVertices[v];
    if (!std::isfinite(static_cast<float>(p.x)) || !std::isfinite(static_cast<float>(p.y)) || !std::isfinite(static_cast<float>(p.z)))
      fail(path, where + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
  }
  MeshCounts counts;
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    const aiFace& face = m->mFaces[f];
    if (face.mNumIndices > 0 && !face.mIndices) fail(path, where + ": face " + std::to_string(f) + " has no index array");
    for (unsigned k = 0; k < face.mNumIndices; ++k)
      if (face.mIndices[k] >= m->mNumVertices)
        fail(path, where + ": face " + std::to_string(f) + ": vertex index " + std::to_string(face.mIndices[k]) + " is outside [0, " +
                       std::to_string(m->mNumVertices) + ")");
    if (face.mNumIndices == 0) fail(path, where + ": face " + std::to_string(f) + " has no vertex index");
    if (face.mNumIndices >= 3) counts.triangles += face.mNumIndices - 2;
    else if (face.mNumIndices == 2) ++counts.lines;
    else ++counts.points;
    if (counts.triangles > kMaxImportTriangles) fail(path, where + " has more than " + std::to_string(kMaxImportTriangles) + " triangles");
  }
  return counts;
}

struct PositionHash {
  std::size_t operator()(const Vec3f& p) const {
    std::uint32_t b[3];
    std::memcpy(b, &p, sizeof b);
    return std::hash<std::uint64_t>()((std::uint64_t{b[0]} << 32 | b[1]) * 0x9e3779b97f4a7c15ull ^ b[2]);
  }
};

/// Appends the triangles of aiMesh `index` to `out`, vertices through `xf` (in double, then
/// rounded to float): only the vertices its faces use, and those of equal position once (Assimp's
/// COLLADA and FBX readers repeat a vertex for every corner; merged, closed meshes stay closed).
void append_mesh(const std::string& path, const aiScene& scene, unsigned index, const AffineTransform& xf, const aiNode* node,
                 TriangleMesh& out) {
  const aiMesh& m = *scene.mMeshes[index];
  std::vector<std::uint32_t> remap(m.mNumVertices, std::numeric_limits<std::uint32_t>::max());
  std::unordered_map<Vec3f, std::uint32_t, PositionHash> merged;
  auto vertex = [&](unsigned v) {
    if (remap[v] == std::numeric_limits<std::uint32_t>::max()) {
      const aiVector3D& p = m.mVertices[v];
      const Vec3f w = Vec3f(xf.apply_point(Vec3d(p.x, p.y, p.z))) + Vec3f(0.0f);  // + 0: -0 becomes +0
      if (!is_finite(w)) fail(path, node_name(node) + " places mesh " + std::to_string(index) + "'s vertex " + std::to_string(v) + " at a non-finite point");
      const auto [it, added] = merged.emplace(w, static_cast<std::uint32_t>(out.vertices.size()));
      if (added) {
        if (out.vertices.size() >= kMaxVertices) fail(path, "more than 2^32-1 vertices");
        out.vertices.push_back(w);
      }
      remap[v] = it->second;
    }
    return remap[v];
  };
  for (unsigned f = 0; f < m.mNumFaces; ++f) {
    const aiFace& face = m.mFaces[f];
    for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
      out.triangles.push_back({vertex(face.mIndices[0]), vertex(face.mIndices[k]), vertex(face.mIndices[k + 1])});
  }
}

struct Placement {
  std::size_t mesh;  ///< index into the distinct node mesh lists
  AffineTransform world;
  const aiNode* node;
};

/// The validated node tree (depth-first, children in order): what every node places.
std::vector<Placement> walk_nodes(const std::string& path, const aiScene& scene, std::vector<std::vector<unsigned>>& mesh_lists,
                                  std::size_t& node_count) {
  if (!scene.mRootNode) fail(path, "the scene has no root node");
  if (scene.mNumMeshes > 0 && !scene.mMeshes) fail(path, "the scene has no mesh array");
  std::map<std::vector<unsigned>, std::size_t> list_index;
  std::vector<Placement> placements;
  struct Frame {
    const aiNode* node;
    AffineTransform parent_world;
    std::size_t depth;
  };
  std::vector<Frame> stack{{scene.mRootNode, AffineTransform::identity(), 1}};
  std::unordered_set<const aiNode*> seen;
  node_count = 0;
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    const aiNode* node = f.node;
    if (!seen.insert(node).second) fail(path, "recursive nodes: " + node_name(node) + " is reached twice");
    if (++node_count > kMaxImportNodes) fail(path, "more than " + std::to_string(kMaxImportNodes) + " nodes");
    if (f.depth > kMaxImportNodeDepth) fail(path, "the node tree is deeper than " + std::to_string(kMaxImportNodeDepth) + " levels");
    const AffineTransform world = f.parent_world * affine(path, node);
    if (node->mNumMeshes > 0) {
      if (!node->mMeshes) fail(path, node_name(node) + " has no mesh index array");
      std::vector<unsigned> list(node->mMeshes, node->mMeshes + node->mNumMeshes);
      for (const unsigned m : list)
        if (m >= scene.mNumMeshes) fail(path, node_name(node) + " names mesh " + std::to_string(m) + " of " + std::to_string(scene.mNumMeshes));
      require_placeable(path, node, world);
      const auto [it, added] = list_index.emplace(std::move(list), mesh_lists.size());
      if (added) mesh_lists.push_back(it->first);
      placements.push_back({it->second, world, node});
    }
    if (node->mNumChildren == 0) continue;
    if (!node->mChildren) fail(path, node_name(node) + " has no child array");
    if (node->mNumChildren > kMaxImportNodes - node_count - stack.size())
      fail(path, "more than " + std::to_string(kMaxImportNodes) + " nodes");
    for (unsigned c = node->mNumChildren; c-- > 0;) {
      if (!node->mChildren[c]) fail(path, node_name(node) + " has a missing child");
      stack.push_back({node->mChildren[c], world, f.depth + 1});
    }
  }
  return placements;
}

/// Builds the raylab scene from a validated aiScene (scene_import.h).
Scene build_scene(const std::string& path, const aiScene& ai, SceneImportReport& report) {
  std::vector<std::vector<unsigned>> mesh_lists;
  const std::vector<Placement> placements = walk_nodes(path, ai, mesh_lists, report.nodes);
  std::vector<MeshCounts> counts(ai.mNumMeshes);
  std::vector<bool> validated(ai.mNumMeshes, false);
  std::vector<std::uint64_t> list_triangles(mesh_lists.size(), 0);
  std::vector<std::size_t> uses(mesh_lists.size(), 0);
  for (std::size_t l = 0; l < mesh_lists.size(); ++l)
    for (const unsigned m : mesh_lists[l]) {
      if (!validated[m]) {
        counts[m] = validate_mesh(path, ai, m);
        validated[m] = true;
      }
      list_triangles[l] += counts[m].triangles;
    }
  for (const Placement& p : placements) ++uses[p.mesh];
  // Caps before anything is allocated: each mesh list is stored once (flat or as a base).
  std::uint64_t stored = 0, instances = 0;
  for (std::size_t l = 0; l < mesh_lists.size(); ++l) {
    if (list_triangles[l] == 0) continue;
    stored += list_triangles[l];
    if (uses[l] > 1) instances += uses[l];
    ++report.meshes;
  }
  for (unsigned m = 0; m < ai.mNumMeshes; ++m) {
    if (!validated[m]) continue;
    report.lines += counts[m].lines;
    report.points += counts[m].points;
  }
  if (stored > kMaxImportTriangles)
    fail(path, "the scene stores " + std::to_string(stored) + " triangles, more than " + std::to_string(kMaxImportTriangles));
  if (instances > kMaxImportInstances)
    fail(path, "the scene has " + std::to_string(instances) + " instances, more than " + std::to_string(kMaxImportInstances));
  if (stored == 0)
    fail(path, "no triangles (" + std::to_string(report.lines) + " lines, " + std::to_string(report.points) + " points left out)");

  Scene scene;
  std::vector<std::uint32_t> base_of(mesh_lists.size(), std::numeric_limits<std::uint32_t>::max());
  for (const Placement& p : placements) {
    if (list_triangles[p.mesh] == 0) continue;
    if (uses[p.mesh] == 1) {
      for (const unsigned m : mesh_lists[p.mesh]) append_mesh(path, ai, m, p.world, p.node, scene.mesh);
      ++report.flattened_meshes;
      continue;
    }
    if (base_of[p.mesh] == std::numeric_limits<std::uint32_t>::max()) {
      auto base = std::make_shared<Scene>();
      base->spec = path + " (" + node_name(p.node) + "'s mesh)";
      for (const unsigned m : mesh_lists[p.mesh]) append_mesh(path, ai, m, AffineTransform::identity(), p.node, base->mesh);
      base_of[p.mesh] = static_cast<std::uint32_t>(scene.bases.size());
      scene.bases.push_back(std::move(base));
    }
    scene.instances.push_back({p.world, base_of[p.mesh]});
  }
  scene.flat_mesh_count = report.flattened_meshes;
  scene.left_out_lines = report.lines;
  scene.left_out_points = report.points;
  report.instances = scene.instances.size();
  return scene;
}

std::string assimp_error(const Assimp::Importer& importer) {
  std::string e = importer.GetErrorString();
  if (e.size() > 240) e = e.substr(0, 240) + "...";
  return e.empty() ? "no reason given" : e;
}

/// How long Assimp may take on a file of `bytes`: 10 s, plus 1 s per MiB (Assimp reads tens of
/// MiB per second; an endless loop inside it, as on a stray character in a COLLADA index list,
/// is stopped instead of hanging raylab).
std::chrono::milliseconds assimp_time_limit(std::uint64_t bytes) {
  return std::chrono::milliseconds(10'000 + static_cast<std::int64_t>(bytes >> 20) * 1'000);
}

/// Assimp's reader chooses by the extension: a file without one is given a name that has it and
/// opened under its own (the directory, where relative buffers are looked up, is the same).
std::string name_for_assimp(const std::string& path, const FileFormatDoc& doc) {
  return has_no_extension(path) ? path + doc.extensions.front() : path;
}

/// Reads the file through Assimp and builds the scene: run in a child process (import_scene).
Scene read_with_assimp(const std::string& path, const std::string& name, const FileFormatDoc& doc,
                       SceneImportReport& report) {
  Assimp::Importer importer;
  auto* io = new CappedIOSystem(name, path);
  importer.SetIOHandler(io);  // the importer owns it
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_ANIMATIONS, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_CAMERAS, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_LIGHTS, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_READ_TEXTURES, false);
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  const aiScene* ai = nullptr;
  try {
    ai = importer.ReadFile(name, aiProcess_ValidateDataStructure);
  } catch (const std::bad_alloc&) {
    fail(path, "Assimp ran out of memory reading the file");
  } catch (const std::exception& e) {
    fail(path, std::string("Assimp failed: ") + e.what());
  } catch (...) {
    fail(path, "Assimp failed with an unknown exception");
  }
  if (!ai) {
    const std::string refused = io->refusal().empty() ? "" : " (raylab refused to open " + io->refusal() + ")";
    fail(path, "Assimp could not read the " + doc.name + " file: " + assimp_error(importer) + refused);
  }
  if (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE) fail(path, "no triangles (Assimp read an incomplete scene: no meshes)");
  return build_scene(path, *ai, report);
}

/// The imported scene and its report through the child's pipe (child_process.h); the reader checks
/// every count against the caps before it allocates.
void write_mesh(PipeSink& sink, const TriangleMesh& mesh) {
  sink.put_vector(mesh.vertices);
  sink.put_vector(mesh.triangles);
}

TriangleMesh read_mesh(PipeSource& source) {
  TriangleMesh mesh;
  mesh.vertices = source.get_vector<Vec3f>(3 * kMaxImportTriangles);
  mesh.triangles = source.get_vector<std::array<std::uint32_t, 3>>(kMaxImportTriangles);
  return mesh;
}

void write_imported(PipeSink& sink, const Scene& scene, const SceneImportReport& report) {
  sink.put(report);
  write_mesh(sink, scene.mesh);
  sink.put_vector(scene.spheres);
  sink.put<std::uint64_t>(scene.flat_mesh_count);
  sink.put<std::uint64_t>(scene.left_out_lines);
  sink.put<std::uint64_t>(scene.left_out_points);
  sink.put<std::uint64_t>(scene.bases.size());
  for (const auto& base : scene.bases) {
    sink.put_string(base->spec);
    write_mesh(sink, base->mesh);
  }
  sink.put_vector(scene.instances);
}

Scene read_imported(PipeSource& source, SceneImportReport& report) {
  report = source.get<SceneImportReport>();
  Scene scene;
  scene.mesh = read_mesh(source);
  scene.spheres = source.get_vector<Sphere>(kMaxImportTriangles);
  scene.flat_mesh_count = source.get<std::uint64_t>();
  scene.left_out_lines = source.get<std::uint64_t>();
  scene.left_out_points = source.get<std::uint64_t>();
  const auto bases = source.get<std::uint64_t>();
  if (bases > kMaxImportNodes) throw std::length_error("wrote " + std::to_string(bases) + " bases, more than " + std::to_string(kMaxImportNodes));
  for (std::uint64_t b = 0; b < bases; ++b) {
    auto base = std::make_shared<Scene>();
    base->spec = source.get_string(std::uint64_t{1} << 16);
    base->mesh = read_mesh(source);
    scene.bases.push_back(std::move(base));
  }
  scene.instances = source.get_vector<SceneInstance>(kMaxImportInstances);
  return scene;
}

}  // namespace

Scene import_scene(const std::string& path, SceneImportReport* report) {
  const FileFormat format = detect_file_format(path);
  const FileFormatDoc& doc = file_format_doc(format);
  if (doc.library != FileLibrary::assimp) fail(path, doc.name + " is read by OpenMesh as one mesh (mesh_io), not as a scene by Assimp");
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) fail(path, "cannot determine the file size");
  check_before_assimp(path, format, size);

  SceneImportReport local;
  Scene scene = run_in_child_process<Scene>(
      path + ": Assimp", [&] { return read_with_assimp(path, name_for_assimp(path, doc), doc, local); },
      [&](PipeSink& sink, const Scene& read) { write_imported(sink, read, local); },
      [&](PipeSource& source) { return read_imported(source, local); }, assimp_time_limit(size));
  if (local.lines > 0 || local.points > 0)
    warn_input(path + ": left out " + std::to_string(local.lines) + " lines and " + std::to_string(local.points) +
               " points (raylab traces triangles)");
  if (report) *report = local;
  return scene;
}

}  // namespace raylab
