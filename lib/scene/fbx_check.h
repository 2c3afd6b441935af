#pragma once
/// What raylab checks in an FBX file before Assimp 5.2.5 parses it, for faults that crash
/// Assimp rather than fail:
/// - its readers recurse once per nesting level of the file's records (binary FBX) or braces
///   (ASCII FBX) and overflow the stack on deep nesting (a 1.4 MB file of 200,000 nested scopes
///   crashed it), so nesting is capped at kMaxFbxDepth levels;
/// - its converter aborts (an assertion Debian's build keeps) on a Model property of type KTime
///   or ColorAndAlpha (found by fuzz_scene_import; valid files may hold one), so such a file is
///   refused with a message that says so.
/// Both are measured without recursion:
/// - binary FBX ("Kaydara FBX Binary", version at byte 23; 64-bit record headers from version
///   7500): records are walked by their end offsets; a walk that meets an offset outside the
///   file stops there and leaves the fault to Assimp's own checks;
/// - ASCII FBX: '{' and '}' outside ';' comments and quoted strings.
#include <string>
#include <string_view>

namespace raylab {

inline constexpr std::size_t kMaxFbxDepth = 256;

/// Checks the FBX file at `path` whose whole content is `data`; throws InputError naming the
/// file for either fault.
void check_fbx(const std::string& path, std::string_view data);

}  // namespace raylab
