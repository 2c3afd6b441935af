#pragma once
/// What raylab checks in a glTF 2.0 file (Khronos glTF 2.0 specification) before Assimp parses
/// it, so that malformed files fail with one clear line instead of reaching a parser that trusts
/// them (Assimp's glTF reader recurses through JSON and the node tree, and sizes its arrays by
/// accessor counts):
/// - binary glTF: the 12-byte header ("glTF", version 2, total length = file size) and chunk
///   lengths within the file, the first chunk JSON;
/// - JSON nested at most kMaxGltfJsonDepth deep, and valid; asset.version "2.x";
/// - buffers: a data: URI, the binary chunk (GLB buffer 0), or a file beside the glTF that
///   exists (a missing .bin is named), is a regular file and holds byteLength bytes;
/// - buffer views and accessors (sparse ones too) within their buffers; accessor types, counts
///   (an accessor without buffer view holds at most kMaxGltfZeroAccessorBytes of zeros);
/// - every index between objects (nodes, meshes, accessors, buffer views, cameras, skins,
///   images, textures, samplers, materials, scenes) within range;
/// - the node graph a forest (no node with two parents, no cycle: "recursive nodes"), at most
///   kMaxGltfNodeDepth deep; node matrices and TRS values finite.
#include <cstdint>
#include <string>
#include <string_view>

namespace raylab {

inline constexpr int kMaxGltfJsonDepth = 64;
inline constexpr int kMaxGltfNodeDepth = 256;
inline constexpr std::uint64_t kMaxGltfZeroAccessorBytes = std::uint64_t{1} << 28;

/// Checks the glTF file at `path` whose whole content is `data` (`binary`: a .glb). External
/// buffers are looked up beside `path` and must be at most `max_file_bytes` long. Throws
/// InputError naming the file and the fault.
void check_gltf(const std::string& path, std::string_view data, bool binary, std::uint64_t max_file_bytes);

}  // namespace raylab
