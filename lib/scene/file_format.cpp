#include "scene/file_format.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "geometry/input_error.h"
#include "scene/little_endian.h"

namespace raylab {
namespace {

constexpr std::size_t kHeadBytes = 4096;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

/// The first white-space-separated token of `line`.
std::string_view first_token(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && space(line[i])) ++i;
  std::size_t j = i;
  while (j < line.size() && !space(line[j])) ++j;
  return line.substr(i, j - i);
}

bool is_off_magic(std::string_view token) {
  if (!token.ends_with("OFF")) return false;
  token.remove_suffix(3);
  if (token.starts_with("ST")) token.remove_prefix(2);
  if (token.starts_with("C")) token.remove_prefix(1);
  if (token.starts_with("N")) token.remove_prefix(1);
  return token.empty();
}

/// The first token after blank and '#' comment lines (OFF and OBJ allow comments before their
/// first statement); empty when the text ends first, or the token's line does not end in the
/// text (the head may cut a file mid-line).
std::string_view first_statement(std::string_view text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view token = first_token(text.substr(pos, end - pos));
    pos = end + 1;
    if (token.empty() || token.front() == '#') continue;
    return end == text.size() ? std::string_view() : token;
  }
  return {};
}

bool is_obj_statement(std::string_view token) {
  static const char* const kStatements[] = {"v", "vt", "vn", "vp", "f", "o", "g", "s", "l", "p", "mtllib", "usemtl"};
  return std::any_of(std::begin(kStatements), std::end(kStatements), [&](const char* k) { return token == k; });
}

}  // namespace

const std::vector<FileFormatDoc>& file_formats() {
  static const std::vector<FileFormatDoc> formats = {
      {FileFormat::off, "OFF (Geomview, Princeton Shape Benchmark)", {".off"}, FileLibrary::openmesh},
      {FileFormat::obj, "Wavefront OBJ (groups become one mesh)", {".obj"}, FileLibrary::openmesh},
      {FileFormat::ply, "PLY, ASCII or binary", {".ply"}, FileLibrary::openmesh},
      {FileFormat::stl, "STL, ASCII or binary", {".stl"}, FileLibrary::openmesh},
      {FileFormat::gltf, "glTF 2.0 (JSON, buffers embedded or in files beside it)", {".gltf"}, FileLibrary::assimp},
      {FileFormat::glb, "glTF 2.0, binary", {".glb"}, FileLibrary::assimp},
      {FileFormat::fbx, "Autodesk FBX, binary or ASCII", {".fbx"}, FileLibrary::assimp},
      {FileFormat::collada, "COLLADA", {".dae"}, FileLibrary::assimp},
      {FileFormat::three_ds, "3D Studio", {".3ds"}, FileLibrary::assimp},
  };
  return formats;
}

const FileFormatDoc& file_format_doc(FileFormat format) {
  for (const auto& f : file_formats())
    if (f.format == format) return f;
  throw std::logic_error("file_format_doc: unknown format");
}

std::string library_name(FileLibrary library) { return library == FileLibrary::openmesh ? "OpenMesh" : "Assimp"; }

std::string known_extensions() {
  std::string out;
  for (const auto& f : file_formats())
    for (const auto& e : f.extensions) out += (out.empty() ? "" : ", ") + e;
  return out;
}

std::optional<FileFormat> format_by_extension(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  for (const auto& f : file_formats())
    if (std::find(f.extensions.begin(), f.extensions.end(), ext) != f.extensions.end()) return f.format;
  return std::nullopt;
}

bool has_no_extension(const std::string& path) { return std::filesystem::path(path).extension().empty(); }

bool looks_like_utf16(std::string_view head) {
  if (head.size() >= 2 && ((head[0] == '\xff' && head[1] == '\xfe') || (head[0] == '\xfe' && head[1] == '\xff'))) return true;
  const std::size_t n = std::min<std::size_t>(head.size(), 256) & ~std::size_t{1};
  if (n < 4) return false;
  std::size_t nul_even = 0, nul_odd = 0;
  for (std::size_t i = 0; i < n; ++i) (i % 2 ? nul_odd : nul_even) += head[i] == '\0';
  return (nul_odd == n / 2 && nul_even == 0) || (nul_even == n / 2 && nul_odd == 0);
}

std::optional<FileFormat> format_by_content(std::string_view head, std::uint64_t size) {
  if (head.starts_with("glTF")) return FileFormat::glb;
  if (head.starts_with("Kaydara FBX Binary")) return FileFormat::fbx;
  if (head.size() >= 84 && 84 + 50 * static_cast<std::uint64_t>(read_le(head, 80, 4)) == size) return FileFormat::stl;
  if (head.size() >= 6 && head[0] == '\x4d' && head[1] == '\x4d' && read_le(head, 2, 4) == size) return FileFormat::three_ds;
  std::string_view text = head;
  if (text.starts_with("\xef\xbb\xbf")) text.remove_prefix(3);
  while (!text.empty() && space(text.front())) text.remove_prefix(1);
  const std::string_view token = first_token(text.substr(0, text.find('\n')));
  const std::string_view statement = first_statement(text);
  if (token == "ply") return FileFormat::ply;
  if (is_off_magic(statement)) return FileFormat::off;
  if (token == "solid") return FileFormat::stl;
  if (text.starts_with("{")) return FileFormat::gltf;
  if (text.starts_with("; FBX")) return FileFormat::fbx;
  if ((text.starts_with("<?xml") || text.starts_with("<COLLADA")) && text.find("<COLLADA") != std::string_view::npos)
    return FileFormat::collada;
  if (is_obj_statement(statement)) return FileFormat::obj;
  return std::nullopt;
}

void reject_utf16_text(const std::string& path, std::string_view head) {
  if (looks_like_utf16(head))
    throw InputError(path + ": the file is UTF-16 text; raylab reads ASCII or UTF-8 (convert it, e.g. with iconv -f UTF-16 -t UTF-8)");
}

FileFormat detect_file_format(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw InputError(path + ": no such file");
  if (!std::filesystem::is_regular_file(status)) throw InputError(path + ": not a regular file");
  if (!has_no_extension(path)) {
    if (const auto f = format_by_extension(path)) return *f;
    throw InputError(path + ": unknown scene file format (expected " + known_extensions() + ", or no extension)");
  }
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot determine the file size");
  if (size == 0) throw InputError(path + ": empty file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open for reading");
  std::string head(std::min<std::uint64_t>(size, kHeadBytes), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (static_cast<std::size_t>(in.gcount()) != head.size()) throw InputError(path + ": read error");
  reject_utf16_text(path, head);
  if (const auto f = format_by_content(head, size)) return *f;
  throw InputError(path + ": no extension, and the content is none of the formats raylab reads (" + known_extensions() + ")");
}

}  // namespace raylab
