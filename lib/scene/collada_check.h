#pragma once
/// What raylab checks in a COLLADA file (Khronos COLLADA 1.4/1.5) before Assimp parses it, where
/// Assimp 5.2.5 trusts the file (found by fuzz_scene_import):
/// - XML elements nested at most kMaxColladaDepth deep (its reader recurses through nodes);
/// - index lists (<p>, <vcount>, <v>, <h>) hold only decimal digits and white space: Assimp's
///   <p> reader loops forever, growing its index array, on any other character;
/// - a `count` attribute of an array (<float_array>, <int_array>, ...) or a primitive element
///   (<triangles>, <polylist>, ...) is no larger than the numbers it holds, and an <accessor>'s
///   count times stride no larger than the file: Assimp reserves memory by these counts before
///   it reads a single value.
#include <string>
#include <string_view>

namespace raylab {

inline constexpr std::size_t kMaxColladaDepth = 256;

/// Checks the COLLADA text `data` of the file at `path`; throws InputError naming the file, the
/// element (and its line) and the fault.
void check_collada(const std::string& path, std::string_view data);

}  // namespace raylab
