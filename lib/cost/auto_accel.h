#pragma once
/// `auto[:model=PATH,rays=KIND]`: the accelerator a fitted cost model picks for the scene it is
/// given. Every candidate structure (the lab's own: BVH of each width, kd-tree, octree, BSP tree,
/// uniform and nested grids, with the parameter variants the model can rank, including trees
/// built from the model itself, `cost=`) whose family the model covers is built, its features
/// read (tree_features.h), and its time predicted by the model's tree level for rays of KIND
/// (default: the mean over primary, diffuse and shadow rays); the fastest prediction is kept and
/// the others freed. Embree and brute force are not candidates. The BSP tree is skipped above
/// kAutoBspMaxPrimitives (its build is quadratic in the worst case). Without `model=` the lab's
/// committed default model (model_file.h) is used, and the choice says so. On an instanced
/// scene the choice is made for each base and for the flat geometry apart (placed as
/// make_instanced_aggregate places them); the choice reported is the largest part's.
#include <memory>
#include <string>
#include <vector>

#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr std::size_t kAutoBspMaxPrimitives = std::size_t{1} << 15;

struct AutoCandidate {
  std::string spec;
  double predicted_ns_per_ray = 0.0;  ///< NaN when skipped
  std::string skipped;                ///< why, when skipped
};

struct AutoChoice {
  std::string model;  ///< the model file used
  std::string rays;   ///< the ray kind predicted for, or "mixed"
  std::string chosen;
  double predicted_ns_per_ray = 0.0;
  std::vector<AutoCandidate> candidates;
};

/// The candidate specs for a model whose families are `families` (model path spliced into the
/// `cost=` variants).
std::vector<std::string> auto_candidate_specs(const std::vector<std::string>& families, const std::string& model);

class AutoAccelerator final : public Aggregate {
 public:
  AutoAccelerator(std::unique_ptr<Aggregate> chosen, AutoChoice choice)
      : inner_(std::move(chosen)), choice_(std::move(choice)) {}

  std::string name() const override { return "auto"; }
  AccelStats stats() const override { return inner_->stats(); }
  bool reports_counters() const override { return inner_->reports_counters(); }
  std::optional<std::uint64_t> structure_hash() const override { return inner_->structure_hash(); }
  Bounds3f bounds() const override { return inner_->bounds(); }
  bool intersect(Ray& ray, Hit& hit) const override { return inner_->intersect(ray, hit); }
  bool intersect(Ray& ray, Hit& hit, RayCounters& c) const override { return inner_->intersect(ray, hit, c); }
  bool occluded(const Ray& ray) const override { return inner_->occluded(ray); }
  bool occluded(const Ray& ray, RayCounters& c) const override { return inner_->occluded(ray, c); }

  const AutoChoice& choice() const { return choice_; }
  const Aggregate& chosen() const { return *inner_; }

 private:
  std::unique_ptr<Aggregate> inner_;
  AutoChoice choice_;
};

}  // namespace raylab
