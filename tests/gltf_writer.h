#pragma once
// Small glTF 2.0 files written by the tests themselves (Khronos glTF 2.0 specification): meshes
// of float VEC3 positions and uint32 indices in one buffer (triangles, and primitives of lines or
// points beside them), nodes with a matrix or TRS and children, one scene of root nodes. The
// buffer is embedded as a base64 data URI, written beside the file as a .bin, or carried in a
// binary glTF (.glb) container.
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "geometry/transform.h"
#include "geometry/triangle_mesh.h"

namespace raylab::test {

struct GltfNode {
  int mesh = -1;
  std::vector<int> children;
  std::optional<AffineTransform> matrix;  ///< written as the column-major 4x4 `matrix`
  std::optional<std::array<double, 3>> translation;
  std::optional<std::array<double, 4>> rotation;  ///< unit quaternion x, y, z, w
  std::optional<std::array<double, 3>> scale;
  std::string name;
};

/// A node placing `mesh` (-1: none) by translation, rotation (quaternion x, y, z, w) and scale.
inline GltfNode trs_node(int mesh, std::array<double, 3> t, std::array<double, 4> r = {0, 0, 0, 1},
                         std::array<double, 3> s = {1, 1, 1}, std::vector<int> children = {}) {
  GltfNode n;
  n.mesh = mesh;
  n.children = std::move(children);
  n.translation = t;
  n.rotation = r;
  n.scale = s;
  return n;
}

/// glTF primitive modes other than TRIANGLES (glTF 2.0 §3.7.2.1, mesh.primitive.mode).
enum class GltfMode { points = 0, lines = 1, line_loop = 2, line_strip = 3 };

/// A primitive of mode `mode` in mesh `mesh`, beside that mesh's triangles: its own positions
/// and, unless empty, uint32 indices into them.
struct GltfPrimitive {
  int mesh = 0;
  GltfMode mode = GltfMode::lines;
  std::vector<Vec3f> positions;
  std::vector<std::uint32_t> indices;
};

struct GltfDocument {
  std::vector<TriangleMesh> meshes;  ///< a mesh without triangles has only its `primitives`
  std::vector<GltfNode> nodes;
  std::vector<int> roots;
  std::vector<GltfPrimitive> primitives;  ///< line and point primitives, after their mesh's triangles
};

enum class GltfBuffer { embedded, external, binary };

inline std::string base64(const std::string& bytes) {
  static const char* const kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kAlphabet[v >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

/// The glTF JSON of `doc` (buffer 0 without uri) and, in `bin`, the buffer's bytes.
inline nlohmann::json gltf_json(const GltfDocument& doc, std::string& bin) {
  using nlohmann::json;
  json j = {{"asset", {{"version", "2.0"}, {"generator", "raylab tests"}}}};
  json views = json::array(), accessors = json::array(), meshes = json::array();
  auto add = [&](const void* data, std::size_t bytes) {
    const std::size_t offset = bin.size();
    bin.append(static_cast<const char*>(data), bytes);
    while (bin.size() % 4) bin += '\0';
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
    return views.size() - 1;
  };
  auto add_positions = [&](const std::vector<Vec3f>& positions) {
    Bounds3f b;
    for (const Vec3f& p : positions) b.extend(p);
    const std::size_t pv = add(positions.data(), positions.size() * sizeof(Vec3f));
    accessors.push_back({{"bufferView", pv}, {"componentType", 5126}, {"count", positions.size()}, {"type", "VEC3"},
                         {"min", {b.lo.x, b.lo.y, b.lo.z}}, {"max", {b.hi.x, b.hi.y, b.hi.z}}});
    return accessors.size() - 1;
  };
  auto add_indices = [&](const void* indices, std::size_t count) {  // count uint32 indices
    const std::size_t iv = add(indices, count * sizeof(std::uint32_t));
    accessors.push_back({{"bufferView", iv}, {"componentType", 5125}, {"count", count}, {"type", "SCALAR"}});
    return accessors.size() - 1;
  };
  for (std::size_t i = 0; i < doc.meshes.size(); ++i) {
    const TriangleMesh& m = doc.meshes[i];
    json primitives = json::array();
    if (!m.triangles.empty()) {
      const std::size_t position = add_positions(m.vertices);
      const std::size_t indices = add_indices(m.triangles.data(), 3 * m.triangles.size());
      primitives.push_back({{"attributes", {{"POSITION", position}}}, {"indices", indices}});
    }
    for (const GltfPrimitive& p : doc.primitives) {
      if (p.mesh != static_cast<int>(i)) continue;
      json primitive = {{"attributes", {{"POSITION", add_positions(p.positions)}}}, {"mode", static_cast<int>(p.mode)}};
      if (!p.indices.empty()) primitive["indices"] = add_indices(p.indices.data(), p.indices.size());
      primitives.push_back(primitive);
    }
    meshes.push_back({{"primitives", primitives}});
  }
  json nodes = json::array();
  for (const GltfNode& n : doc.nodes) {
    json node = json::object();
    if (!n.name.empty()) node["name"] = n.name;
    if (n.mesh >= 0) node["mesh"] = n.mesh;
    if (!n.children.empty()) node["children"] = n.children;
    if (n.matrix) {
      json m = json::array();
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m.push_back(r < 3 ? n.matrix->m[r][c] : (c == 3 ? 1.0 : 0.0));
      node["matrix"] = m;
    }
    if (n.translation) node["translation"] = *n.translation;
    if (n.rotation) node["rotation"] = *n.rotation;
    if (n.scale) node["scale"] = *n.scale;
    nodes.push_back(node);
  }
  j["bufferViews"] = views;
  j["accessors"] = accessors;
  j["meshes"] = meshes;
  j["nodes"] = nodes;
  j["scenes"] = {{{"nodes", doc.roots}}};
  j["scene"] = 0;
  j["buffers"] = {{{"byteLength", bin.size()}}};
  return j;
}

/// Writes glTF JSON `j` with buffer 0 = `bin` to `path` (a .gltf, or for GltfBuffer::binary a
/// .glb; any name works). GltfBuffer::external writes the buffer to PATH.bin beside it.
inline void write_gltf_json(const std::string& path, nlohmann::json j, const std::string& bin, GltfBuffer buffer) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (buffer == GltfBuffer::embedded) {
    j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin);
    out << j.dump();
  } else if (buffer == GltfBuffer::external) {
    const std::string bin_name = path.substr(path.find_last_of('/') + 1) + ".bin";
    j["buffers"][0]["uri"] = bin_name;
    std::ofstream(path.substr(0, path.find_last_of('/') + 1) + bin_name, std::ios::binary | std::ios::trunc) << bin;
    out << j.dump();
  } else {
    std::string text = j.dump();
    while (text.size() % 4) text += ' ';
    auto u32 = [&](std::uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
    out.write("glTF", 4);
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    u32(static_cast<std::uint32_t>(text.size()));
    u32(0x4E4F534Au);
    out << text;
    u32(static_cast<std::uint32_t>(bin.size()));
    u32(0x004E4942u);
    out << bin;
  }
}

/// Writes `doc` to `path` (see write_gltf_json).
inline void write_gltf(const std::string& path, const GltfDocument& doc, GltfBuffer buffer = GltfBuffer::embedded) {
  std::string bin;
  const nlohmann::json j = gltf_json(doc, bin);
  write_gltf_json(path, j, bin, buffer);
}

/// A quaternion (x, y, z, w) turning by `radians` about the unit axis (x, y, z).
inline std::array<double, 4> quaternion(const Vec3d& axis, double radians) {
  const Vec3d k = normalize(axis) * std::sin(radians / 2);
  return {k.x, k.y, k.z, std::cos(radians / 2)};
}

}  // namespace raylab::test
