#include "cost/accel_spec_key.h"

#include <mutex>
#include <unordered_map>

#include "accel/common/accel_factory.h"
#include "accel/common/fitted_cost.h"
#include "geometry/spec_string.h"

namespace raylab {

std::string canonical_accel_spec(const std::string& accel_spec) {
  // A function of the spec alone (the accelerator kinds and their parameters are registered
  // during static initialisation), asked for every model entry and candidate at each `auto`
  // choice: the forms found are kept for the process (a spec that throws is not kept).
  static std::mutex mutex;
  static std::unordered_map<std::string, std::string> found;
  {
    const std::lock_guard lock(mutex);
    if (const auto it = found.find(accel_spec); it != found.end()) return it->second;
  }
  const SpecString spec = parse_spec(accel_spec);
  std::map<std::string, std::string> params;
  for (const ParamDoc& p : find_accelerator_kind(spec.name).params) params[p.key] = p.default_value;
  for (const auto& [key, value] : spec.params) params[key] = value;
  if (const auto cost = params.find("cost"); cost != params.end() && cost->second != fitted_cost_param().default_value)
    cost->second = "fitted";
  std::string out = spec.name;
  char sep = ':';
  for (const auto& [key, value] : params) {
    out += sep + key + "=" + value;
    sep = ',';
  }
  const std::lock_guard lock(mutex);
  found.emplace(accel_spec, out);
  return out;
}

}  // namespace raylab
