#include "accel/common/fitted_cost.h"
#include "accel/common/structure_hash.h"
#include "accel/kdtree/kdtree.h"

namespace raylab {

KdTree::KdTree(std::shared_ptr<const Scene> scene, const KdTreeConfig& config)
    : scene_(std::move(scene)), config_(config), data_(build_kdtree(*scene_, config_)) {
  hash_ = fnv1a(data_.prims, fnv1a(data_.nodes));
  if (config_.traversal == KdTraversal::recursive) {
    tris_ = make_triangle_soup(*scene_);
    return;
  }
  lines_ = kd_node_lines(data_.nodes);
  packets_ = kd_pack_leaves(*scene_, data_.prims, lines_);
  // Packed leaves carry their primitive ids; without packets (spheres) the leaves index prims.
  if (!packets_.empty()) std::vector<std::uint32_t>().swap(data_.prims);
}

AccelStats KdTree::stats() const {
  return {data_.nodes.size() * sizeof(KdNode) + data_.prims.size() * sizeof(std::uint32_t) +
              tris_.size() * sizeof(KdTriangle) + lines_.size() * sizeof(KdNodeLine) +
              packets_.size() * sizeof(TrianglePacket),
          data_.nodes.size(),
          data_.sah_cost};
}

std::optional<std::uint64_t> KdTree::structure_hash() const { return hash_; }

namespace {

const std::vector<std::string> kBuilders = {"midpoint", "median", "sah"};
const std::vector<std::string> kSweeps = {"sort", "events"};
const std::vector<std::string> kTraversals = {"recursive", "stack"};

std::vector<ParamDoc> kdtree_params() {
  return {{"builder", "sah", "midpoint | median | sah"},
          {"sweep", "events", "SAH sweep: sort (per-node sort, O(N log^2 N)) | events (Wald-Havran 2006, O(N log N))"},
          {"clip", "exact", "split clipping: none | bbox | exact (CGAL triangle/box predicate, perfect splits)"},
          {"traversal", "stack", "recursive (Kaplan/Arvo/Jansen) | stack"},
          {"c_trav", "1", "SAH traversal cost"},
          {"c_isect", "0.07", "SAH intersection cost (kdtree_config.h: kKdDefaultIsect)"},
          fitted_cost_param(),
          {"empty_bonus", "0.2", "SAH empty-space bonus in [0,1)"},
          {"max_depth", "0", "safety depth limit; 0 = 8 + 1.3 log2 N, at most 64"},
          {"leaf_size", "4", "midpoint/median: largest leaf"},
          {"mailbox", "off", "skip primitives a ray already tested"},
          kernel_param_doc()};
}

}  // namespace

KdTreeConfig read_kdtree_config(SpecReader& r) {
  KdTreeConfig c;
  const std::string b = r.get_choice("builder", "sah", kBuilders);
  c.builder = b == "midpoint" ? KdBuilder::midpoint : (b == "median" ? KdBuilder::median : KdBuilder::sah);
  c.sweep = r.get_choice("sweep", "events", kSweeps) == "sort" ? KdSweep::sort : KdSweep::events;
  c.clip = parse_clip_mode(r.get_choice("clip", "exact", clip_mode_names()));
  c.traversal = r.get_choice("traversal", "stack", kTraversals) == "recursive" ? KdTraversal::recursive : KdTraversal::stack;
  c.fitted_cost = read_sah_constants(r, "kdtree", 1.0, kKdDefaultIsect, c.cost);
  c.cost.empty_bonus = r.get_double("empty_bonus", 0.2, 0.0, 0.99);
  c.max_depth = static_cast<int>(r.get_int("max_depth", 0, 0, 64));
  c.leaf_size = static_cast<int>(r.get_int("leaf_size", 4, 1, 1 << 20));
  c.mailbox = r.get_bool("mailbox", false);
  c.kernel = read_kernel_choice(r);
  return c;
}

namespace {

std::unique_ptr<Aggregate> make_kdtree(std::shared_ptr<const Scene> scene, const KdTreeConfig& config) {
  if (scene->instanced())
    return make_instanced_for_kernel(config.kernel, *scene, [&](std::shared_ptr<const Scene> base) {
      return make_kdtree(std::move(base), config);
    });
  return std::make_unique<KdTree>(std::move(scene), config);
}

}  // namespace

AccelKind make_kdtree_kind() {
  return {"kdtree",
          "kd-tree: midpoint/median/SAH builders, sort or event sweep, exact split clipping",
          kdtree_params(),
          build_with_fitted_cost(read_kdtree_config, make_kdtree),
          [](SpecReader& r) -> AccuracyBound {
            return kernel_accuracy(read_kdtree_config(r).kernel, "conservative placement and traversal");
          },
          {"builder=midpoint,traversal=recursive", "builder=median,clip=bbox,mailbox=on", "sweep=sort,clip=none",
           "clip=bbox,traversal=recursive,mailbox=on", "cost=default", "kernel=watertight",
           "kernel=watertight,traversal=recursive,clip=bbox,mailbox=on"}};
}

namespace {
const AccelRegistration kdtree_registration(make_kdtree_kind(), 40);
}

}  // namespace raylab
