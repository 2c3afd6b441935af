#include "scene/fbx_check.h"

#include <cstdint>
#include <vector>

#include "geometry/input_error.h"
#include "scene/little_endian.h"

namespace raylab {
namespace {

bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

[[noreturn]] void too_deep(const std::string& path) {
  throw InputError(path + ": FBX scopes nested deeper than " + std::to_string(kMaxFbxDepth) + " levels");
}

/// An enclosing element: its key (record name) and its first string value, if any.
struct Scope {
  std::string_view key, value;
};

/// Whether `scopes` (outermost first) end in a property table that gives a Model its properties:
/// the Model's own, or the Model object type's template (used when a Model has none).
bool in_model_properties(const std::vector<Scope>& scopes) {
  const std::size_t n = scopes.size();
  if (n < 2 || scopes[n - 1].key != "Properties70") return false;
  if (scopes[n - 2].key == "Model") return true;
  return n >= 3 && scopes[n - 2].key == "PropertyTemplate" && scopes[n - 3].key == "ObjectType" && scopes[n - 3].value == "Model";
}

/// The first two string properties of a binary record ('S', u32 length, bytes) in [at, end).
void binary_strings(std::string_view data, std::uint64_t at, std::uint64_t end, std::string_view (&strings)[2]) {
  for (auto& s : strings) {
    if (at + 5 > end || data[static_cast<std::size_t>(at)] != 'S') return;
    const std::uint64_t length = read_le(data, static_cast<std::size_t>(at + 1), 4);
    if (at + 5 + length > end) return;
    s = data.substr(static_cast<std::size_t>(at + 5), static_cast<std::size_t>(length));
    at += 5 + length;
  }
}

/// Throws for a Model property type that Assimp 5.2.5's FBX converter asserts on.
void check_model_property(const std::string& path, std::string_view name, std::string_view type) {
  if (type == "KTime" || type == "ColorAndAlpha")
    throw InputError(path + ": FBX model property '" + std::string(name.substr(0, 60)) + "' of type " + std::string(type) +
                     ": Assimp 5.2.5 aborts on model properties of this type (an assertion in its FBX converter)");
}

void check_binary(const std::string& path, std::string_view data) {
  constexpr std::size_t kHeader = 27;  // magic (23 bytes) and version
  if (data.size() < kHeader) throw InputError(path + ": binary FBX shorter than its 27-byte header");
  const bool wide = read_le(data, 23, 4) >= 7500;
  const std::size_t word = wide ? 8 : 4, record_header = 3 * word + 1;
  std::vector<std::uint64_t> ends;  // of the records whose nested lists we are in
  std::vector<Scope> scopes;        // the same records
  std::uint64_t pos = kHeader;
  while (pos + record_header <= data.size()) {
    while (!ends.empty() && pos >= ends.back()) {
      ends.pop_back();
      scopes.pop_back();
    }
    const std::uint64_t end = read_le(data, static_cast<std::size_t>(pos), word);
    if (end == 0) {  // the null record closing a nested list (or the top level)
      if (ends.empty()) return;
      pos += record_header;
      continue;
    }
    const std::uint64_t properties = read_le(data, static_cast<std::size_t>(pos + 2 * word), word);
    const std::uint64_t name_length = static_cast<unsigned char>(data[static_cast<std::size_t>(pos + 3 * word)]);
    const std::uint64_t first = pos + record_header + name_length;
    if (end <= pos || end > data.size())
      throw InputError(path + ": binary FBX record at byte " + std::to_string(pos) + " ends at byte " + std::to_string(end) +
                       ", not between its start and the end of the file (" + std::to_string(data.size()) + " bytes)");
    if (first > end || properties > end - first)
      throw InputError(path + ": binary FBX record at byte " + std::to_string(pos) + ": its name and property list (" +
                       std::to_string(properties) + " bytes) run past the record's end at byte " + std::to_string(end));
    const std::uint64_t nested = first + properties;
    const std::string_view name = data.substr(static_cast<std::size_t>(pos + record_header), static_cast<std::size_t>(name_length));
    std::string_view strings[2];  // P: the property's name and type
    binary_strings(data, first, nested, strings);
    if (name == "P" && in_model_properties(scopes)) check_model_property(path, strings[0], strings[1]);
    if (nested < end) {
      ends.push_back(end);
      scopes.push_back({name, strings[0]});
      if (ends.size() > kMaxFbxDepth) too_deep(path);
      pos = nested;
    } else {
      pos = end;
    }
  }
}

void check_ascii(const std::string& path, std::string_view data) {
  std::vector<Scope> scopes;
  std::string_view key;                   // the element whose values the scanner is in
  std::vector<std::string_view> strings;  // the quoted values of `key` so far
  auto finish_element = [&] {
    if (key == "P" && strings.size() >= 2 && in_model_properties(scopes)) check_model_property(path, strings[0], strings[1]);
    strings.clear();
  };
  for (std::size_t i = 0; i < data.size(); ++i) {
    const char c = data[i];
    if (c == ';') {
      i = data.find('\n', i);
      if (i == std::string_view::npos) break;
    } else if (c == '"') {
      const std::size_t close = data.find('"', i + 1);
      if (close == std::string_view::npos) break;
      strings.push_back(data.substr(i + 1, close - i - 1));
      i = close;
    } else if (c == '{') {
      scopes.push_back({key, strings.empty() ? std::string_view() : strings[0]});
      finish_element();
      if (scopes.size() > kMaxFbxDepth) too_deep(path);
      key = {};
    } else if (c == '}') {
      finish_element();
      if (!scopes.empty()) scopes.pop_back();
      key = {};
    } else if (c == ':') {
      // A key is the word just before ':'; it starts a new element.
      std::size_t start = i;
      while (start > 0 && !space(data[start - 1]) && data[start - 1] != ',' && data[start - 1] != '{' && data[start - 1] != '}') --start;
      finish_element();
      key = data.substr(start, i - start);
    }
  }
  finish_element();
}

}  // namespace

void check_fbx(const std::string& path, std::string_view data) {
  if (data.starts_with("Kaydara FBX Binary")) check_binary(path, data);
  else check_ascii(path, data);
}

}  // namespace raylab
