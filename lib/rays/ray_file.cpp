#include "rays/ray_file.h"

#include <charconv>
#include <stdexcept>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "geometry/input_error.h"
#include "scene/scene.h"

namespace raylab {
namespace {

constexpr std::size_t kMaxLineLength = 4096;
constexpr float kInf = std::numeric_limits<float>::infinity();

/// A buffered writer that reports failure as InputError naming the file.
class Writer {
 public:
  explicit Writer(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb"), &std::fclose) {
    if (!file_) throw InputError(path + ": cannot open for writing");
    buffer_.reserve(kFlushSize + 256);
  }
  void put(std::string_view s) {
    buffer_.append(s);
    if (buffer_.size() >= kFlushSize) flush();
  }
  void put(float x) {
    char tmp[32];
    const auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, x);
    buffer_.append(tmp, end);
  }
  void put(std::size_t x) {
    char tmp[32];
    const auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, x);
    buffer_.append(tmp, end);
  }
  void close() {
    flush();
    if (std::fflush(file_.get()) != 0 || std::ferror(file_.get())) throw InputError(path_ + ": write failed");
  }

 private:
  void flush() {
    if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_.get()) != buffer_.size())
      throw InputError(path_ + ": write failed");
    buffer_.clear();
  }
  static constexpr std::size_t kFlushSize = 1 << 16;
  std::string path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
  std::string buffer_;
};

/// Splits at any run of the separators.
std::vector<std::string_view> split(std::string_view line, std::string_view separators) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    const std::size_t start = line.find_first_not_of(separators, i);
    if (start == std::string_view::npos) break;
    std::size_t end = line.find_first_of(separators, start);
    if (end == std::string_view::npos) end = line.size();
    out.push_back(line.substr(start, end - start));
    i = end;
  }
  return out;
}

/// Parses a whole field as a float (from_chars accepts decimal, `inf` and `nan`); returns a
/// fault description or an empty string.
std::string parse_float(std::string_view s, float& out) {
  const char* end = s.data() + s.size();
  const auto [p, ec] = std::from_chars(s.data(), end, out, std::chars_format::general);
  if (ec == std::errc() && p == end) return std::isnan(out) ? "NaN is not allowed" : "";
  std::string fault = "'";
  fault += s;
  fault += ec == std::errc::result_out_of_range ? "' is outside the float range" : "' is not a number";
  return fault;
}

class LineReader {
 public:
  explicit LineReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw InputError(path + ": cannot open");
  }
  /// Next line that is neither blank nor a comment; false at the end of the file.
  bool next(std::string& line) {
    // istream::getline into a fixed buffer, so a file without line breaks cannot exhaust memory.
    for (;;) {
      in_.getline(buffer_, sizeof buffer_);
      if (in_.bad()) throw InputError(path_ + ": read failed");
      if (in_.fail()) {
        if (in_.eof()) return false;
        ++number_;
        throw fault("line longer than " + std::to_string(kMaxLineLength) + " characters");
      }
      ++number_;
      const auto count = static_cast<std::size_t>(in_.gcount());
      line.assign(buffer_, in_.eof() ? count : count - 1);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::size_t first = line.find_first_not_of(" \t");
      if (first != std::string::npos && line[first] != '#') return true;
      if (in_.eof()) return false;
    }
  }
  InputError fault(const std::string& what) const {
    return InputError(path_ + ":" + std::to_string(number_) + ": " + what);
  }

 private:
  std::string path_;
  std::ifstream in_;
  std::size_t number_ = 0;
  char buffer_[kMaxLineLength + 1];
};

}  // namespace

void write_rays(const std::string& path, const std::vector<Ray>& rays) {
  Writer w(path);
  w.put("# raylab rays: ox oy oz dx dy dz tmin tmax\n");
  for (const Ray& r : rays) {
    const float v[8] = {r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax};
    for (int i = 0; i < 8; ++i) {
      w.put(v[i]);
      w.put(i == 7 ? "\n" : " ");
    }
  }
  w.close();
}

std::vector<Ray> read_rays(const std::string& path) {
  static const char* const kNames[8] = {"ox", "oy", "oz", "dx", "dy", "dz", "tmin", "tmax"};
  LineReader reader(path);
  std::vector<Ray> rays;
  std::string line;
  while (reader.next(line)) {
    const auto fields = split(line, " \t");
    if (fields.size() != 8)
      throw reader.fault("expected 8 numbers (ox oy oz dx dy dz tmin tmax), found " + std::to_string(fields.size()));
    float v[8];
    for (int i = 0; i < 8; ++i) {
      const std::string fault = parse_float(fields[i], v[i]);
      if (!fault.empty()) throw reader.fault(std::string(kNames[i]) + ": " + fault);
      if (std::isinf(v[i]) && !(i == 7 && v[i] > 0.0f))
        throw reader.fault(std::string(kNames[i]) + " is infinite (only tmax may be inf)");
    }
    const Ray r{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, v[6], v[7]};
    if (r.dir == Vec3f(0.0f)) throw reader.fault("the direction is zero");
    if (!(r.tmin >= 0.0f)) throw reader.fault("tmin is negative");
    if (!(r.tmin <= r.tmax)) throw reader.fault("tmin is greater than tmax");
    if (rays.size() == kMaxRaysPerFile)
      throw reader.fault("more than " + std::to_string(kMaxRaysPerFile) + " rays");
    rays.push_back(r);
  }
  if (rays.empty()) throw InputError(path + ": no rays");
  return rays;
}

void write_hits_csv(const std::string& path, const std::vector<Hit>& hits, const Scene* scene,
                    const std::vector<std::string>* contacts) {
  if (contacts && contacts->size() != hits.size()) throw std::invalid_argument("write_hits_csv: one contact per hit");
  const bool with_base = scene && scene->instanced();
  bool instanced = with_base;
  for (const Hit& h : hits) instanced = instanced || h.instance != kInvalidId;
  if (with_base)
    for (const Hit& h : hits)
      if (h.valid() && h.instance != kInvalidId && h.instance >= scene->instances.size())
        throw std::logic_error("write_hits_csv: a hit names instance " + std::to_string(h.instance) + " the scene lacks");
  Writer w(path);
  w.put(with_base ? "ray,prim,t,u,v,instance,base" : instanced ? "ray,prim,t,u,v,instance" : "ray,prim,t,u,v");
  w.put(contacts ? ",contact\n" : "\n");
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const Hit& h = hits[i];
    w.put(i);
    const auto end_row = [&] {
      if (contacts) {
        w.put(",");
        w.put((*contacts)[i].c_str());
      }
      w.put("\n");
    };
    if (!h.valid()) {
      w.put(with_base ? ",-1,inf,0,0,-1,-1" : instanced ? ",-1,inf,0,0,-1" : ",-1,inf,0,0");
      end_row();
      continue;
    }
    w.put(",");
    w.put(static_cast<std::size_t>(h.prim));
    for (float x : {h.t, h.u, h.v}) {
      w.put(",");
      w.put(x);
    }
    if (instanced) {
      w.put(",");
      if (h.instance == kInvalidId) w.put("-1");
      else w.put(static_cast<std::size_t>(h.instance));
    }
    if (with_base) {
      w.put(",");
      if (h.instance == kInvalidId) w.put("-1");
      else w.put(static_cast<std::size_t>(scene->instances[h.instance].base));
    }
    end_row();
  }
  w.close();
}

std::vector<Hit> read_hits_csv(const std::string& path) {
  LineReader reader(path);
  std::string line;
  if (!reader.next(line)) throw InputError(path + ": empty file, expected the header ray,prim,t,u,v");
  const bool contact = line.size() > 8 && line.compare(line.size() - 8, 8, ",contact") == 0;
  if (contact) line.resize(line.size() - 8);
  std::size_t columns;
  if (line == "ray,prim,t,u,v") columns = 5;
  else if (line == "ray,prim,t,u,v,instance") columns = 6;
  else if (line == "ray,prim,t,u,v,instance,base") columns = 7;
  else throw reader.fault("expected the header ray,prim,t,u,v[,instance[,base]][,contact]");
  const bool instanced = columns >= 6;
  const auto parse_id = [&](std::string_view s, const char* what) -> unsigned {
    if (s == "-1") return kInvalidId;
    std::uint64_t x;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (ec != std::errc() || p != s.data() + s.size() || x >= kInvalidId)
      throw reader.fault(std::string(what) + " '" + std::string(s) + "' is not -1 or an id below 2^32-1");
    return static_cast<unsigned>(x);
  };
  std::vector<Hit> hits;
  while (reader.next(line)) {
    std::vector<std::string_view> fields;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= line.size(); ++i)
      if (i == line.size() || line[i] == ',') {
        fields.push_back(std::string_view(line).substr(start, i - start));
        start = i + 1;
      }
    if (fields.size() != columns + (contact ? 1 : 0))
      throw reader.fault("expected " + std::to_string(columns + (contact ? 1 : 0)) + " fields, found " +
                         std::to_string(fields.size()));
    std::uint64_t index;
    const auto [p, ec] = std::from_chars(fields[0].data(), fields[0].data() + fields[0].size(), index);
    if (ec != std::errc() || p != fields[0].data() + fields[0].size() || index != hits.size())
      throw reader.fault("ray '" + std::string(fields[0]) + "' is not the row index " + std::to_string(hits.size()));
    if (hits.size() == kMaxRaysPerFile) throw reader.fault("more than " + std::to_string(kMaxRaysPerFile) + " rows");
    Hit h;
    h.prim = parse_id(fields[1], "prim");
    float v[3];
    static const char* const kNames[3] = {"t", "u", "v"};
    for (int i = 0; i < 3; ++i) {
      const std::string fault = parse_float(fields[2 + i], v[i]);
      if (!fault.empty()) throw reader.fault(std::string(kNames[i]) + ": " + fault);
    }
    if (h.valid() ? !std::isfinite(v[0]) : v[0] != kInf)
      throw reader.fault(h.valid() ? "t of a hit is not finite" : "t of a miss is not inf");
    h.t = v[0];
    h.u = v[1];
    h.v = v[2];
    if (instanced) h.instance = parse_id(fields[5], "instance");
    // The base follows from the instance and the scene; it is checked for form only.
    if (columns == 7 && (parse_id(fields[6], "base") == kInvalidId) != (h.instance == kInvalidId))
      throw reader.fault("base '" + std::string(fields[6]) + "' must be -1 exactly when the instance is");
    hits.push_back(h);
  }
  return hits;
}

}  // namespace raylab
