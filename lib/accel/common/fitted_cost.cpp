#include "accel/common/fitted_cost.h"

#include "geometry/input_error.h"

namespace raylab {
namespace {

FittedCostLoader& loader() {
  static FittedCostLoader l = nullptr;
  return l;
}

}  // namespace

void set_fitted_cost_loader(FittedCostLoader l) { loader() = l; }

ParamDoc fitted_cost_param() {
  return {"cost", "(none)",
          "a fitted cost model (raylab fit) whose constants replace c_trav/c_isect: a model.json path, or "
          "'default' for the lab's committed model"};
}

bool read_fitted_cost(SpecReader& reader, const std::string& family, const std::vector<std::string>& manual_keys,
                      FittedSahCost& out) {
  if (!reader.has("cost")) return false;
  for (const std::string& key : manual_keys)
    if (reader.has(key))
      throw InputError("accelerator '" + reader.spec().text + "': cost= and " + key + "= are exclusive (the model sets it)");
  const std::string path = reader.get_string("cost", "");
  if (path.empty()) throw InputError("accelerator '" + reader.spec().text + "': cost= needs a model file or 'default'");
  if (!loader()) throw InputError("accelerator '" + reader.spec().text + "': this program cannot read cost models");
  out = loader()(path, family);
  return true;
}

}  // namespace raylab
