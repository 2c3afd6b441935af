#include "accel/bvh/primitive_bvh.h"

#include <stdexcept>

namespace raylab {

BvhConfig primitive_bvh_default_config() {
  BvhConfig c;
  c.builder = BvhBuilder::binned;
  c.max_leaf_size = 2;
  c.cost.c_trav = 1.0;
  c.cost.c_isect = 8.0;
  return c;
}

namespace {

std::vector<Bounds3f> world_bounds(const std::vector<std::shared_ptr<const Primitive>>& prims) {
  std::vector<Bounds3f> boxes;
  boxes.reserve(prims.size());
  for (const auto& p : prims) {
    if (!p) throw std::invalid_argument("PrimitiveBvh: null primitive");
    boxes.push_back(p->bounds());
  }
  return boxes;
}

}  // namespace

PrimitiveBvh::PrimitiveBvh(std::vector<std::shared_ptr<const Primitive>> prims, const BvhConfig& config)
    : prims_(std::move(prims)), config_(config) {
  const std::vector<Bounds3f> boxes = world_bounds(prims_);
  for (const Bounds3f& b : boxes) bounds_.extend(b);
  tree_ = build_bvh_over_boxes(boxes, config_);
  leaf_prims_.reserve(tree_.prims.size());
  for (const std::uint32_t p : tree_.prims) leaf_prims_.push_back(prims_[p].get());
  sah_cost_ = bvh_sah_cost(tree_, config_.cost);
}

AccelStats PrimitiveBvh::stats() const {
  return {tree_.nodes.size() * sizeof(Bvh2Node) + tree_.prims.size() * sizeof(std::uint32_t) +
              leaf_prims_.size() * sizeof(const Primitive*),
          tree_.nodes.size(), sah_cost_};
}

}  // namespace raylab
