#include "scene/mesh_io.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <istream>
#include <streambuf>
#include <string_view>
#include <vector>

#include "geometry/input_error.h"
#include "geometry/input_warning.h"
#include "scene/file_format.h"
#include "scene/openmesh_conversion.h"

namespace raylab {
namespace {

using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;
using TriMesh = OpenMeshTriMesh;

constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();
/// Warnings kept per file; further findings of the same kind are counted in one more line.
constexpr std::size_t kMaxWarningsPerFile = 8;

/// OpenMesh's IO manager is a process-wide singleton and its streams are global.
std::mutex& openmesh_mutex() {
  static std::mutex m;
  return m;
}

void silence_openmesh() {
  static std::once_flag once;
  std::call_once(once, [] {
    omerr().disable();
    omlog().disable();
    omout().disable();
  });
}

/// A read-only stream over text already in memory (OpenMesh's readers take std::istream).
class ViewStreambuf : public std::streambuf {
 public:
  explicit ViewStreambuf(std::string_view text) {
    char* p = const_cast<char*>(text.data());  // never written: no put area, no putback
    setg(p, p, p + text.size());
  }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
    const off_type from = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : egptr() - eback();
    const off_type to = from + off;
    if (to < 0 || to > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + to, egptr());
    return pos_type(to);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override { return seekoff(off_type(pos), std::ios_base::beg, which); }
};

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InputError(path + ": " + what); }
[[noreturn]] void fail_at(const std::string& path, std::size_t line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

std::string shown(std::string_view token) {
  std::string s(token.substr(0, 40));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + s + (token.size() > 40 ? "...'" : "'");
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

bool to_double(std::string_view s, double& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

bool to_int(std::string_view s, std::int64_t& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

/// A coordinate is accepted when it parses and stays finite after rounding to float.
bool finite_float(double d) { return std::isfinite(static_cast<float>(d)); }

std::string read_whole_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail(path, "no such file");
  if (!std::filesystem::is_regular_file(status)) fail(path, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open for reading");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail(path, "cannot determine the file size");
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) fail(path, "read error");
  return data;
}

/// Splits text into lines (with 1-based numbers), optionally cutting `#` comments.
class LineReader {
 public:
  LineReader(std::string_view text, bool strip_comments) : text_(text), strip_(strip_comments) {}
  /// Next line holding a token, split into tokens; false at the end of the text.
  bool next(std::vector<std::string_view>& tokens) {
    while (pos_ < text_.size()) {
      const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
      std::string_view line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      if (strip_) line = line.substr(0, line.find('#'));
      tokens.clear();
      std::size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
      }
      if (!tokens.empty()) return true;
    }
    return false;
  }
  std::size_t line() const { return line_; }
  std::size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }
  std::size_t offset() const { return std::min(pos_, text_.size()); }

 private:
  std::string_view text_;
  bool strip_;
  std::size_t pos_ = 0, line_ = 0;
};

/// Whitespace-separated tokens with line numbers.
class TokenReader {
 public:
  explicit TokenReader(std::string_view text, std::size_t first_line = 1) : text_(text), line_(first_line) {}
  bool next(std::string_view& token) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= text_.size()) return false;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    token = text_.substr(start, pos_ - start);
    return true;
  }
  std::size_t line() const { return line_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0, line_;
};

struct ScanResult {
  std::size_t faces = 0, triangles = 0, polygons = 0;
  std::size_t lines = 0, points = 0;  ///< OBJ `l` segments and `p` points, left out
  bool binary = false;  ///< a binary STL (OpenMesh's stream reader must be told)
};

// ---------------------------------------------------------------------------------------------
// OFF (Princeton Shape Benchmark / Geomview): [ST][C][N]OFF, "V F E", V vertex lines, F face lines.

/// Also writes `canonical`: the same mesh as plain OFF without comments, colours or normals, which
/// is what OpenMesh's OFF reader parses (it rejects comments before the header and misreads
/// per-face colours in files whose header does not announce them).
ScanResult scan_off(const std::string& path, std::string_view text, std::string& canonical) {
  LineReader lines(text, true);
  std::vector<std::string_view> tok;
  if (!lines.next(tok)) fail(path, "empty file");
  std::string_view magic = tok[0];
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF") fail_at(path, lines.line(), "not an OFF file (header " + shown(magic) + ")");
  std::string_view prefix = magic.substr(0, magic.size() - 3);
  if (prefix.starts_with("ST")) prefix.remove_prefix(2);
  if (prefix.starts_with("C")) prefix.remove_prefix(1);
  if (prefix.starts_with("N")) prefix.remove_prefix(1);
  if (!prefix.empty()) fail_at(path, lines.line(), "unsupported OFF variant " + shown(magic));
  std::size_t first = 1;
  if (tok.size() > 1 && tok[1] == "BINARY") fail_at(path, lines.line(), "binary OFF is not supported");
  if (tok.size() == 1) {
    if (!lines.next(tok)) fail(path, "missing the vertex and face counts after the header");
    first = 0;
  }
  if (tok.size() < first + 2) fail_at(path, lines.line(), "expected 'vertices faces [edges]' counts");
  std::int64_t nv = 0, nf = 0;
  if (!to_int(tok[first], nv) || nv < 0) fail_at(path, lines.line(), "bad vertex count " + shown(tok[first]));
  if (!to_int(tok[first + 1], nf) || nf < 0) fail_at(path, lines.line(), "bad face count " + shown(tok[first + 1]));
  const std::uint64_t rest = lines.remaining();
  if (static_cast<std::uint64_t>(nv) > kMaxVertices) fail_at(path, lines.line(), "vertex count " + std::to_string(nv) + " exceeds 2^32-1");
  // Each vertex line holds at least "0 0 0\n" (6 bytes), each face line "3 0 0 0\n" (8 bytes).
  if (static_cast<std::uint64_t>(nf) > rest || 6 * static_cast<std::uint64_t>(nv) + 8 * static_cast<std::uint64_t>(nf) > rest + 1)
    fail_at(path, lines.line(),
            "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces, more than the remaining " +
                std::to_string(rest) + " bytes can hold");
  canonical.reserve(text.size());
  canonical += "OFF\n" + std::to_string(nv) + " " + std::to_string(nf) + " 0\n";
  for (std::int64_t i = 0; i < nv; ++i) {
    if (!lines.next(tok)) fail(path, "unexpected end of file at vertex " + std::to_string(i) + " of " + std::to_string(nv));
    if (tok.size() < 3) fail_at(path, lines.line(), "vertex " + std::to_string(i) + ": expected 3 coordinates");
    for (int a = 0; a < 3; ++a) {
      double d;
      if (!to_double(tok[a], d)) fail_at(path, lines.line(), "vertex " + std::to_string(i) + ": bad coordinate " + shown(tok[a]));
      if (!finite_float(d)) fail_at(path, lines.line(), "vertex " + std::to_string(i) + " has a non-finite coordinate");
      canonical.append(tok[a]);
      canonical += a < 2 ? ' ' : '\n';
    }
  }
  ScanResult r;
  std::vector<std::int64_t> corners;
  for (std::int64_t f = 0; f < nf; ++f) {
    if (!lines.next(tok)) fail(path, "unexpected end of file at face " + std::to_string(f) + " of " + std::to_string(nf));
    std::int64_t n = 0;
    if (!to_int(tok[0], n)) fail_at(path, lines.line(), "face " + std::to_string(f) + ": bad corner count " + shown(tok[0]));
    if (n < 3) fail_at(path, lines.line(), "face " + std::to_string(f) + " has " + std::to_string(n) + " corners (at least 3 needed)");
    if (static_cast<std::uint64_t>(n) + 1 > tok.size())
      fail_at(path, lines.line(), "face " + std::to_string(f) + ": expected " + std::to_string(n) + " vertex indices");
    corners.clear();
    for (std::int64_t k = 1; k <= n; ++k) {
      std::int64_t idx;
      if (!to_int(tok[k], idx)) fail_at(path, lines.line(), "face " + std::to_string(f) + ": bad vertex index " + shown(tok[k]));
      if (idx < 0 || idx >= nv)
        fail_at(path, lines.line(),
                "face " + std::to_string(f) + ": vertex index " + std::to_string(idx) + " is outside [0, " + std::to_string(nv) + ")");
      corners.push_back(idx);
    }
    for (std::int64_t k = 0; k <= n; ++k) {
      canonical.append(tok[static_cast<std::size_t>(k)]);
      canonical += k < n ? ' ' : '\n';
    }
    ++r.faces;
    r.triangles += static_cast<std::size_t>(n - 2);
    if (n > 3) ++r.polygons;
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// OBJ (Wavefront): v / vt / vn / f lines; 1-based indices, negative ones relative to the end.
// `l` polylines (k vertices: k-1 segments) and `p` points are counted and left out.

ScanResult scan_obj(const std::string& path, std::string_view text) {
  LineReader lines(text, true);
  std::vector<std::string_view> tok;
  std::int64_t nv = 0, nvt = 0, nvn = 0;
  ScanResult r;
  auto resolve = [&](std::string_view s, std::int64_t count, const char* what) {
    std::int64_t idx;
    if (!to_int(s, idx)) fail_at(path, lines.line(), std::string("face ") + std::to_string(r.faces) + ": bad " + what + " index " + shown(s));
    const std::int64_t resolved = idx > 0 ? idx - 1 : count + idx;
    if (idx == 0 || resolved < 0 || resolved >= count)
      fail_at(path, lines.line(),
              std::string("face ") + std::to_string(r.faces) + ": " + what + " index " + std::to_string(idx) + " is out of range (" +
                  std::to_string(count) + " defined so far)");
    return resolved;
  };
  std::vector<std::int64_t> corners;
  while (lines.next(tok)) {
    const std::string_view key = tok[0];
    if (!std::all_of(key.begin(), key.end(), [](char ch) { return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_'; }))
      fail_at(path, lines.line(), "not an OBJ statement: " + shown(key));
    if (key == "v") {
      if (tok.size() < 4) fail_at(path, lines.line(), "vertex " + std::to_string(nv) + ": expected 3 coordinates");
      for (int a = 1; a <= 3; ++a) {
        double d;
        if (!to_double(tok[a], d)) fail_at(path, lines.line(), "vertex " + std::to_string(nv) + ": bad coordinate " + shown(tok[a]));
        if (!finite_float(d)) fail_at(path, lines.line(), "vertex " + std::to_string(nv) + " has a non-finite coordinate");
      }
      if (static_cast<std::uint64_t>(++nv) > kMaxVertices) fail_at(path, lines.line(), "more than 2^32-1 vertices");
    } else if (key == "l") {
      r.lines += tok.size() > 2 ? tok.size() - 2 : 0;
    } else if (key == "p") {
      r.points += tok.size() - 1;
    } else if (key == "vt") {
      ++nvt;
    } else if (key == "vn") {
      ++nvn;
    } else if (key == "f") {
      if (tok.size() < 4) fail_at(path, lines.line(), "face " + std::to_string(r.faces) + " has fewer than 3 corners");
      corners.clear();
      for (std::size_t k = 1; k < tok.size(); ++k) {
        std::string_view ref = tok[k];
        const std::size_t s1 = ref.find('/');
        corners.push_back(resolve(ref.substr(0, s1), nv, "vertex"));
        if (s1 != std::string_view::npos) {
          std::string_view rest = ref.substr(s1 + 1);
          const std::size_t s2 = rest.find('/');
          const std::string_view vt = rest.substr(0, s2);
          if (!vt.empty()) resolve(vt, nvt, "texture");
          if (s2 != std::string_view::npos) {
            const std::string_view vn = rest.substr(s2 + 1);
            if (!vn.empty()) resolve(vn, nvn, "normal");
          }
        }
      }
      ++r.faces;
      r.triangles += corners.size() - 2;
      if (corners.size() > 3) ++r.polygons;
    }
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// PLY (Turk, "The PLY Polygon File Format", 1994): a text header of elements and properties,
// then ASCII or binary (little- or big-endian) data.

struct PlyProperty {
  std::string name;
  bool is_list = false;
  int count_type = 0;  ///< byte size of a list's count (with its kind in count_kind)
  char count_kind = 'u';
  int type = 0;  ///< byte size of the scalar (or of a list's items)
  char kind = 'f';  ///< 'i' signed, 'u' unsigned, 'f' float
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
};

bool ply_type(std::string_view t, int& size, char& kind) {
  struct T { const char* name; int size; char kind; };
  static const T types[] = {{"char", 1, 'i'},   {"int8", 1, 'i'},    {"uchar", 1, 'u'},  {"uint8", 1, 'u'},
                            {"short", 2, 'i'},  {"int16", 2, 'i'},   {"ushort", 2, 'u'}, {"uint16", 2, 'u'},
                            {"int", 4, 'i'},    {"int32", 4, 'i'},   {"uint", 4, 'u'},   {"uint32", 4, 'u'},
                            {"float", 4, 'f'},  {"float32", 4, 'f'}, {"double", 8, 'f'}, {"float64", 8, 'f'}};
  for (const auto& x : types)
    if (t == x.name) { size = x.size; kind = x.kind; return true; }
  return false;
}

/// Reads one binary scalar as double.
class BinaryReader {
 public:
  BinaryReader(std::string_view data, std::size_t pos, bool big_endian) : data_(data), pos_(pos), big_(big_endian) {}
  bool read(int size, char kind, double& out) {
    if (size != 1 && size != 2 && size != 4 && size != 8) return false;
    if (pos_ + static_cast<std::size_t>(size) > data_.size()) return false;
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, static_cast<std::size_t>(size));
    pos_ += static_cast<std::size_t>(size);
    if (big_ != (std::endian::native == std::endian::big))
      for (int i = 0, j = size - 1; i < j; ++i, --j) std::swap(b[i], b[j]);
    switch (size * 4 + (kind == 'f' ? 2 : kind == 'i' ? 1 : 0)) {
      case 4: out = b[0]; break;
      case 5: out = static_cast<std::int8_t>(b[0]); break;
      case 8: { std::uint16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case 9: { std::int16_t v; std::memcpy(&v, b, 2); out = v; break; }
      case 16: { std::uint32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case 17: { std::int32_t v; std::memcpy(&v, b, 4); out = v; break; }
      case 18: { float v; std::memcpy(&v, b, 4); out = v; break; }
      case 34: { double v; std::memcpy(&v, b, 8); out = v; break; }
      default: return false;
    }
    return true;
  }
  std::size_t pos() const { return pos_; }

 private:
  std::string_view data_;
  std::size_t pos_;
  bool big_;
};

/// Also writes `canonical` when the header has lines that are no PLY keyword (an exporter's
/// "Created by ..." line): the file without them, which is what OpenMesh then reads; each such
/// line adds a warning.
ScanResult scan_ply(const std::string& path, std::string_view text, std::string& canonical, std::vector<std::string>& warnings) {
  LineReader lines(text, false);
  std::vector<std::string_view> tok;
  std::string header;  // the header's lines that are kept, tokens joined by single spaces
  auto keep = [&] {
    for (std::size_t k = 0; k < tok.size(); ++k) {
      header.append(tok[k]);
      header += k + 1 < tok.size() ? ' ' : '\n';
    }
  };
  if (!lines.next(tok) || tok[0] != "ply") fail(path, "not a PLY file (no 'ply' magic on the first line)");
  keep();
  if (!lines.next(tok) || tok[0] != "format" || tok.size() != 3 || tok[2] != "1.0") fail_at(path, lines.line(), "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
  keep();
  const std::string_view fmt = tok[1];
  if (fmt != "ascii" && fmt != "binary_little_endian" && fmt != "binary_big_endian")
    fail_at(path, lines.line(), "unknown PLY format " + shown(fmt));
  const bool ascii = fmt == "ascii";
  std::vector<PlyElement> elements;
  bool ended = false;
  std::size_t skipped = 0;
  while (lines.next(tok)) {
    const std::string_view key = tok[0];
    if (key != "comment" && key != "obj_info" && key != "end_header" && key != "element" && key != "property") {
      if (++skipped <= kMaxWarningsPerFile)
        warnings.push_back(path + ":" + std::to_string(lines.line()) + ": skipped a PLY header line that is no PLY keyword: " +
                           shown(key) + (tok.size() > 1 ? " ..." : ""));
      continue;
    }
    keep();
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") { ended = true; break; }
    if (key == "element") {
      std::int64_t count;
      if (tok.size() != 3 || !to_int(tok[2], count) || count < 0) fail_at(path, lines.line(), "expected 'element NAME COUNT'");
      elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(count), {}});
    } else if (key == "property") {
      if (elements.empty()) fail_at(path, lines.line(), "property before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!ply_type(tok[2], p.count_type, p.count_kind) || p.count_kind == 'f' || !ply_type(tok[3], p.type, p.kind))
          fail_at(path, lines.line(), "bad list property types");
        p.name = tok[4];
      } else if (tok.size() == 3) {
        if (!ply_type(tok[1], p.type, p.kind)) fail_at(path, lines.line(), "unknown property type " + shown(tok[1]));
        p.name = tok[2];
      } else {
        fail_at(path, lines.line(), "expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
      }
      elements.back().props.push_back(p);
    }
  }
  if (!ended) fail(path, "the header has no 'end_header'");
  if (skipped > kMaxWarningsPerFile)
    warnings.push_back(path + ": skipped " + std::to_string(skipped - kMaxWarningsPerFile) + " more such header lines");
  const std::size_t body = lines.offset();
  if (skipped > 0) {
    canonical.reserve(header.size() + text.size() - body);
    canonical = header;
    canonical.append(text.substr(body));
  }
  const std::uint64_t rest = text.size() - body;
  const PlyElement* vertex = nullptr;
  const PlyElement* face = nullptr;
  for (const auto& e : elements) {
    if (e.props.empty()) fail(path, "element '" + e.name + "' has no properties");
    std::uint64_t min_bytes = 0;
    for (const auto& p : e.props) min_bytes += ascii ? 2 : static_cast<std::uint64_t>(p.is_list ? p.count_type : p.type);
    if (e.count > rest || e.count * min_bytes > rest + 1)
      fail(path, "header declares " + std::to_string(e.count) + " '" + e.name + "' elements, more than the remaining " +
                     std::to_string(rest) + " bytes can hold");
    if (e.name == "vertex") vertex = &e;
    if (e.name == "face") face = &e;
  }
  if (!vertex) fail(path, "no 'vertex' element");
  if (vertex->count > kMaxVertices) fail(path, "vertex count exceeds 2^32-1");
  int axis_of[3] = {-1, -1, -1};
  for (std::size_t k = 0; k < vertex->props.size(); ++k)
    for (int a = 0; a < 3; ++a)
      if (!vertex->props[k].is_list && vertex->props[k].name == std::string(1, static_cast<char>('x' + a))) axis_of[a] = static_cast<int>(k);
  if (axis_of[0] < 0 || axis_of[1] < 0 || axis_of[2] < 0) fail(path, "the vertex element lacks an x, y or z property");
  int index_prop = -1;
  if (face) {
    for (std::size_t k = 0; k < face->props.size(); ++k)
      if (face->props[k].is_list && (face->props[k].name == "vertex_indices" || face->props[k].name == "vertex_index"))
        index_prop = static_cast<int>(k);
    if (index_prop < 0) fail(path, "the face element has no 'vertex_indices' list");
    if (face->props[static_cast<std::size_t>(index_prop)].kind == 'f') fail(path, "face vertex indices must be integers");
  }

  ScanResult r;
  TokenReader tokens(text.substr(body), lines.line() + 1);
  BinaryReader bin(text, body, fmt == "binary_big_endian");
  std::string_view t;
  auto value = [&](int size, char kind, const std::string& where) -> double {
    double d = 0;
    if (ascii) {
      if (!tokens.next(t)) fail(path, "unexpected end of file in " + where);
      if (kind == 'f') {
        if (!to_double(t, d)) fail_at(path, tokens.line(), where + ": bad number " + shown(t));
      } else {
        std::int64_t i;
        if (!to_int(t, i)) fail_at(path, tokens.line(), where + ": bad integer " + shown(t));
        d = static_cast<double>(i);
      }
    } else if (!bin.read(size, kind, d)) {
      fail(path, "unexpected end of file in " + where);
    }
    return d;
  };
  for (const auto& e : elements) {
    const bool is_vertex = &e == vertex, is_face = &e == face;
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::string where = e.name + " " + std::to_string(i);
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& p = e.props[k];
        if (!p.is_list) {
          const double d = value(p.type, p.kind, where);
          if (is_vertex && (static_cast<int>(k) == axis_of[0] || static_cast<int>(k) == axis_of[1] || static_cast<int>(k) == axis_of[2]) &&
              !finite_float(d))
            fail(path, "vertex " + std::to_string(i) + " has a non-finite coordinate");
          continue;
        }
        const double n = value(p.count_type, p.count_kind, where);
        if (n < 0 || n > static_cast<double>(rest)) fail(path, where + ": bad list length " + std::to_string(static_cast<std::int64_t>(n)));
        const bool indices = is_face && static_cast<int>(k) == index_prop;
        if (indices && n < 3) fail(path, "face " + std::to_string(i) + " has " + std::to_string(static_cast<int>(n)) + " corners (at least 3 needed)");
        for (std::int64_t j = 0; j < static_cast<std::int64_t>(n); ++j) {
          const double idx = value(p.type, p.kind, where);
          if (indices && !(idx >= 0 && idx < static_cast<double>(vertex->count)))
            fail(path, "face " + std::to_string(i) + ": vertex index " + std::to_string(static_cast<std::int64_t>(idx)) + " is outside [0, " +
                           std::to_string(vertex->count) + ")");
        }
        if (indices) {
          ++r.faces;
          r.triangles += static_cast<std::size_t>(n) - 2;
          if (n > 3) ++r.polygons;
        }
      }
    }
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// STL: binary (80-byte header, uint32 count, 50 bytes per triangle) or ASCII (solid/facet/...).

std::uint32_t le_u32(const char* p) {
  unsigned char b[4];
  std::memcpy(b, p, 4);
  return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 | static_cast<std::uint32_t>(b[2]) << 16 |
         static_cast<std::uint32_t>(b[3]) << 24;
}

float le_f32(const char* p) {
  const std::uint32_t u = le_u32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

ScanResult scan_stl(const std::string& path, std::string_view text) {
  ScanResult r;
  if (text.size() >= 84) {
    const std::uint64_t n = le_u32(text.data() + 80);
    if (84 + 50 * n == text.size()) {
      for (std::uint64_t i = 0; i < n; ++i) {
        const char* tri = text.data() + 84 + 50 * i + 12;
        for (int k = 0; k < 9; ++k)
          if (!std::isfinite(le_f32(tri + 4 * k))) fail(path, "triangle " + std::to_string(i) + " has a non-finite coordinate");
      }
      r.faces = r.triangles = n;
      r.binary = true;
      return r;
    }
  }
  reject_utf16_text(path, text);
  std::size_t lead = 0;
  while (lead < text.size() && is_space(text[lead])) ++lead;
  if (text.substr(lead, 5) != "solid") {
    if (text.size() < 84) fail(path, "neither ASCII STL (no 'solid') nor binary STL (shorter than the 84-byte header)");
    fail(path, "neither ASCII STL (no 'solid') nor binary STL (its header declares " + std::to_string(le_u32(text.data() + 80)) +
                   " triangles, 84 + 50 x that bytes, but the file has " + std::to_string(text.size()) + ")");
  }
  TokenReader tokens(text);
  std::string_view t;
  auto expect = [&](std::string_view word) {
    if (!tokens.next(t)) fail(path, "unexpected end of file, expected '" + std::string(word) + "'");
    if (t != word) fail_at(path, tokens.line(), "expected '" + std::string(word) + "', found " + shown(t));
  };
  auto number = [&](const std::string& where, bool coordinate) {
    if (!tokens.next(t)) fail(path, "unexpected end of file in " + where);
    double d;
    if (!to_double(t, d)) fail_at(path, tokens.line(), where + ": bad number " + shown(t));
    if (coordinate && !finite_float(d)) fail_at(path, tokens.line(), where + " has a non-finite coordinate");
  };
  // Exporters write several `solid NAME ... endsolid NAME` blocks, some of them empty, into one
  // file: all of them make one mesh. A name is the rest of its solid/endsolid line; text
  // between solids is ignored, as OpenMesh's reader ignores it.
  bool in_solid = false;
  std::size_t name_line = 0;
  while (tokens.next(t)) {
    if (tokens.line() == name_line) continue;
    if (t == "solid" || t == "endsolid") {
      in_solid = t == "solid";
      name_line = tokens.line();
      continue;
    }
    if (t != "facet") {
      if (!in_solid) continue;
      fail_at(path, tokens.line(), "expected 'facet' or 'endsolid', found " + shown(t));
    }
    const std::string where = "triangle " + std::to_string(r.faces);
    expect("normal");
    for (int k = 0; k < 3; ++k) number(where + " normal", false);
    expect("outer");
    expect("loop");
    for (int v = 0; v < 3; ++v) {
      expect("vertex");
      for (int k = 0; k < 3; ++k) number(where, true);
    }
    expect("endloop");
    expect("endfacet");
    ++r.faces;
    ++r.triangles;
  }
  return r;
}

// ---------------------------------------------------------------------------------------------

TriangleMesh from_openmesh(const std::string& path, const PolyMesh& m, MeshLoadReport& report) {
  if (m.n_vertices() > kMaxVertices) fail(path, "more than 2^32-1 vertices");
  TriangleMesh out;
  out.vertices.reserve(m.n_vertices());
  for (const auto vh : m.vertices()) {
    const auto& p = m.point(vh);
    const Vec3f v(p[0], p[1], p[2]);
    if (!is_finite(v)) fail(path, "vertex " + std::to_string(vh.idx()) + " has a non-finite coordinate");
    out.vertices.push_back(v);
  }
  std::vector<std::uint32_t> corners;
  for (const auto fh : m.faces()) {
    corners.clear();
    for (const auto vh : m.fv_range(fh)) corners.push_back(static_cast<std::uint32_t>(vh.idx()));
    if (corners.size() < 3) continue;
    if (corners.size() > 3) ++report.polygons_triangulated;
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) out.triangles.push_back({corners[0], corners[k], corners[k + 1]});
  }
  for (std::size_t t = 0; t < out.size(); ++t)
    if (is_degenerate_exact(out.vertex(t, 0), out.vertex(t, 1), out.vertex(t, 2))) ++report.zero_area_triangles;
  return out;
}

}  // namespace

bool has_mesh_extension(const std::string& path) {
  const auto f = format_by_extension(path);
  return f && file_format_doc(*f).library == FileLibrary::openmesh;
}

TriangleMesh load_mesh(const std::string& path, MeshLoadReport* report) {
  const FileFormat format = detect_file_format(path);
  const FileFormatDoc& doc = file_format_doc(format);
  if (doc.library != FileLibrary::openmesh)
    fail(path, doc.name + " is a scene format read by Assimp (load it as a scene, file:PATH), not one mesh");
  MeshLoadReport local;
  ScanResult scan;
  std::string text = read_whole_file(path);
  if (text.empty()) fail(path, "empty file");
  std::string canonical;  // what OpenMesh reads instead of `text`, when not empty
  switch (format) {
    case FileFormat::off: reject_utf16_text(path, text); scan = scan_off(path, text, canonical); break;
    case FileFormat::obj: reject_utf16_text(path, text); scan = scan_obj(path, text); break;
    case FileFormat::ply: reject_utf16_text(path, text); scan = scan_ply(path, text, canonical, local.warnings); break;
    case FileFormat::stl: scan = scan_stl(path, text); break;
    default: break;
  }
  if (scan.triangles == 0 && scan.lines + scan.points > 0)
    fail(path, "no triangles (" + std::to_string(scan.lines) + " lines, " + std::to_string(scan.points) + " points left out)");
  if (scan.triangles == 0) fail(path, "no triangles");
  local.lines = scan.lines;
  local.points = scan.points;
  if (scan.lines + scan.points > 0)
    local.warnings.push_back(path + ": left out " + std::to_string(scan.lines) + " lines and " + std::to_string(scan.points) +
                             " points (raylab traces triangles)");
  if (!canonical.empty()) std::string().swap(text);

  silence_openmesh();
  PolyMesh m;
  {
    std::lock_guard lock(openmesh_mutex());
    OpenMesh::IO::Options opt;
    if (scan.binary) opt += OpenMesh::IO::Options::Binary;
    ViewStreambuf buffer(canonical.empty() ? std::string_view(text) : std::string_view(canonical));
    std::istream in(&buffer);
    // OpenMesh picks its reader by this name's extension; the file itself may have none.
    if (!OpenMesh::IO::read_mesh(m, in, doc.extensions.front(), opt)) fail(path, "OpenMesh could not read the file");
  }
  local.faces_read = scan.faces;
  TriangleMesh mesh = from_openmesh(path, m, local);
  local.faces_skipped = scan.faces > m.n_faces() ? scan.faces - m.n_faces() : 0;
  if (mesh.size() == 0) fail(path, "no triangles");
  for (const auto& w : local.warnings) warn_input(w);
  if (report) *report = std::move(local);
  return mesh;
}

void save_mesh(const TriangleMesh& mesh, const std::string& path, bool binary) {
  if (!has_mesh_extension(path)) fail(path, "unknown mesh format (expected .off, .obj, .ply or .stl)");
  silence_openmesh();
  TriMesh m = to_openmesh(mesh);
  OpenMesh::IO::Options opt;
  if (binary) opt += OpenMesh::IO::Options::Binary;
  std::lock_guard lock(openmesh_mutex());
  if (!OpenMesh::IO::write_mesh(m, path, opt)) fail(path, "OpenMesh could not write the file");
}

}  // namespace raylab
