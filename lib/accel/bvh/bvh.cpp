#include "accel/bvh/bvh.h"
#include "accel/common/fitted_cost.h"

#include <string>

#include "accel/common/structure_hash.h"
#include "geometry/input_error.h"

namespace raylab {

Bvh::Bvh(std::shared_ptr<const Scene> scene, const BvhConfig& config)
    : scene_(std::move(scene)), config_(config), tree_(build_bvh(*scene_, config_)), bounds_(scene_->bounds()) {
  build_sah_cost_ = bvh_sah_cost(tree_, config_.cost);
  const bool quantized = config_.nodes == BvhNodes::quantized;
  WideCollapseOptions collapse;
  collapse.method = config_.collapse;
  collapse.max_leaf_primitives = static_cast<std::uint32_t>(config_.max_leaf_size);
  collapse.threads = config_.threads;
  collapse.cost = config_.wide_cost;
  if (config_.width == 4 && !quantized) wide4_ = collapse_bvh<4>(tree_, *scene_, collapse);
  if (config_.width == 8 && !quantized) wide8_ = collapse_bvh<8>(tree_, *scene_, collapse);
  if (config_.width == 4 && quantized) quantized4_ = quantize_wide_bvh(collapse_bvh<4>(tree_, *scene_, collapse));
  if (config_.width == 8 && quantized) quantized8_ = quantize_wide_bvh(collapse_bvh<8>(tree_, *scene_, collapse));
  if (config_.width != 2 && config_.leaves == BvhLeaves::indexed) {
    BuildArray<TrianglePacket>& packets = config_.width == 4 ? (quantized ? quantized4_.packets : wide4_.packets)
                                                             : (quantized ? quantized8_.packets : wide8_.packets);
    indexed_ = index_packets(*scene_, packets);
    BuildArray<TrianglePacket>().swap(packets);
  }
}

AccelStats Bvh::stats() const {
  const bool quantized = config_.nodes == BvhNodes::quantized;
  const std::size_t leaf_bytes = indexed_.bytes();
  if (config_.width == 4 && quantized) return {quantized4_.bytes() + leaf_bytes, quantized4_.nodes.size(), build_sah_cost_};
  if (config_.width == 8 && quantized) return {quantized8_.bytes() + leaf_bytes, quantized8_.nodes.size(), build_sah_cost_};
  if (config_.width == 4) return {wide4_.bytes() + leaf_bytes, wide4_.nodes.size(), build_sah_cost_};
  if (config_.width == 8) return {wide8_.bytes() + leaf_bytes, wide8_.nodes.size(), build_sah_cost_};
  return {tree_.nodes.size() * sizeof(Bvh2Node) + tree_.prims.size() * sizeof(std::uint32_t), tree_.nodes.size(),
          build_sah_cost_};
}

namespace {

/// Folds the wide tree's topology (each node's child references and lane count) into `h`.
template <class Nodes>
std::uint64_t hash_wide_topology(const Nodes& nodes, std::uint64_t h) {
  for (const auto& node : nodes) h = fnv1a(&node.used, sizeof node.used, fnv1a(node.child, sizeof node.child, h));
  return h;
}

}  // namespace

std::optional<std::uint64_t> Bvh::structure_hash() const {
  std::uint64_t h = fnv1a(tree_.prims, fnv1a(tree_.nodes));
  h = hash_wide_topology(wide4_.nodes, hash_wide_topology(wide8_.nodes, h));
  return hash_wide_topology(quantized4_.nodes, hash_wide_topology(quantized8_.nodes, h));
}

namespace {

const std::vector<std::string> kBuilders = {"midpoint", "median", "sweep", "binned", "spatial"};
const std::vector<std::string> kWidths = {"2", "4", "8"};
const std::vector<std::string> kOptimizations = {"none", "reinsert"};
const std::vector<std::string> kCollapses = {"greedy", "sah"};
const std::vector<std::string> kNodeKinds = {"full", "quantized"};
const std::vector<std::string> kLeafKinds = {"packed", "indexed"};

std::vector<ParamDoc> bvh_params() {
  return {{"builder", "binned",
           "midpoint | median | sweep (full-sweep SAH, all axes) | binned (binned SAH, TBB) | spatial (SBVH)"},
          {"leaf_size", "4 (width=2), 16 (width=8, SAH builders), 8 (otherwise)", "largest leaf, in [1, 64]"},
          {"bins", "32", "SAH bins per axis, in [2, 256]"},
          {"c_trav", "1 (width=2), 3 (width=4|8)", "SAH traversal cost"},
          {"c_isect", "1", "SAH intersection cost"},
          fitted_cost_param(),
          {"alpha", "1e-5", "SBVH: try spatial splits where child overlap exceeds alpha * SA(root)"},
          {"max_duplication", "1", "SBVH: at most (1 + max_duplication) * N references"},
          {"width", "8", "children per node: 2 (binary, scalar) | 4 | 8 (collapsed, SIMD box tests, packed leaves)"},
          {"collapse", "sah",
           "sah (the wide tree of least SAH cost over all collapses of the binary one, small subtrees merged into "
           "leaves; Ylitie et al. 2017) | greedy (open the child of largest area until the node is full; width 4 or 8)"},
          {"nodes", "full",
           "full (float child boxes) | quantized (8-bit child boxes relative to the node's, enlarged outward: "
           "half the node bytes, same first hits; width 4 or 8)"},
          {"leaves", "packed",
           "packed (each triangle's vertices copied into SIMD packets) | indexed (vertex indices into one copy "
           "of the leaves' vertices, gathered at each test: fewer bytes, slower tests; width 4 or 8)"},
          {"robust", "on",
           "on: Ize's conservative box test + `kernel` | off: the fast variant (plain slab test, Moller-Trumbore)"},
          kernel_param_doc("certified (robust=on), watertight (robust=off)"),
          {"threads", "0", "build threads; 0 = all"},
          {"optimize", "none",
           "none | reinsert (Bittner et al. 2013: reinsert the children of the least efficient nodes where the SAH "
           "grows least, on the binary tree before the wide collapse; leaves unchanged)"},
          {"optimize_passes", "0", "reinsertion passes at most (2% of the interior nodes each); 0 = until the SAH cost "
                                   "improves < 0.1% over 50 passes"},
          {"optimize_budget", "0",
           "wall time of the reinsertion passes at most, seconds, checked between passes; setting up and writing back "
           "the tree come on top (0.1 s of passes added 0.17-0.21 s to the build at 1.2e6 triangles, docs/bvh_scale); "
           "0 = no limit"}};
}

}  // namespace

BvhConfig read_bvh_config(SpecReader& r) {
  BvhConfig c;
  const std::string b = r.get_choice("builder", "binned", kBuilders);
  c.builder = b == "midpoint" ? BvhBuilder::midpoint
              : b == "median" ? BvhBuilder::median
              : b == "sweep"  ? BvhBuilder::sweep
              : b == "binned" ? BvhBuilder::binned
                              : BvhBuilder::spatial;
  c.width = std::stoi(r.get_choice("width", "8", kWidths));
  // Wide trees test leaves a packet of kPacketWidth triangles at a time: leaves of up to two
  // packets cut node visits on thin, overlapping geometry (bench_bvh, against embree-robust:
  // walls diffuse 0.86 -> 0.95, shadow 0.82 -> 0.98; grass 0.81-0.85 -> 0.90-1.01; CGAL meshes
  // within -3%..+3%). The SAH builders at width 8 may stop at up to four packets, where the SAH
  // finds a leaf cheaper (bench_bvh, 7 scenes, 2 runs, 8 -> 16: diffuse +2-4% robust, +4-7%
  // robust=off; shadow +9-13%; primary -1%..+3%; 24 and 32 measured as 16).
  const bool sah = c.builder == BvhBuilder::sweep || c.builder == BvhBuilder::binned || c.builder == BvhBuilder::spatial;
  const int default_leaf = c.width == 2 ? 4 : c.width == 8 && sah ? 16 : 8;
  c.max_leaf_size = static_cast<int>(r.get_int("leaf_size", default_leaf, 1, 64));
  c.bins = static_cast<int>(r.get_int("bins", 32, 2, 256));
  // Wide trees test a packet of kPacketWidth triangles for about the price of one box test, so
  // their binary tree is built with costlier traversal, i.e. fuller leaves (measured on the CGAL
  // meshes: c_trav = 3 is ~10% faster than 1 at width 8 and halves the packed-leaf memory).
  c.fitted_cost =
      read_sah_constants(r, c.width == 2 ? "bvh" : "bvh" + std::to_string(c.width), c.width == 2 ? 1.0 : 3.0, 1.0, c.cost);
  // Wide trees' leaves are tested a packet at a time, so their SAH counts whole packets (as
  // Embree's counts blocks of 4 triangles).
  c.cost.leaf_block = c.width == 2 ? 1u : static_cast<unsigned>(kPacketWidth);
  c.spatial_alpha = r.get_double("alpha", 1e-5, 0.0, 1.0);
  c.max_duplication = r.get_double("max_duplication", 1.0, 0.0, 16.0);
  c.collapse = r.get_choice("collapse", "sah", kCollapses) == "greedy" ? BvhCollapse::greedy : BvhCollapse::sah;
  c.nodes = r.get_choice("nodes", "full", kNodeKinds) == "quantized" ? BvhNodes::quantized : BvhNodes::full;
  if (c.nodes == BvhNodes::quantized && c.width == 2)
    throw InputError("accelerator '" + r.spec().text + "': nodes=quantized needs a wide tree (width=4 or 8)");
  c.leaves = r.get_choice("leaves", "packed", kLeafKinds) == "indexed" ? BvhLeaves::indexed : BvhLeaves::packed;
  if (c.leaves == BvhLeaves::indexed && c.width == 2)
    throw InputError("accelerator '" + r.spec().text + "': leaves=indexed needs a wide tree (width=4 or 8)");
  c.robust = r.get_bool("robust", true);
  c.kernel = read_kernel_choice(r, c.robust ? KernelChoice::certified : KernelChoice::watertight);
  if (c.kernel == KernelChoice::certified && !c.robust)
    throw InputError("accelerator '" + r.spec().text + "': kernel=certified needs the conservative box test (robust=on)");
  c.threads = static_cast<int>(r.get_int("threads", 0, 0, 1024));
  c.optimize = r.get_choice("optimize", "none", kOptimizations) == "reinsert" ? BvhOptimize::reinsert : BvhOptimize::none;
  c.optimize_passes = static_cast<int>(r.get_int("optimize_passes", 0, 0, 1000000));
  c.optimize_budget = r.get_double("optimize_budget", 0.0, 0.0, 1e6);
  return c;
}

namespace {

std::unique_ptr<Aggregate> make_bvh(std::shared_ptr<const Scene> scene, const BvhConfig& config) {
  if (scene->instanced())
    return make_instanced_for_kernel(config.kernel, *scene, [&](std::shared_ptr<const Scene> base) {
      return make_bvh(std::move(base), config);
    });
  return std::make_unique<Bvh>(std::move(scene), config);
}

/// `cost=MODEL` resolved where its constants mean what the model measured: the binary family's
/// (width 2) per binary node visit and primitive test, so in the binary SAH; the wide families'
/// per wide node visit and primitive test, so in the SAH collapse, which forms the wide nodes
/// (the binary tree it collapses keeps `cost`'s defaults; with collapse=greedy, which has no
/// costs, the binary SAH takes them as before).
std::unique_ptr<Aggregate> build_bvh_with_context(std::shared_ptr<const Scene> scene, SpecReader& r,
                                                  const BuildContext& context) {
  BvhConfig config = read_bvh_config(r);
  const double primitives = scene->total_primitive_count();
  if (config.fitted_cost && config.width != 2 && config.collapse == BvhCollapse::sah) {
    BvhSahCost fitted;
    apply_fitted_cost(config.fitted_cost, context, primitives, fitted);
    config.wide_cost = {fitted.c_trav, fitted.c_isect * kPacketWidth};
  } else {
    apply_fitted_cost(config.fitted_cost, context, primitives, config.cost);
  }
  return make_bvh(std::move(scene), config);
}

}  // namespace

AccelKind make_bvh_kind() {
  return {"bvh",
          "BVH: midpoint/median/sweep-SAH/binned-SAH/SBVH builders, near-first stack traversal",
          bvh_params(),
          build_bvh_with_context,
          [](SpecReader& r) -> AccuracyBound {
            const BvhConfig c = read_bvh_config(r);
            if (c.robust) return kernel_accuracy(c.kernel, "Ize's conservative box test");
            AccuracyBound b = float_accuracy(
                0.5, 1e-3,
                "the fast variant (plain slab test, Moller-Trumbore) may lose crossing rays through shared edges and "
                "vertices (bound: 50% of edge/vertex-aimed crossing rays, 0.1% of other crossing rays); touching, "
                "on-surface and ill-conditioned rays: no agreement claimed");
            b.kernel = "mt";
            return b;
          },
          {"width=2", "width=4", "robust=off", "width=2,robust=off", "width=4,robust=off",
           "builder=midpoint", "builder=median,leaf_size=1", "width=4,builder=median,leaf_size=1", "builder=spatial",
           "builder=sweep", "cost=default", "width=2,cost=default", "kernel=watertight", "kernel=watertight,width=4",
           "kernel=watertight,width=2", "optimize=reinsert", "optimize=reinsert,width=2", "nodes=quantized",
           "nodes=quantized,width=4,robust=off", "nodes=quantized,kernel=watertight", "leaves=indexed",
           "leaves=indexed,nodes=quantized", "leaves=indexed,width=4,robust=off", "leaves=indexed,kernel=watertight",
           "collapse=greedy", "collapse=greedy,width=4,robust=off"}};
}

namespace {
const AccelRegistration bvh_registration(make_bvh_kind(), 70);
}

}  // namespace raylab
