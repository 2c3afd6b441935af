#include "accel/common/fitted_cost.h"

namespace raylab {

ParamDoc fitted_cost_param() {
  return {"cost", "(none)",
          "a fitted cost model (raylab fit) whose constants replace c_trav/c_isect: a model.json path, or "
          "'default' for the lab's committed model"};
}

std::optional<FittedCostRequest> read_fitted_cost(SpecReader& reader, const std::string& family,
                                                  const std::vector<std::string>& manual_keys) {
  if (!reader.has("cost")) return std::nullopt;
  for (const std::string& key : manual_keys)
    if (reader.has(key))
      throw InputError("accelerator '" + reader.spec().text + "': cost= and " + key + "= are exclusive (the model sets it)");
  const std::string model = reader.get_string("cost", "");
  if (model.empty()) throw InputError("accelerator '" + reader.spec().text + "': cost= needs a model file or 'default'");
  return FittedCostRequest{model, family};
}

}  // namespace raylab
