#include "accel/common/fitted_cost.h"
#include "accel/common/structure_hash.h"
#include "accel/bsp/bsp.h"

#include "accel/kdtree/kdtree.h"

namespace raylab {

BspTree::BspTree(std::shared_ptr<const Scene> scene, const BspConfig& config)
    : scene_(std::move(scene)), config_(config), data_(build_bsp(*scene_, config_)) {
  bsp_pack_leaves(*scene_, data_.nodes, data_.prims, packed_nodes_, packets_);
}

AccelStats BspTree::stats() const {
  return {(data_.nodes.size() + packed_nodes_.size()) * sizeof(BspNode) + data_.prims.size() * sizeof(std::uint32_t) +
              packets_.size() * sizeof(TrianglePacket),
          data_.nodes.size(),
          data_.sah_cost};
}

std::optional<std::uint64_t> BspTree::structure_hash() const {
  const std::uint64_t h = fnv1a(data_.nodes);
  return fnv1a(data_.prims, h);
}

BspConfig read_bsp_config(SpecReader& r) {
  BspConfig c;
  c.fitted_cost = read_sah_constants(r, "bsp", 1.0, kKdDefaultIsect, c.cost);
  c.cost.empty_bonus = r.get_double("empty_bonus", 0.2, 0.0, 0.99);
  c.triangle_candidates = static_cast<int>(r.get_int("triangle_candidates", 6, 0, 1024));
  c.axis_candidates = static_cast<int>(r.get_int("axis_candidates", 2, 0, 64));
  c.leaf_size = static_cast<int>(r.get_int("leaf_size", 4, 1, 1 << 20));
  c.max_depth = static_cast<int>(r.get_int("max_depth", 0, 0, 48));
  c.kernel = read_kernel_choice(r);
  return c;
}

namespace {

std::unique_ptr<Aggregate> make_bsp(std::shared_ptr<const Scene> scene, const BspConfig& config) {
  if (scene->instanced())
    return make_instanced_for_kernel(config.kernel, *scene, [&](std::shared_ptr<const Scene> base) {
      return make_bsp(std::move(base), config);
    });
  return std::make_unique<BspTree>(std::move(scene), config);
}

}  // namespace

AccelKind make_bsp_kind() {
  return {"bsp",
          "BSP tree: triangles' supporting planes (auto-partition) and axis planes by SAH on convex cells, exact "
          "classification, straddlers referenced on both sides",
          {{"c_trav", "1", "SAH traversal cost"},
           {"c_isect", "0.07", "SAH intersection cost (the kd-tree's default)"},
           fitted_cost_param(),
           {"empty_bonus", "0.2", "SAH empty-space bonus"},
           {"triangle_candidates", "6", "supporting planes tried per node"},
           {"axis_candidates", "2", "axis-aligned planes tried per axis and node"},
           {"leaf_size", "4", "nodes with at most this many primitives become leaves"},
           {"max_depth", "0", "safety depth limit; 0 = 6 + 1.3 log2 N, at most 48"},
           kernel_param_doc()},
          build_with_fitted_cost(read_bsp_config, make_bsp),
          [](SpecReader& r) -> AccuracyBound {
            return kernel_accuracy(read_bsp_config(r).kernel, "exact classification, error-bounded traversal");
          },
          {"axis_candidates=0,c_isect=1.5", "cost=default", "kernel=watertight"}};
}

namespace {
const AccelRegistration bsp_registration(make_bsp_kind(), 60);
}

}  // namespace raylab
