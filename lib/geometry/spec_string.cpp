#include "geometry/spec_string.h"

#include <charconv>
#include <cmath>

#include "geometry/input_error.h"

namespace raylab {
namespace {

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

std::string strip_parens(std::string_view v) {
  if (v.size() >= 2 && v.front() == '(' && v.back() == ')') return std::string(v.substr(1, v.size() - 2));
  return std::string(v);
}

}  // namespace

bool parse_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  auto [p, ec] = std::from_chars(s.data(), end, out);
  return ec == std::errc() && p == end && std::isfinite(out);
}

bool parse_int(std::string_view s, std::int64_t& out) {
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  auto [p, ec] = std::from_chars(s.data(), end, out);
  return ec == std::errc() && p == end;
}

SpecString parse_spec(std::string_view text) {
  SpecString spec;
  spec.text = std::string(text);
  const auto colon = text.find(':');
  spec.name = std::string(text.substr(0, colon));
  if (spec.name.empty()) throw InputError("spec " + quoted(text) + ": empty name");
  if (colon == std::string_view::npos) return spec;
  const std::string_view rest = text.substr(colon + 1);
  // Split at top-level commas.
  std::vector<std::string_view> items;
  int depth = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= rest.size(); ++i) {
    if (i == rest.size() || (rest[i] == ',' && depth == 0)) {
      items.push_back(rest.substr(start, i - start));
      start = i + 1;
    } else if (rest[i] == '(') {
      ++depth;
    } else if (rest[i] == ')') {
      if (--depth < 0) throw InputError("spec " + quoted(text) + ": unbalanced ')'");
    }
  }
  if (depth != 0) throw InputError("spec " + quoted(text) + ": unbalanced '('");
  for (std::string_view item : items) {
    if (item.empty()) throw InputError("spec " + quoted(text) + ": empty item");
    const auto eq = item.find('=');
    // A '=' inside parentheses belongs to a nested spec, not to this item.
    const auto paren = item.find('(');
    if (eq == std::string_view::npos || (paren != std::string_view::npos && paren < eq)) {
      if (!spec.params.empty())
        throw InputError("spec " + quoted(text) + ": positional value " + quoted(item) + " after key=value items");
      spec.positional.push_back(strip_parens(item));
      continue;
    }
    std::string key(item.substr(0, eq));
    if (key.empty()) throw InputError("spec " + quoted(text) + ": empty key in " + quoted(item));
    for (const auto& [k, v] : spec.params)
      if (k == key) throw InputError("spec " + quoted(text) + ": key " + quoted(key) + " given twice");
    spec.params.emplace_back(std::move(key), strip_parens(item.substr(eq + 1)));
  }
  return spec;
}

SpecReader::SpecReader(SpecString spec) : spec_(std::move(spec)), used_(spec_.params.size(), false) {}

bool SpecReader::has(const std::string& key) const {
  for (const auto& [k, v] : spec_.params)
    if (k == key) return true;
  return false;
}

const std::string* SpecReader::find(const std::string& key) {
  for (std::size_t i = 0; i < spec_.params.size(); ++i)
    if (spec_.params[i].first == key) {
      used_[i] = true;
      return &spec_.params[i].second;
    }
  return nullptr;
}

std::string SpecReader::get_string(const std::string& key, const std::string& fallback) {
  const std::string* v = find(key);
  return v ? *v : fallback;
}

std::string SpecReader::get_choice(const std::string& key, const std::string& fallback,
                                   const std::vector<std::string>& choices) {
  const std::string* v = find(key);
  if (!v) return fallback;
  for (const auto& c : choices)
    if (c == *v) return c;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : "|") + c;
  throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is not one of " + list);
}

std::int64_t SpecReader::get_int(const std::string& key, std::int64_t fallback, std::int64_t lo, std::int64_t hi) {
  const std::string* v = find(key);
  if (!v) return fallback;
  std::int64_t out;
  if (!parse_int(*v, out))
    throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is not an integer");
  if (out < lo || out > hi)
    throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is outside [" + std::to_string(lo) +
                     ", " + std::to_string(hi) + "]");
  return out;
}

double SpecReader::get_double(const std::string& key, double fallback, double lo, double hi) {
  const std::string* v = find(key);
  if (!v) return fallback;
  double out;
  if (!parse_double(*v, out))
    throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is not a finite number");
  if (out < lo || out > hi)
    throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is outside [" + std::to_string(lo) +
                     ", " + std::to_string(hi) + "]");
  return out;
}

bool SpecReader::get_bool(const std::string& key, bool fallback) {
  const std::string* v = find(key);
  if (!v) return fallback;
  if (*v == "on" || *v == "true" || *v == "1") return true;
  if (*v == "off" || *v == "false" || *v == "0") return false;
  throw InputError("spec " + quoted(spec_.text) + ": " + key + "=" + *v + " is not on|off");
}

std::int64_t SpecReader::get_positional_int(const std::string& what, std::int64_t lo, std::int64_t hi) {
  if (spec_.positional.empty()) throw InputError("spec " + quoted(spec_.text) + ": missing " + what);
  positional_used_ = true;
  std::int64_t out;
  const std::string& v = spec_.positional.front();
  if (!parse_int(v, out)) throw InputError("spec " + quoted(spec_.text) + ": " + what + " " + quoted(v) + " is not an integer");
  if (out < lo || out > hi)
    throw InputError("spec " + quoted(spec_.text) + ": " + what + " " + v + " is outside [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  return out;
}

namespace {
std::string key_list(const std::vector<ParamDoc>& valid) {
  std::string list;
  for (const auto& p : valid) list += (list.empty() ? "" : ", ") + p.key;
  return list.empty() ? "none" : list;
}
}  // namespace

void SpecReader::reject_unknown_keys(const std::vector<ParamDoc>& valid) const {
  for (const auto& [key, value] : spec_.params) {
    bool known = false;
    for (const auto& p : valid) known = known || p.key == key;
    if (!known)
      throw InputError("spec " + quoted(spec_.text) + ": unknown parameter " + quoted(key) + " for '" + spec_.name +
                       "' (valid: " + key_list(valid) + ")");
  }
}

void SpecReader::finish(const std::vector<ParamDoc>& valid) const {
  const std::string list = key_list(valid);
  for (std::size_t i = 0; i < spec_.params.size(); ++i)
    if (!used_[i])
      throw InputError("spec " + quoted(spec_.text) + ": unknown parameter " + quoted(spec_.params[i].first) +
                       " for '" + spec_.name + "' (valid: " + list + ")");
  const std::size_t allowed = positional_used_ ? 1 : 0;
  if (spec_.positional.size() > allowed)
    throw InputError("spec " + quoted(spec_.text) + ": unexpected value " + quoted(spec_.positional[allowed]) +
                     " for '" + spec_.name + "' (valid keys: " + list + ")");
}

}  // namespace raylab
