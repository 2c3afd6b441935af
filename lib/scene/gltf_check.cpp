#include "scene/gltf_check.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <vector>

#include "geometry/input_error.h"
#include "scene/little_endian.h"

namespace raylab {
namespace {

using Json = nlohmann::json;

constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
constexpr std::uint64_t kMaxCount = std::uint64_t{1} << 32;

/// Deepest nesting of arrays and objects in JSON text (strings skipped); stops counting past `limit`.
int json_depth(std::string_view text, int limit) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (deepest > limit) return deepest;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

std::uint64_t component_bytes(std::uint64_t type) {
  switch (type) {
    case 5120: case 5121: return 1;  // (unsigned) byte
    case 5122: case 5123: return 2;  // (unsigned) short
    case 5125: case 5126: return 4;  // unsigned int, float
    default: return 0;
  }
}

std::uint64_t components(const std::string& type) {
  static const std::pair<const char*, std::uint64_t> kTypes[] = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                                  {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
  for (const auto& [name, n] : kTypes)
    if (type == name) return n;
  return 0;
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

bool is_base64(char c) { return c == '=' || base64_value(c) >= 0; }

std::string base64_decoded(std::string_view s) {
  std::string out;
  out.reserve(s.size() / 4 * 3);
  std::uint32_t bits = 0;
  int n = 0;
  for (const char c : s) {
    const int v = base64_value(c);
    if (v < 0) break;  // '=' padding
    bits = bits << 6 | static_cast<std::uint32_t>(v);
    if ((n += 6) >= 8) {
      n -= 8;
      out += static_cast<char>(bits >> n & 0xff);
    }
  }
  return out;
}



std::optional<std::string> percent_decoded(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out += s[i];
      continue;
    }
    if (i + 2 >= s.size() || !std::isxdigit(static_cast<unsigned char>(s[i + 1])) || !std::isxdigit(static_cast<unsigned char>(s[i + 2])))
      return std::nullopt;
    out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
    i += 2;
  }
  return out;
}

class GltfChecker {
 public:
  GltfChecker(const std::string& path, std::uint64_t max_file_bytes) : path_(path), max_file_bytes_(max_file_bytes) {}

  void check(std::string_view data, bool binary) {
    data_ = data;
    std::string_view json_text = data;
    std::optional<std::uint64_t> bin_chunk;
    if (binary) json_text = split_glb(data, bin_chunk);
    if (json_depth(json_text, kMaxGltfJsonDepth) > kMaxGltfJsonDepth)
      fail("JSON nested deeper than " + std::to_string(kMaxGltfJsonDepth) + " levels");
    const Json root = Json::parse(json_text.begin(), json_text.end(), nullptr, false);
    if (root.is_discarded()) fail("not valid JSON");
    if (!root.is_object()) fail("the JSON is not an object");
    check_asset(root);
    check_buffers(root, bin_chunk);
    check_buffer_views(root);
    check_accessors(root);
    check_meshes(root);
    check_nodes(root);
    check_others(root);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(path_ + ": glTF: " + what); }

  /// The binary glTF container: header, JSON chunk, optional BIN chunk (its length in `bin`).
  std::string_view split_glb(std::string_view data, std::optional<std::uint64_t>& bin) {
    if (data.size() < 20) fail("binary glTF shorter than its 12-byte header and first chunk header");
    if (data.substr(0, 4) != "glTF") fail("binary glTF without the 'glTF' magic");
    if (read_le(data, 4, 4) != 2) fail("binary glTF version " + std::to_string(read_le(data, 4, 4)) + " (raylab reads glTF 2.0)");
    if (read_le(data, 8, 4) != data.size())
      fail("binary glTF header declares " + std::to_string(read_le(data, 8, 4)) + " bytes, the file has " + std::to_string(data.size()));
    const std::uint64_t json_length = read_le(data, 12, 4);
    if (read_le(data, 16, 4) != 0x4E4F534Au) fail("the first chunk of a binary glTF must be JSON");
    if (20 + json_length > data.size()) fail("the JSON chunk runs past the end of the file");
    const std::uint64_t next = 20 + json_length;
    if (next + 8 <= data.size() && read_le(data, static_cast<std::size_t>(next + 4), 4) == 0x004E4942u) {
      const std::uint64_t bin_length = read_le(data, static_cast<std::size_t>(next), 4);
      if (next + 8 + bin_length > data.size()) fail("the BIN chunk runs past the end of the file");
      bin = bin_length;
      bin_offset_ = next + 8;
    }
    return data.substr(20, static_cast<std::size_t>(json_length));
  }

  const Json& array(const Json& obj, const char* key, const std::string& where) const {
    static const Json empty = Json::array();
    const auto it = obj.find(key);
    if (it == obj.end()) return empty;
    if (!it->is_array()) fail(where + "'" + key + "' is not an array");
    return *it;
  }

  const Json& object_at(const Json& arr, std::size_t i, const std::string& what) const {
    if (!arr[i].is_object()) fail(what + " " + std::to_string(i) + " is not an object");
    return arr[i];
  }

  /// An unsigned integer member; kNone when absent and not `required`.
  std::uint64_t integer(const Json& obj, const char* key, const std::string& where, bool required = false) const {
    const auto it = obj.find(key);
    if (it == obj.end()) {
      if (required) fail(where + ": no '" + key + "'");
      return kNone;
    }
    if (!it->is_number_unsigned()) fail(where + ": '" + key + "' is not a non-negative integer");
    return it->get<std::uint64_t>();
  }

  /// An index member that must name one of `count` objects (`what`).
  std::uint64_t index(const Json& obj, const char* key, std::size_t count, const std::string& what, const std::string& where,
                      bool required = false) const {
    const std::uint64_t i = integer(obj, key, where, required);
    if (i != kNone && i >= count)
      fail(where + ": '" + key + "' " + std::to_string(i) + " is out of range (" + std::to_string(count) + " " + what + ")");
    return i;
  }

  void finite_numbers(const Json& obj, const char* key, std::size_t n, const std::string& where) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return;
    if (!it->is_array() || it->size() != n) fail(where + ": '" + key + "' is not an array of " + std::to_string(n) + " numbers");
    for (const auto& x : *it)
      if (!x.is_number() || !std::isfinite(x.get<double>())) fail(where + ": '" + key + "' has a non-finite or non-numeric value");
  }

  void check_asset(const Json& root) const {
    const auto asset = root.find("asset");
    if (asset == root.end() || !asset->is_object()) fail("no 'asset' object");
    const auto version = asset->find("version");
    if (version == asset->end() || !version->is_string()) fail("no asset.version");
    const std::string v = version->get<std::string>();
    if (!v.starts_with("2.")) fail("version '" + v.substr(0, 16) + "' (raylab reads glTF 2.0)");
  }

  void check_buffers(const Json& root, std::optional<std::uint64_t> bin_chunk) {
    const Json& buffers = array(root, "buffers", "");
    const std::filesystem::path dir = std::filesystem::path(path_).parent_path();
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const Json& b = object_at(buffers, i, "buffer");
      const std::string where = "buffer " + std::to_string(i);
      const std::uint64_t length = integer(b, "byteLength", where, true);
      if (length == 0 || length > max_file_bytes_) fail(where + ": byteLength " + std::to_string(length) + " is out of range");
      buffer_lengths_.push_back(length);
      buffer_sources_.push_back({});
      const auto uri = b.find("uri");
      if (uri == b.end()) {
        if (i != 0 || !bin_chunk) fail(where + " has no uri (only buffer 0 of a binary glTF may use the BIN chunk)");
        if (*bin_chunk < length) fail(where + ": the BIN chunk holds " + std::to_string(*bin_chunk) + " bytes, fewer than byteLength");
        buffer_sources_.back().bytes = data_.substr(static_cast<std::size_t>(bin_offset_), static_cast<std::size_t>(length));
        buffer_sources_.back().loaded = true;
        continue;
      }
      if (!uri->is_string()) fail(where + ": uri is not a string");
      const std::string& u = uri->get_ref<const std::string&>();  // lives as long as the JSON: data_uri views it
      if (u.starts_with("data:")) {
        const std::size_t comma = u.find(',');
        if (comma == std::string::npos || u.substr(0, comma).find(";base64") == std::string::npos)
          fail(where + ": only base64 data URIs are read");
        const std::string_view payload = std::string_view(u).substr(comma + 1);
        if (!std::all_of(payload.begin(), payload.end(), is_base64)) fail(where + ": the data URI is not base64");
        if (payload.size() / 4 * 3 < length) fail(where + ": the data URI holds fewer than byteLength bytes");
        buffer_sources_.back().data_uri = payload;
        continue;
      }
      if (u.find("://") != std::string::npos) fail(where + ": uri '" + u.substr(0, 80) + "' is not a file beside the glTF");
      std::error_code ec;
      std::filesystem::path file = dir / u;
      if (!std::filesystem::exists(file, ec))
        if (const auto decoded = percent_decoded(u)) file = dir / *decoded;
      const auto status = std::filesystem::status(file, ec);
      if (ec || !std::filesystem::exists(status)) fail(where + ": '" + u.substr(0, 80) + "' not found (looked for " + file.string() + ")");
      if (!std::filesystem::is_regular_file(status)) fail(where + ": '" + u.substr(0, 80) + "' is not a regular file");
      const std::uint64_t size = std::filesystem::file_size(file, ec);
      if (ec || size < length)
        fail(where + ": '" + u.substr(0, 80) + "' holds " + std::to_string(size) + " bytes, fewer than byteLength " + std::to_string(length));
      if (size > max_file_bytes_) fail(where + ": '" + u.substr(0, 80) + "' is larger than " + std::to_string(max_file_bytes_) + " bytes");
      buffer_sources_.back().file = file.string();
    }
  }

  /// The first byteLength bytes of buffer `b`, decoded or read on first use.
  std::string_view buffer_bytes(std::size_t b) {
    BufferSource& s = buffer_sources_[b];
    if (!s.loaded) {
      if (!s.file.empty()) {
        std::ifstream in(s.file, std::ios::binary);
        s.storage.assign(static_cast<std::size_t>(buffer_lengths_[b]), '\0');
        in.read(s.storage.data(), static_cast<std::streamsize>(s.storage.size()));
        if (static_cast<std::uint64_t>(in.gcount()) != buffer_lengths_[b]) fail("buffer " + std::to_string(b) + ": read error");
      } else {
        s.storage = base64_decoded(s.data_uri);
        if (s.storage.size() < buffer_lengths_[b]) fail("buffer " + std::to_string(b) + ": the data URI holds fewer than byteLength bytes");
      }
      s.bytes = s.storage;
      s.loaded = true;
    }
    return s.bytes;
  }

  void check_buffer_views(const Json& root) {
    const Json& views = array(root, "bufferViews", "");
    for (std::size_t i = 0; i < views.size(); ++i) {
      const Json& v = object_at(views, i, "bufferView");
      const std::string where = "bufferView " + std::to_string(i);
      const std::uint64_t buffer = index(v, "buffer", buffer_lengths_.size(), "buffers", where, true);
      std::uint64_t offset = integer(v, "byteOffset", where);
      if (offset == kNone) offset = 0;
      const std::uint64_t length = integer(v, "byteLength", where, true);
      if (length == 0 || offset > buffer_lengths_[buffer] || length > buffer_lengths_[buffer] - offset)
        fail(where + ": bytes [" + std::to_string(offset) + ", +" + std::to_string(length) + ") lie outside buffer " +
             std::to_string(buffer) + " of " + std::to_string(buffer_lengths_[buffer]) + " bytes");
      const std::uint64_t stride = integer(v, "byteStride", where);
      if (stride != kNone && (stride < 4 || stride > 252)) fail(where + ": byteStride " + std::to_string(stride) + " is outside [4, 252]");
      views_.push_back({buffer, offset, length, stride == kNone ? 0 : stride});
    }
  }

  /// Whether `count` elements of `element` bytes, `stride` apart (0: packed), from `offset` fit in `length` bytes.
  static bool fits(std::uint64_t offset, std::uint64_t count, std::uint64_t element, std::uint64_t stride, std::uint64_t length) {
    const std::uint64_t step = stride ? stride : element;
    return offset <= length && element <= length - offset && (count - 1) * step <= length - offset - element;
  }

  void check_accessors(const Json& root) {
    const Json& accessors = array(root, "accessors", "");
    for (std::size_t i = 0; i < accessors.size(); ++i) {
      const Json& a = object_at(accessors, i, "accessor");
      const std::string where = "accessor " + std::to_string(i);
      const std::uint64_t component = component_bytes(integer(a, "componentType", where, true));
      if (component == 0) fail(where + ": unknown componentType");
      const auto type = a.find("type");
      const std::uint64_t n = type != a.end() && type->is_string() ? components(type->get<std::string>()) : 0;
      if (n == 0) fail(where + ": missing or unknown type");
      const std::uint64_t count = integer(a, "count", where, true);
      if (count == 0 || count > kMaxCount) fail(where + ": count " + std::to_string(count) + " is out of range");
      const std::uint64_t element = component * n;
      std::uint64_t offset = integer(a, "byteOffset", where);
      if (offset == kNone) offset = 0;
      const std::uint64_t view = index(a, "bufferView", views_.size(), "bufferViews", where);
      accessors_.push_back({integer(a, "componentType", where), n, count, view, offset, a.contains("sparse")});
      if (view != kNone) {
        if (!fits(offset, count, element, views_[view].stride, views_[view].length))
          fail(where + ": " + std::to_string(count) + " elements run past the end of bufferView " + std::to_string(view));
      } else if (count * element > kMaxGltfZeroAccessorBytes) {
        fail(where + ": " + std::to_string(count) + " elements without a bufferView exceed " +
             std::to_string(kMaxGltfZeroAccessorBytes) + " bytes");
      }
      const auto sparse = a.find("sparse");
      if (sparse == a.end()) continue;
      if (!sparse->is_object()) fail(where + ": sparse is not an object");
      const std::uint64_t sparse_count = integer(*sparse, "count", where + " sparse", true);
      if (sparse_count == 0 || sparse_count > count) fail(where + ": sparse count " + std::to_string(sparse_count) + " is out of range");
      for (const char* part : {"indices", "values"}) {
        const auto p = sparse->find(part);
        if (p == sparse->end() || !p->is_object()) fail(where + ": sparse." + part + " is missing");
        const std::string pw = where + " sparse." + part;
        const std::uint64_t pv = index(*p, "bufferView", views_.size(), "bufferViews", pw, true);
        std::uint64_t po = integer(*p, "byteOffset", pw);
        if (po == kNone) po = 0;
        std::uint64_t bytes = element;
        if (std::string(part) == "indices") {
          const std::uint64_t ct = integer(*p, "componentType", pw, true);
          if (ct != 5121 && ct != 5123 && ct != 5125) fail(pw + ": componentType must be an unsigned integer type");
          bytes = component_bytes(ct);
        }
        if (!fits(po, sparse_count, bytes, 0, views_[pv].length)) fail(pw + ": runs past the end of bufferView " + std::to_string(pv));
      }
    }
  }

  void check_accessor_ref(const Json& obj, const char* key, const std::string& where, bool required = false) const {
    index(obj, key, accessors_.size(), "accessors", where, required);
  }

  void check_meshes(const Json& root) {
    const Json& meshes = array(root, "meshes", "");
    const std::size_t materials = array(root, "materials", "").size();
    mesh_count_ = meshes.size();
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      const Json& m = object_at(meshes, i, "mesh");
      const std::string where = "mesh " + std::to_string(i);
      const Json& primitives = array(m, "primitives", where + ": ");
      for (std::size_t k = 0; k < primitives.size(); ++k) {
        const Json& p = object_at(primitives, k, where + " primitive");
        const std::string pw = where + " primitive " + std::to_string(k);
        const auto attributes = p.find("attributes");
        if (attributes == p.end() || !attributes->is_object()) fail(pw + ": no attributes");
        for (const auto& [name, value] : attributes->items()) {
          if (!value.is_number_unsigned() || value.get<std::uint64_t>() >= accessors_.size())
            fail(pw + ": attribute " + name.substr(0, 40) + " names no accessor");
          const Accessor& a = accessors_[value.get<std::size_t>()];
          if (name == "POSITION" && (a.component_type != 5126 || a.components != 3)) fail(pw + ": POSITION is not a float VEC3 accessor");
        }
        const std::uint64_t indices = index(p, "indices", accessors_.size(), "accessors", pw);
        if (indices != kNone) {
          const Accessor& a = accessors_[indices];
          if (a.components != 1 || (a.component_type != 5121 && a.component_type != 5123 && a.component_type != 5125))
            fail(pw + ": indices are not an unsigned integer SCALAR accessor");
          if (a.sparse) fail(pw + ": sparse index accessors are not read");
          const auto position = attributes->find("POSITION");
          if (position != attributes->end()) {
            const std::uint64_t vertices = accessors_[position->get<std::size_t>()].count;
            const std::uint64_t largest = largest_index(indices);
            if (largest >= vertices)
              fail(pw + ": vertex index " + std::to_string(largest) + " is outside [0, " + std::to_string(vertices) + ")");
          }
        }
        index(p, "material", materials, "materials", pw);
        const std::uint64_t mode = integer(p, "mode", pw);
        if (mode != kNone && mode > 6) fail(pw + ": mode " + std::to_string(mode) + " is not a glTF primitive mode");
        const Json& targets = array(p, "targets", pw + ": ");
        for (const auto& t : targets) {
          if (!t.is_object()) fail(pw + ": a morph target is not an object");
          for (const auto& [name, value] : t.items())
            if (!value.is_number_unsigned() || value.get<std::uint64_t>() >= accessors_.size())
              fail(pw + ": morph target attribute " + name.substr(0, 40) + " names no accessor");
        }
      }
    }
  }

  /// The largest value of an index accessor (Assimp drops faces with indices out of range
  /// silently, so raylab reads them itself).
  std::uint64_t largest_index(std::uint64_t accessor) {
    const Accessor& a = accessors_[accessor];
    if (a.view == kNone) return 0;
    const View& v = views_[a.view];
    const std::uint64_t bytes = component_bytes(a.component_type);
    const std::uint64_t step = v.stride ? v.stride : bytes;
    const std::string_view data = buffer_bytes(v.buffer);
    const std::uint64_t first = v.offset + a.offset;
    std::uint64_t largest = 0;
    for (std::uint64_t i = 0; i < a.count; ++i)
      largest = std::max(largest, read_le(data, static_cast<std::size_t>(first + i * step), static_cast<std::size_t>(bytes)));
    return largest;
  }

  void check_nodes(const Json& root) {
    const Json& nodes = array(root, "nodes", "");
    const std::size_t n = nodes.size();
    const std::size_t cameras = array(root, "cameras", "").size(), skins = array(root, "skins", "").size();
    std::vector<std::uint64_t> parent(n, kNone);
    for (std::size_t i = 0; i < n; ++i) {
      const Json& node = object_at(nodes, i, "node");
      const std::string where = "node " + std::to_string(i);
      for (const auto& c : array(node, "children", where + ": ")) {
        if (!c.is_number_unsigned() || c.get<std::uint64_t>() >= n) fail(where + ": a child index is out of range");
        const auto child = c.get<std::size_t>();
        if (child == i) fail("recursive nodes: node " + std::to_string(i) + " is its own child");
        if (parent[child] != kNone) fail("node " + std::to_string(child) + " has two parents (nodes " + std::to_string(parent[child]) + " and " + std::to_string(i) + ")");
        parent[child] = i;
      }
      index(node, "mesh", mesh_count_, "meshes", where);
      index(node, "camera", cameras, "cameras", where);
      index(node, "skin", skins, "skins", where);
      finite_numbers(node, "matrix", 16, where);
      finite_numbers(node, "translation", 3, where);
      finite_numbers(node, "rotation", 4, where);
      finite_numbers(node, "scale", 3, where);
    }
    // Depth from the roots, iteratively; nodes no root reaches lie on a cycle.
    std::vector<int> depth(n, -1);
    std::vector<std::size_t> stack;
    for (std::size_t i = 0; i < n; ++i)
      if (parent[i] == kNone) {
        depth[i] = 1;
        stack.push_back(i);
      }
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      for (const auto& c : array(nodes[i], "children", "")) {
        const auto child = c.get<std::size_t>();
        depth[child] = depth[i] + 1;
        if (depth[child] > kMaxGltfNodeDepth) fail("the node tree is deeper than " + std::to_string(kMaxGltfNodeDepth) + " levels");
        stack.push_back(child);
      }
    }
    for (std::size_t i = 0; i < n; ++i)
      if (depth[i] < 0) fail("recursive nodes: node " + std::to_string(i) + " is its own ancestor");
    const Json& scenes = array(root, "scenes", "");
    for (std::size_t s = 0; s < scenes.size(); ++s)
      for (const auto& r : array(object_at(scenes, s, "scene"), "nodes", "scene " + std::to_string(s) + ": "))
        if (!r.is_number_unsigned() || r.get<std::uint64_t>() >= n) fail("scene " + std::to_string(s) + ": a node index is out of range");
    index(root, "scene", scenes.size(), "scenes", "the default scene");
    for (std::size_t s = 0; s < skins; ++s) {
      const Json& skin = object_at(array(root, "skins", ""), s, "skin");
      const std::string where = "skin " + std::to_string(s);
      for (const auto& j : array(skin, "joints", where + ": "))
        if (!j.is_number_unsigned() || j.get<std::uint64_t>() >= n) fail(where + ": a joint index is out of range");
      index(skin, "skeleton", n, "nodes", where);
      check_accessor_ref(skin, "inverseBindMatrices", where);
    }
    const Json& animations = array(root, "animations", "");
    for (std::size_t a = 0; a < animations.size(); ++a) {
      const Json& anim = object_at(animations, a, "animation");
      const std::string where = "animation " + std::to_string(a);
      const Json& samplers = array(anim, "samplers", where + ": ");
      for (std::size_t k = 0; k < samplers.size(); ++k) {
        const Json& s = object_at(samplers, k, where + " sampler");
        check_accessor_ref(s, "input", where, true);
        check_accessor_ref(s, "output", where, true);
      }
      for (const auto& ch : array(anim, "channels", where + ": ")) {
        if (!ch.is_object()) fail(where + ": a channel is not an object");
        index(ch, "sampler", samplers.size(), "samplers", where, true);
        const auto target = ch.find("target");
        if (target == ch.end() || !target->is_object()) fail(where + ": a channel has no target");
        index(*target, "node", n, "nodes", where);
      }
    }
  }

  /// Images, textures and the texture references of materials.
  void check_others(const Json& root) const {
    const Json& images = array(root, "images", "");
    for (std::size_t i = 0; i < images.size(); ++i)
      index(object_at(images, i, "image"), "bufferView", views_.size(), "bufferViews", "image " + std::to_string(i));
    const Json& textures = array(root, "textures", "");
    const std::size_t samplers = array(root, "samplers", "").size();
    for (std::size_t i = 0; i < textures.size(); ++i) {
      const Json& t = object_at(textures, i, "texture");
      index(t, "source", images.size(), "images", "texture " + std::to_string(i));
      index(t, "sampler", samplers, "samplers", "texture " + std::to_string(i));
    }
    const Json& materials = array(root, "materials", "");
    for (std::size_t i = 0; i < materials.size(); ++i) check_texture_refs(object_at(materials, i, "material"), textures.size(), "material " + std::to_string(i));
  }

  /// Every `*Texture` member's index, at any depth (JSON depth is capped).
  void check_texture_refs(const Json& obj, std::size_t textures, const std::string& where) const {
    if (!obj.is_object()) return;
    for (const auto& [key, value] : obj.items()) {
      if (!value.is_object()) continue;
      if (key.size() >= 7 && key.ends_with("Texture")) index(value, "index", textures, "textures", where + " " + key.substr(0, 40), true);
      check_texture_refs(value, textures, where);
    }
  }

  struct View {
    std::uint64_t buffer, offset, length, stride;
  };
  struct Accessor {
    std::uint64_t component_type, components, count;
    std::uint64_t view, offset;  ///< view kNone: all zeros
    bool sparse;
  };
  struct BufferSource {
    std::string_view data_uri;  ///< base64 payload, or
    std::string file;           ///< a file beside the glTF, or (loaded from the start) the BIN chunk
    std::string storage;
    std::string_view bytes;
    bool loaded = false;
  };

  const std::string& path_;
  std::string_view data_;
  std::uint64_t bin_offset_ = 0;
  std::vector<BufferSource> buffer_sources_;
  std::uint64_t max_file_bytes_;
  std::vector<std::uint64_t> buffer_lengths_;
  std::vector<View> views_;
  std::vector<Accessor> accessors_;
  std::size_t mesh_count_ = 0;
};

}  // namespace

void check_gltf(const std::string& path, std::string_view data, bool binary, std::uint64_t max_file_bytes) {
  GltfChecker(path, max_file_bytes).check(data, binary);
}

}  // namespace raylab
