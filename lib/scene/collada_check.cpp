#include "scene/collada_check.h"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "geometry/input_error.h"

namespace raylab {
namespace {

bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
bool digit(char c) { return c >= '0' && c <= '9'; }

bool one_of(std::string_view name, std::initializer_list<std::string_view> names) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// The value of attribute `key` in a start tag's attribute text (without the quotes).
std::optional<std::string_view> attribute(std::string_view attrs, std::string_view key) {
  std::size_t i = 0;
  while (i < attrs.size()) {
    while (i < attrs.size() && (space(attrs[i]) || attrs[i] == '/')) ++i;
    const std::size_t name_start = i;
    while (i < attrs.size() && attrs[i] != '=' && !space(attrs[i])) ++i;
    const std::string_view name = attrs.substr(name_start, i - name_start);
    while (i < attrs.size() && space(attrs[i])) ++i;
    if (i >= attrs.size() || attrs[i] != '=') return std::nullopt;
    ++i;
    while (i < attrs.size() && space(attrs[i])) ++i;
    if (i >= attrs.size() || (attrs[i] != '"' && attrs[i] != '\'')) return std::nullopt;
    const char quote = attrs[i++];
    const std::size_t value_start = i;
    while (i < attrs.size() && attrs[i] != quote) ++i;
    if (name == key) return attrs.substr(value_start, i - value_start);
    ++i;
  }
  return std::nullopt;
}

class ColladaChecker {
 public:
  ColladaChecker(const std::string& path, std::string_view data) : path_(path), data_(data) {}

  void check() {
    std::size_t i = 0;
    while (i < data_.size()) {
      const std::size_t lt = std::min(data_.find('<', i), data_.size());
      if (!stack_.empty()) text(data_.substr(i, lt - i), i);
      if (lt == data_.size()) break;
      i = tag(lt);
    }
    while (!stack_.empty()) close();  // unclosed elements (malformed XML) are checked too
  }

 private:
  struct Element {
    std::string_view name;
    std::size_t offset;             ///< of its start tag
    std::optional<std::uint64_t> count;
    std::uint64_t numbers = 0;      ///< in its text (arrays, index lists) or its index lists (primitives)
    bool in_number = false;         ///< the text so far ends inside a number
  };

  [[noreturn]] void fail(std::size_t offset, const std::string& what) const {
    const auto line = 1 + std::count(data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
    throw InputError(path_ + ":" + std::to_string(line) + ": COLLADA: " + what);
  }

  static bool is_index_list(std::string_view name) { return one_of(name, {"p", "vcount", "v", "h"}); }
  static bool is_array(std::string_view name) {
    return one_of(name, {"float_array", "int_array", "bool_array", "Name_array", "IDREF_array", "SIDREF_array", "token_array"});
  }
  static bool is_primitive(std::string_view name) {
    return one_of(name, {"triangles", "polylist", "polygons", "lines", "linestrips", "tristrips", "trifans"});
  }

  std::optional<std::uint64_t> number_attribute(std::string_view attrs, std::string_view key, std::size_t offset) const {
    const auto value = attribute(attrs, key);
    if (!value) return std::nullopt;
    if (value->empty() || value->size() > 18 || !std::all_of(value->begin(), value->end(), digit))
      fail(offset, std::string(key) + " '" + std::string(value->substr(0, 20)) + "' is not a count");
    return std::stoull(std::string(*value));
  }

  void text(std::string_view t, std::size_t offset) {
    Element& e = stack_.back();
    const bool index_list = is_index_list(e.name);
    if (!index_list && !is_array(e.name)) return;
    for (std::size_t k = 0; k < t.size(); ++k) {
      const char c = t[k];
      if (space(c)) {
        e.in_number = false;
        continue;
      }
      if (index_list && !digit(c)) fail(offset + k, std::string("<") + std::string(e.name) + "> holds a character that is no digit: an index list holds unsigned integers only");
      if (!e.in_number) ++e.numbers;
      e.in_number = true;
    }
  }

  /// Handles the markup at `lt`; returns the offset after it.
  std::size_t tag(std::size_t lt) {
    auto skip_to = [&](std::size_t from, std::string_view end) {
      const std::size_t k = data_.find(end, from);
      return k == std::string_view::npos ? data_.size() : k + end.size();
    };
    if (data_.substr(lt, 4) == "<!--") return skip_to(lt + 4, "-->");
    if (data_.substr(lt, 9) == "<![CDATA[") return skip_to(lt + 9, "]]>");
    if (lt + 1 < data_.size() && (data_[lt + 1] == '?' || data_[lt + 1] == '!')) return skip_to(lt + 2, ">");
    std::size_t end = lt + 1;
    for (char quote = 0; end < data_.size(); ++end) {
      const char c = data_[end];
      if (quote) { if (c == quote) quote = 0; }
      else if (c == '"' || c == '\'') quote = c;
      else if (c == '>') break;
    }
    if (end >= data_.size()) return data_.size();
    const bool closing = data_[lt + 1] == '/';
    const bool empty = data_[end - 1] == '/';
    std::size_t name_end = lt + (closing ? 2 : 1);
    while (name_end < end && !space(data_[name_end]) && data_[name_end] != '/') ++name_end;
    const std::string_view name = data_.substr(lt + (closing ? 2 : 1), name_end - lt - (closing ? 2 : 1));
    if (closing) {
      if (!stack_.empty()) close();
      return end + 1;
    }
    const std::string_view attrs = data_.substr(name_end, end - name_end);
    Element e{name, lt, std::nullopt};
    if (is_array(name) || is_primitive(name)) e.count = number_attribute(attrs, "count", lt);
    if (name == "accessor") {
      const std::uint64_t count = number_attribute(attrs, "count", lt).value_or(0);
      const std::uint64_t stride = number_attribute(attrs, "stride", lt).value_or(1);
      if (count > data_.size() || stride > data_.size() || count * std::max<std::uint64_t>(stride, 1) > data_.size())
        fail(lt, "an accessor of count " + std::to_string(count) + " and stride " + std::to_string(stride) +
                     " reads more values than the file's " + std::to_string(data_.size()) + " bytes can hold");
    }
    stack_.push_back(e);
    if (stack_.size() > kMaxColladaDepth) fail(lt, "XML elements nested deeper than " + std::to_string(kMaxColladaDepth) + " levels");
    if (empty) close();
    return end + 1;
  }

  void close() {
    const Element e = stack_.back();
    stack_.pop_back();
    if (e.count && *e.count > e.numbers)
      fail(e.offset, std::string("<") + std::string(e.name) + "> declares count " + std::to_string(*e.count) + " but holds " +
                         std::to_string(e.numbers) + (is_primitive(e.name) ? " indices" : " values"));
    if (is_index_list(e.name) && !stack_.empty()) stack_.back().numbers += e.numbers;
  }

  const std::string& path_;
  std::string_view data_;
  std::vector<Element> stack_;
};

}  // namespace

void check_collada(const std::string& path, std::string_view data) { ColladaChecker(path, data).check(); }

}  // namespace raylab
