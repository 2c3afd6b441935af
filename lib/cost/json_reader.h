#pragma once
/// Typed access to a JSON object of a model file (model_file.h) or one of its sections, every
/// error one InputError naming the file and the key path ("model.json.families.bvh: missing key
/// 'rows'").
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geometry/input_error.h"

namespace raylab {

class JsonReader {
 public:
  using Json = nlohmann::ordered_json;

  JsonReader(const Json& j, std::string where) : j_(j), where_(std::move(where)) {
    if (!j_.is_object()) throw InputError(where_ + ": expected a JSON object");
  }
  const Json& at(const std::string& key) const {
    const auto it = j_.find(key);
    if (it == j_.end()) throw InputError(where_ + ": missing key '" + key + "'");
    return *it;
  }
  JsonReader object(const std::string& key) const { return JsonReader(at(key), where_ + "." + key); }
  double number(const std::string& key, bool nullable = false) const {
    const Json& v = at(key);
    if (nullable && v.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw InputError(where_ + "." + key + ": expected a finite number");
    return v.get<double>();
  }
  std::string string(const std::string& key) const {
    const Json& v = at(key);
    if (!v.is_string()) throw InputError(where_ + "." + key + ": expected a string");
    return v.get<std::string>();
  }
  bool boolean(const std::string& key) const {
    const Json& v = at(key);
    if (!v.is_boolean()) throw InputError(where_ + "." + key + ": expected true or false");
    return v.get<bool>();
  }
  std::vector<std::string> strings(const std::string& key) const {
    const Json& v = at(key);
    if (!v.is_array()) throw InputError(where_ + "." + key + ": expected a list of strings");
    std::vector<std::string> out;
    for (const Json& s : v) {
      if (!s.is_string()) throw InputError(where_ + "." + key + ": expected a list of strings");
      out.push_back(s.get<std::string>());
    }
    return out;
  }
  const Json& json() const { return j_; }
  const std::string& where() const { return where_; }

 private:
  const Json& j_;
  std::string where_;
};

}  // namespace raylab
