#include "cost/accel_spec_key.h"

#include "accel/common/accel_factory.h"
#include "accel/common/fitted_cost.h"
#include "geometry/spec_string.h"

namespace raylab {

std::string canonical_accel_spec(const std::string& accel_spec) {
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
  return out;
}

}  // namespace raylab
