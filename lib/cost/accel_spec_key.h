#pragma once
/// Which model entry stands for an accelerator spec: the data set keys its rows by the spec as
/// the plan spells it (`bvh`, `grid:d=3`), a user or `auto` may spell the same structure
/// otherwise (`bvh:width=8`, `grid`). Two specs name the same structure when their canonical
/// forms agree: the accelerator's name, then every parameter it takes, defaults filled in, sorted
/// by key (`bvh:builder=binned,...,width=8`). Every `cost=MODEL` reads as `cost=fitted`: a tree
/// built from a model's fitted constants stands for one structure whichever model supplied them,
/// so the data set's `bvh:cost=default` rows predict `auto`'s `bvh:width=8,cost=PATH` candidate (a
/// refit moves the constants little; a model fitted on another machine may move them more).
#include <map>
#include <string>

namespace raylab {

/// The canonical form of `accel_spec`; throws InputError for an unknown accelerator.
std::string canonical_accel_spec(const std::string& accel_spec);

/// The entry of `models` (keyed by spec) for `accel_spec`: its own key, else the first key of the
/// same canonical form; nullptr when none (or when a key is not a spec this lab knows).
template <class Model>
const Model* find_spec_model(const std::map<std::string, Model>& models, const std::string& accel_spec) {
  if (const auto it = models.find(accel_spec); it != models.end()) return &it->second;
  const std::string key = canonical_accel_spec(accel_spec);
  for (const auto& [spec, model] : models) {
    try {
      if (canonical_accel_spec(spec) == key) return &model;
    } catch (...) {  // a spec of another lab version: it names no structure here
    }
  }
  return nullptr;
}

}  // namespace raylab
