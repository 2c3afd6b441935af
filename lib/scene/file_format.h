#pragma once
/// The scene file formats raylab reads, the library that reads each, and how a file's format is
/// told: by its extension (any case), or, for a file without an extension, by its content.
///
/// OpenMesh reads one mesh per file (mesh_io.h): OFF, OBJ (its groups become one mesh), PLY and
/// STL. Assimp reads scenes with a node tree (scene_import.h): glTF 2.0 (.gltf, .glb), FBX,
/// COLLADA (.dae) and 3DS.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raylab {

enum class FileFormat { off, obj, ply, stl, gltf, glb, fbx, collada, three_ds };

enum class FileLibrary { openmesh, assimp };

struct FileFormatDoc {
  FileFormat format;
  std::string name;                     ///< e.g. "glTF 2.0, binary"
  std::vector<std::string> extensions;  ///< lower case, with the dot
  FileLibrary library;
};

/// Every format, in listing order (OpenMesh's first).
const std::vector<FileFormatDoc>& file_formats();
const FileFormatDoc& file_format_doc(FileFormat format);
/// "OpenMesh" or "Assimp".
std::string library_name(FileLibrary library);

/// The format named by the extension of `path`; nullopt for no or an unknown extension.
std::optional<FileFormat> format_by_extension(const std::string& path);

/// True when `path` has no extension (std::filesystem's notion: "scene", "dir.d/scene", ".hidden").
bool has_no_extension(const std::string& path);

/// The format of a file from its first bytes `head` (up to 4 KiB, or the whole file) and its
/// size: binary glTF ("glTF" magic), binary STL (84 + 50·n bytes for the n its header
/// declares; tested before ASCII, since binary headers often start with "solid"), 3DS (main
/// chunk 0x4D4D spanning the file), binary FBX ("Kaydara FBX Binary"), then text after
/// leading white space and a UTF-8 byte-order mark: "ply", [ST][C][N]OFF (after '#' comment
/// lines), "solid", '{' (glTF JSON), "; FBX", "<?xml"/"<COLLADA" with a COLLADA element, and an
/// OBJ statement (v, vt, vn, vp, f, o, g, s, l, p, mtllib, usemtl) after '#' comment lines.
/// nullopt when none matches.
std::optional<FileFormat> format_by_content(std::string_view head, std::uint64_t size);

/// UTF-16 text: a byte-order mark (FF FE or FE FF), or, in the first 256 bytes, a NUL at every
/// odd (little-endian) or every even (big-endian) position and nowhere else.
bool looks_like_utf16(std::string_view head);

/// Throws InputError naming `path` when `head` (a file's first bytes) looks_like_utf16.
void reject_utf16_text(const std::string& path, std::string_view head);

/// The format of the file at `path`: by its extension when it has one, by its content
/// (format_by_content) when it has none. Throws InputError naming the file when it is missing,
/// not a regular file or unreadable, its extension is not a known format, or (no extension) it
/// is empty, UTF-16 text, or of no recognised content.
FileFormat detect_file_format(const std::string& path);

/// The extensions of every format, for messages: ".off, .obj, ..., .3ds".
std::string known_extensions();

}  // namespace raylab
