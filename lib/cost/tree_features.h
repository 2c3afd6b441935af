#pragma once
/// Features of a built acceleration structure computed from the structure alone, without
/// tracing a ray: what a cost model can predict time from before any ray is shot.
///
/// Surface-area expectations (MacDonald and Booth 1990; the lecture's "probabilities proportional
/// to surface area"): for a random line under the Cauchy–Crofton measure that meets the root box,
/// the probability that it meets a convex cell n is SA(n)/SA(root), so
///   expected_inner  = Σ_{interior n} SA(n)/SA(root)      (interior nodes visited),
///   expected_leaves = Σ_{leaves l, N(l) > 0} SA(l)/SA(root),
///   expected_tests  = Σ_l N(l)·SA(l)/SA(root)             (primitive tests, no early exit),
///   expected_test_groups = Σ_l ⌈N(l)/4⌉·SA(l)/SA(root)    (tests in SIMD groups of 4),
/// and the SAH cost at C_trav = C_isect = 1 is expected_inner + expected_tests, from which the
/// cost at any ratio follows. Grids count every cell as an interior visit and every non-empty cell
/// as a leaf visit, as their traversal counters do.
///
/// End-point overlap (Aila, Karras and Laine, "On Quality Metrics of Bounding Volume
/// Hierarchies", HPG 2013): the chance that a ray ending on the surface ends inside a node's box
/// on geometry the node does not hold,
///   epo = Σ_n w(n)·A(S \ Q(n) ∩ box(n)) / A(S),  w = 1 (interior) or N(l) (leaf),
/// A the triangle area, Q(n) the primitives of n's subtree. It is 0 for spatial subdivisions,
/// whose cells do not overlap; computed on the binary BVH for every BVH width.
///
/// Memory features (fill_memory_features): estimates from counts and surface areas, since the
/// traversals' counters do not record addresses. A *cell* is an interior node or a non-empty leaf
/// (grids: every cell's entry, and the reference list of a non-empty one), of b = bytes /
/// (inner_nodes + leaves) bytes on average.
///   lines_per_ray_est = (nodes + leaves visited per ray) · (1 + (b − 1)/64), the expected number of
///     64-byte lines a block of b bytes at a random offset spans: distinct lines, because a ray
///     visits a cell at most once (a grid cell on its walk once);
///   working_set_bytes_est = min(bytes, b · Σ_cells [1 − (1 − p_c)^B]), p_c = SA(c)/SA(root), the
///     expected bytes of distinct cells that B = kWorkingSetBatch independent random lines meeting
///     the root box visit (Cauchy–Crofton, as above); coherent camera rays share more and touch less;
///   bytes_over_l2, bytes_over_llc = bytes against this machine's caches (provenance.h).
#include <cstddef>
#include <string>
#include <vector>

#include "cost/run_record.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

struct TreeFeatures {
  double expected_inner = 0.0;
  double expected_leaves = 0.0;
  double expected_tests = 0.0;
  double expected_test_groups = 0.0;
  double epo = 0.0;
  std::size_t inner_nodes = 0;
  std::size_t leaves = 0;      ///< non-empty leaves (cells holding primitives)
  std::size_t references = 0;  ///< primitive references over all leaves
  int depth = 0;               ///< of the deepest leaf (root: 0)
  std::size_t bytes = 0;       ///< AccelStats::bytes
  double batch_cells = 0.0;    ///< Σ_cells [1 − (1 − p_c)^kWorkingSetBatch]: distinct cells a batch of lines visits

  double sah_1_1() const { return expected_inner + expected_tests; }
};

/// The rays of the batch whose working set working_set_bytes_est estimates: a 64×64 tile.
inline constexpr int kWorkingSetBatch = 4096;

/// The structure family of an accelerator spec: its name, except that a BVH of width 4 or 8 is
/// `bvh4` or `bvh8` (a different traversal with different constants). Throws InputError for an
/// unknown accelerator.
std::string structure_family(const std::string& accel_spec);

/// The families tree_features() knows (the lab's own structures and brute force).
const std::vector<std::string>& feature_families();

/// Features of `accel`, built over `scene` (not instanced). Throws InputError when the
/// accelerator's family has no feature extractor (Embree, the exact oracle, instanced scenes).
TreeFeatures tree_features(const Aggregate& accel, const Scene& scene);

/// Copies `f` into the feature columns of `record` (e_inner ... bytes).
void fill_tree_features(RunRecord& record, const TreeFeatures& f);

/// Fills the memory columns of `record` (lines_per_ray_est, working_set_bytes_est, bytes_over_l2,
/// bytes_over_llc) from `f`, the record's counters (nodes_per_ray, leaves_per_ray: 0 gives a
/// lines estimate of 0) and its cache sizes (l2_bytes, llc_bytes: 0 gives a ratio of 0).
void fill_memory_features(RunRecord& record, const TreeFeatures& f);

/// A record that stands for rays of `ray_kind` on a structure with features `f`, measured on
/// this machine (cache sizes from provenance.h): what the tree level of a cost model predicts from.
RunRecord record_for_prediction(const TreeFeatures& f, const std::string& ray_kind, double primitives);

}  // namespace raylab
