#include "accel/common/fitted_cost.h"
#include "accel/common/structure_hash.h"
#include "accel/octree/octree.h"

#include "accel/kdtree/kdtree.h"

namespace raylab {

Octree::Octree(std::shared_ptr<const Scene> scene, const OctreeConfig& config)
    : scene_(std::move(scene)), config_(config), data_(build_octree(*scene_, config_)) {
  octree_pack_leaves(*scene_, data_.nodes, data_.prims, packed_nodes_, packets_);
}

AccelStats Octree::stats() const {
  return {(data_.nodes.size() + packed_nodes_.size()) * sizeof(OctNode) + data_.prims.size() * sizeof(std::uint32_t) +
              packets_.size() * sizeof(TrianglePacket),
          data_.nodes.size(),
          data_.sah_cost};
}

std::optional<std::uint64_t> Octree::structure_hash() const {
  const std::uint64_t h = fnv1a(data_.nodes);
  return fnv1a(data_.prims, h);
}

OctreeConfig read_octree_config(SpecReader& r) {
  OctreeConfig c;
  c.clip = parse_clip_mode(r.get_choice("clip", "exact", clip_mode_names()));
  c.fitted_cost = read_sah_constants(r, "octree", 48.0, 1.5, c.cost);
  c.max_depth = static_cast<int>(r.get_int("max_depth", 0, 0, 20));
  c.mailbox = r.get_bool("mailbox", false);
  const std::string traversal = r.get_choice("traversal", "stack", {"stack", "revelles", "kd"});
  c.traversal = traversal == "kd"         ? OctreeTraversal::kd
                : traversal == "revelles" ? OctreeTraversal::revelles
                                          : OctreeTraversal::stack;
  c.kernel = read_kernel_choice(r);
  return c;
}

namespace {

std::unique_ptr<Aggregate> make_octree(std::shared_ptr<const Scene> scene, const OctreeConfig& config) {
  if (scene->instanced())
    return make_instanced_for_kernel(config.kernel, *scene, [&](std::shared_ptr<const Scene> base) {
      return make_octree(std::move(base), config);
    });
  return std::make_unique<Octree>(std::move(scene), config);
}

}  // namespace

AccelKind make_octree_kind() {
  return {"octree",
          "octree: centre splits (along a node's long axes), kd-tree placement and exact clipping, cost-based "
          "termination, front-to-back stack traversal or Revelles et al. 2000, leaves tested 4-wide",
          {{"clip", "exact", "split clipping: none | bbox | exact"},
           {"c_trav", "48", "traversal cost of the termination rule (measured best; octree_config.h)"},
           {"c_isect", "1.5", "intersection cost of the termination rule"},
           fitted_cost_param(),
           {"max_depth", "0", "safety depth limit; 0 = 3 + ceil(log8 N), at most 20"},
           {"mailbox", "off", "skip primitives a ray already tested"},
           {"traversal", "stack",
            "stack (iterative, crossings ordered per node) | revelles (parametric, Revelles et al. 2000) | kd (centre "
            "planes as three kd-tree splits)"},
           kernel_param_doc()},
          build_with_fitted_cost(read_octree_config, make_octree),
          [](SpecReader& r) -> AccuracyBound {
            return kernel_accuracy(read_octree_config(r).kernel, "conservative placement and traversal");
          },
          {"clip=none", "clip=bbox,mailbox=on,c_trav=1", "traversal=revelles,c_trav=8", "traversal=kd,c_trav=8",
           "clip=none,traversal=kd,mailbox=on", "cost=default", "kernel=watertight,c_trav=4",
           "kernel=watertight,traversal=kd,clip=bbox,mailbox=on"}};
}

namespace {
const AccelRegistration octree_registration(make_octree_kind(), 50);
}

}  // namespace raylab
