#pragma once
// Scene files the tests write themselves: a unit cube, glTF documents placing it, a COLLADA
// tetrahedron under three nodes, and bad scene files for the Assimp path (glTF, binary glTF,
// COLLADA, 3DS, FBX), each with a fragment of the error it must give. Used by
// test_scene_import.cpp (import_scene's messages), test_bad_input.cpp (through the tool) and
// test_tool_cli.cpp.
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "gltf_writer.h"

namespace raylab::test {

/// The unit cube [0,1]^3: 8 vertices, 12 triangles, closed and outward-facing.
inline TriangleMesh unit_cube() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(Vec3f(float(i & 1), float(i >> 1 & 1), float(i >> 2 & 1)));
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

/// The unit cube under two root nodes, the second translated by (2, 0, 0).
inline GltfDocument shared_cube_document() {
  GltfDocument doc;
  doc.meshes = {unit_cube()};
  doc.nodes = {trs_node(0, {0, 0, 0}), trs_node(0, {2, 0, 0})};
  doc.roots = {0, 1};
  return doc;
}

/// A COLLADA tetrahedron (4 triangles) under three nodes, the third nested in the second:
/// a: translate (3, 0, 0); b: the matrix of scale x by 2 and translate y by 1; c (in b): translate
/// (0, 0, 2). `index_list` is the triangles' <p> content.
inline std::string collada_tetrahedron(const std::string& index_list = "0 2 1 0 1 3 0 3 2 1 2 3") {
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries><geometry id="tet"><mesh>
    <source id="p"><float_array id="pa" count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array>
      <technique_common><accessor source="#pa" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="4"><input semantic="VERTEX" source="#v" offset="0"/><p>)" +
         index_list + R"(</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s">
    <node id="a"><translate>3 0 0</translate><instance_geometry url="#tet"/></node>
    <node id="b"><matrix>2 0 0 0 0 1 0 1 0 0 1 0 0 0 0 1</matrix><instance_geometry url="#tet"/>
      <node id="c"><translate>0 0 2</translate><instance_geometry url="#tet"/></node></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)";
}

/// A record of a binary FBX: its name, string properties and nested records.
struct FbxRecord {
  std::string name;
  std::vector<std::string> strings;
  std::vector<FbxRecord> children;
};

/// A binary FBX (version 7400: 32-bit record headers) of the given top-level records.
inline std::string fbx_binary(const std::vector<FbxRecord>& top) {
  std::string out("Kaydara FBX Binary  \0\x1a\0", 23);
  auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  auto patch = [&](std::size_t at, std::size_t v) {
    const auto x = static_cast<std::uint32_t>(v);
    std::memcpy(out.data() + at, &x, 4);
  };
  u32(7400);
  std::function<void(const FbxRecord&)> write = [&](const FbxRecord& r) {
    const std::size_t start = out.size();
    out.append(12, '\0');
    out += static_cast<char>(r.name.size());
    out += r.name;
    const std::size_t properties = out.size();
    for (const std::string& s : r.strings) {
      out += 'S';
      u32(static_cast<std::uint32_t>(s.size()));
      out += s;
    }
    patch(start + 4, r.strings.size());
    patch(start + 8, out.size() - properties);
    for (const FbxRecord& c : r.children) write(c);
    if (!r.children.empty()) out.append(13, '\0');
    patch(start, out.size());
  };
  for (const FbxRecord& r : top) write(r);
  out.append(13, '\0');
  return out;
}

struct BadSceneFile {
  std::string path;
  std::string fault;  ///< a fragment of the one-line error
};

/// Writes every bad scene file into `dir` (which must exist).
inline std::vector<BadSceneFile> write_bad_scene_files(const std::string& dir) {
  using nlohmann::json;
  struct GltfCase {
    std::string name, fault;
    std::function<void(json&, std::string&)> edit;  ///< edits the shared cube's JSON and buffer
  };
  const std::vector<GltfCase> gltf = {
      {"index_out_of_range.gltf", "vertex index 8 is outside [0, 8)",
       [](json&, std::string& bin) { const std::uint32_t v = 8; std::memcpy(bin.data() + 8 * 12, &v, 4); }},
      {"accessor_past_view.gltf", "run past the end of bufferView", [](json& j, std::string&) { j["accessors"][0]["count"] = 9; }},
      {"recursive.gltf", "recursive nodes", [](json& j, std::string&) {
         j["nodes"][0]["children"] = {1};
         j["nodes"][1]["children"] = {0};
       }},
      {"two_parents.gltf", "two parents", [](json& j, std::string&) {
         j["nodes"].push_back({{"children", {1}}});
         j["nodes"][0]["children"] = {1};
       }},
      {"nan_vertex.gltf", "non-finite", [](json&, std::string& bin) {
         const float nan = std::numeric_limits<float>::quiet_NaN();
         std::memcpy(bin.data() + 4, &nan, 4);
       }},
      {"inf_transform.gltf", "non-finite", [](json& j, std::string&) { j["nodes"][0]["scale"] = {1e300, 1, 1}; }},
      {"singular.gltf", "singular transform", [](json& j, std::string&) { j["nodes"][1]["scale"] = {1, 0, 1}; }},
      {"no_triangles.gltf", "no triangles", [](json& j, std::string&) { j["meshes"][0]["primitives"][0]["mode"] = 0; }},
      {"missing_bin.gltf", "'missing.bin' not found", [](json& j, std::string&) { j["buffers"][0]["uri"] = "missing.bin"; }},
      {"version1.gltf", "raylab reads glTF 2.0", [](json& j, std::string&) { j["asset"]["version"] = "1.0"; }},
      {"deep_json.gltf", "nested deeper", [](json& j, std::string&) {
         json deep = 0;
         for (int i = 0; i < 100; ++i) deep = json::array({deep});
         j["extras"] = deep;
       }},
      {"bad_mesh_ref.gltf", "out of range", [](json& j, std::string&) { j["nodes"][0]["mesh"] = 7; }},
      {"huge_count.gltf", "elements without a bufferView", [](json& j, std::string&) {
         j["accessors"][0].erase("bufferView");
         j["accessors"][0]["count"] = 4000000000u;
       }},
  };
  std::vector<BadSceneFile> files;
  for (const GltfCase& c : gltf) {
    std::string bin;
    json j = gltf_json(shared_cube_document(), bin);
    c.edit(j, bin);
    const std::string path = dir + "/" + c.name;
    // The buffer is embedded unless the edit named a file for it.
    if (j["buffers"][0].contains("uri")) std::ofstream(path) << j.dump();
    else write_gltf_json(path, j, bin, GltfBuffer::embedded);
    files.push_back({path, c.fault});
  }
  auto write = [&](const std::string& name, const std::string& bytes, const std::string& fault) {
    std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
    files.push_back({dir + "/" + name, fault});
  };
  // A binary glTF cut short: its header declares more bytes than the file has.
  write_gltf(dir + "/whole.glb", shared_cube_document(), GltfBuffer::binary);
  std::ifstream in(dir + "/whole.glb", std::ios::binary);
  const std::string glb{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  write("truncated.glb", glb.substr(0, glb.size() - 7), "header declares");
  write("text.3ds", "not a 3ds file", "main chunk");
  write("long_chunk.3ds", std::string("\x4d\x4d\xff\xff\x00\x00", 6), "declares");
  write("no_collada.dae", "<?xml version=\"1.0\"?><nothing/>", "COLLADA");
  std::string deep = "<?xml version=\"1.0\"?><COLLADA>";
  for (int i = 0; i < 300; ++i) deep += "<node>";
  write("deep.dae", deep, "nested deeper");
  // Assimp 5.2.5 loops forever on a stray character in an index list (found by fuzz_scene_import).
  write("stray_character.dae", collada_tetrahedron("0 2 1 0 1 3 0 3 2` 1 2 3"), ":10: COLLADA: <p> holds a character that is no digit");
  std::string huge = collada_tetrahedron();
  huge.replace(huge.find("count=\"12\""), 10, "count=\"4000000000\"");
  write("huge_array_count.dae", huge, "declares count 4000000000 but holds 12 values");
  // Assimp 5.2.5 dereferences null on a <float_array> without its count (found by
  // fuzz_scene_import): no check foresees it; the child process that runs Assimp dies, raylab does not.
  std::string countless = collada_tetrahedron();
  countless.replace(countless.find("count=\"12\""), 10, "count:=\"12\"");
  write("float_array_without_count.dae", countless, "Assimp crashed (signal 11, Segmentation fault)");
  // Past raylab's checks Assimp itself refuses: its message, on one line.
  write("broken.dae", "<?xml version=\"1.0\"?>\n<COLLADA version=\"1.4.1\">\n<library_geometries>\n", "Assimp could not read");
  write("garbage.fbx", std::string("\0\1\2garbage", 10), "FBX");
  // Scopes nested deeper than Assimp's recursive FBX readers survive (200,000 levels crashed it).
  std::string braces = "; FBX 7.4.0 project file\n";
  for (int i = 0; i < 300; ++i) braces += "S: {";
  write("deep_ascii.fbx", braces, "nested deeper than 256");
  FbxRecord nest{"N", {}, {}};
  for (int i = 0; i < 300; ++i) nest = FbxRecord{"N", {}, {nest}};
  write("deep_binary.fbx", fbx_binary({nest}), "nested deeper than 256");
  // Assimp 5.2.5 aborts (an assertion) when a 64-bit record's property length wraps its pointer
  // (found by fuzz_scene_import): version 7500, one record "A" with one property 'C' whose
  // property list claims 2^64 - 16 bytes.
  std::string wrapping("Kaydara FBX Binary  \0\x1a\0", 23);
  auto u64 = [&](std::uint64_t v) { wrapping.append(reinterpret_cast<const char*>(&v), 8); };
  wrapping.append("\x4c\x1d\0\0", 4);
  const std::uint64_t record_end = 27 + 25 + 1 + 2;
  u64(record_end), u64(1), u64(~std::uint64_t{15});
  wrapping += "\x01" "A" "C\x01";
  wrapping.append(25 + 16, '\0');
  write("wrapping_property_length.fbx", wrapping, "run past the record's end at byte 55");
  // Assimp 5.2.5 aborts (an assertion) on a Model property of type KTime, valid as it is (found
  // by fuzz_scene_import), in a Model's own properties or in the Model template.
  write("ktime_ascii.fbx",
        "; FBX 7.4.0 project file\nDefinitions:  {\n  ObjectType: \"Model\" {\n    PropertyTemplate: \"FbxNode\" {\n"
        "      Properties70:  {\n        P: \"TimeSpanStart\", \"KTime\", \"Time\", \"\", 0\n      }\n    }\n  }\n}\n",
        "property 'TimeSpanStart' of type KTime");
  const FbxRecord property{"P", {"Tint", "ColorAndAlpha", "", "A"}, {}};
  write("color_and_alpha_binary.fbx",
        fbx_binary({{"Objects", {}, {{"Model", {"Model::a", "Mesh"}, {{"Properties70", {}, {property}}}}}}}),
        "property 'Tint' of type ColorAndAlpha");
  return files;
}

}  // namespace raylab::test
