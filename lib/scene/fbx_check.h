#pragma once
/// What raylab checks in an FBX file before Assimp 5.2.5 parses it, for faults that crash
/// Assimp rather than fail:
/// - its readers recurse once per nesting level of the file's records (binary FBX) or braces
///   (ASCII FBX) and overflow the stack on deep nesting (a 1.4 MB file of 200,000 nested scopes
///   crashed it), so nesting is capped at kMaxFbxDepth levels;
/// - its converter aborts (an assertion Debian's build keeps) on a Model property of type KTime
///   or ColorAndAlpha (found by fuzz_scene_import; valid files may hold one), so such a file is
///   refused with a message that says so;
/// - its binary tokenizer aborts (an assertion) when a 64-bit record's property length wraps its
///   pointer (found by fuzz_scene_import), so a binary record that ends outside the file, or
///   whose name and property list run past its own end, is refused (Assimp refuses such a file
///   too, where it does not abort).
/// All are measured without recursion:
/// - binary FBX ("Kaydara FBX Binary", version at byte 23; 64-bit record headers from version
///   7500): records are walked by their end offsets;
/// - ASCII FBX: '{' and '}' outside ';' comments and quoted strings.
#include <string>
#include <string_view>

namespace raylab {

inline constexpr std::size_t kMaxFbxDepth = 256;

/// Checks the FBX file at `path` whose whole content is `data`; throws InputError naming the
/// file for any of these faults.
void check_fbx(const std::string& path, std::string_view data);

}  // namespace raylab
