/// Binned SAH builder (Wald, "On fast construction of SAH-based bounding volume hierarchies",
/// 2007), parallel with TBB: large nodes bin in parallel chunks, and both children of a node of
/// at least kBvhTaskMinReferences references are built as separate tasks into their own subtrees
/// (bvh_subtree.h). Which nodes become tasks depends only on reference counts, and bins merge
/// exactly (min/max, integer sums), so the tree is the same with any thread count.
///
/// Nodes of at most kBvhSmallSweepMax references use a full sweep instead of bins.
///
/// Work: O(N) per tree level (one binning pass and one partition pass), O(N log N) in all for
/// trees of logarithmic depth; no heap allocation per node below kParallelBinMin references.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <memory>

#include "accel/common/huge_pages.h"
#include "accel/bvh/bvh_builders.h"
#include "accel/bvh/bvh_object_binning.h"
#include "accel/bvh/bvh_subtree.h"
#include "accel/common/tracer.h"

namespace raylab {
namespace {

constexpr std::size_t kParallelBinMin = 1 << 16;  ///< nodes this large bin in parallel
constexpr std::size_t kBinChunk = 1 << 15;

class BinnedSahBuilder {
 public:
  BinnedSahBuilder(BvhBuildRef* refs, const BvhConfig& config) : refs_(refs), config_(config) {}

  void build(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n, const BvhRangeBounds& bounds,
             int depth) const {
    const Bounds3f box = bounds.box();
    out.nodes[slot].box = box;
    const bool small = n <= static_cast<std::size_t>(config_.max_leaf_size);
    if (n == 1) return make_leaf(out, slot, begin, n);
    BvhRangeBounds left, right;
    std::size_t mid = 0;
    const int centroid_axis = bounds.centroid_axis();
    if (depth >= kBvhMaxDepth - 32 || centroid_axis < 0) {
      if (small) return make_leaf(out, slot, begin, n);
      mid = bvh_partition_median(refs_ + begin, n, centroid_axis, left, right);
    } else if (n <= kBvhSmallSweepMax) {
      const BvhSweepSplit s = bvh_best_small_split(refs_ + begin, n, config_.cost.leaf_block);
      const double half_area = bvh_half_area(box);
      const double split_cost = s.axis >= 0 && half_area > 0.0 ? bvh_split_cost(config_.cost, s.cost, half_area)
                                                                 : std::numeric_limits<double>::infinity();
      if (small && !(split_cost < bvh_leaf_cost(config_.cost, n)))
        return make_leaf(out, slot, begin, n);
      mid = s.axis >= 0 ? bvh_partition_small(refs_ + begin, n, s, left, right)
                        : bvh_partition_median(refs_ + begin, n, centroid_axis, left, right);
    } else {
      const BvhBinMapping map(bounds, bvh_object_bins(config_.bins, n));
      const BvhObjectSplit s = find_split(begin, n, map);
      const double half_area = bvh_half_area(box);
      const double split_cost = s.axis >= 0 && half_area > 0.0 ? bvh_split_cost(config_.cost, s.cost, half_area)
                                                                 : std::numeric_limits<double>::infinity();
      if (small && !(split_cost < bvh_leaf_cost(config_.cost, n)))
        return make_leaf(out, slot, begin, n);
      mid = s.axis >= 0 ? bvh_partition_object(refs_ + begin, n, map, s.axis, s.bin, left, right)
                        : bvh_partition_median(refs_ + begin, n, centroid_axis, left, right);
      if (mid == 0 || mid == n) mid = bvh_partition_median(refs_ + begin, n, -1, left, right);
    }
    bvh_split_node(out, slot, n, [&](BvhSubtree& sub, std::uint32_t child, int side) {
      if (side == 0) build(sub, child, begin, mid, left, depth + 1);
      else build(sub, child, begin + mid, n - mid, right, depth + 1);
    });
  }

 private:
  static void make_leaf(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n) {
    out.nodes[slot].first = static_cast<std::uint32_t>(begin);
    out.nodes[slot].count = static_cast<std::uint32_t>(n);
  }

  BvhObjectSplit find_split(std::size_t begin, std::size_t n, const BvhBinMapping& map) const {
    if (n < kParallelBinMin) {
      BvhObjectBins bins;
      bins.reset(map.bins);
      bins.add(refs_ + begin, n, map);
      return bvh_best_object_split(bins, config_.cost.leaf_block);
    }
    const std::size_t chunks = (n + kBinChunk - 1) / kBinChunk;
    auto bins = std::make_unique<BvhObjectBins[]>(chunks);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t c = r.begin(); c != r.end(); ++c) {
        const std::size_t lo = c * kBinChunk, hi = std::min(n, lo + kBinChunk);
        bins[c].reset(map.bins);
        bins[c].add(refs_ + begin + lo, hi - lo, map);
      }
    });
    for (std::size_t c = 1; c < chunks; ++c) bins[0].merge(bins[c]);
    return bvh_best_object_split(bins[0], config_.cost.leaf_block);
  }

  BvhBuildRef* refs_;
  const BvhConfig& config_;
};

/// The binned SAH tree over n references, reference i with the box box_of(i).
template <class BoxOf>
Bvh2 binned_sah(std::size_t n, BoxOf&& box_of, const BvhConfig& config) {
  if (n == 0) return Bvh2{};
  std::unique_ptr<BvhBuildRef[]> refs(new BvhBuildRef[n]);
  advise_huge_pages(refs.get(), n * sizeof(BvhBuildRef));
  BvhSubtree root;
  tbb::task_arena arena(resolve_thread_count(config.threads));
  arena.execute([&] {
    const BvhRangeBounds bounds = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, kBinChunk), BvhRangeBounds(),
        [&](const tbb::blocked_range<std::size_t>& r, BvhRangeBounds b) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            refs[i] = BvhBuildRef::make(bvh_build_box(box_of(i)), static_cast<std::uint32_t>(i));
            b.extend(refs[i]);
          }
          return b;
        },
        [](BvhRangeBounds a, const BvhRangeBounds& b) {
          a.extend(b);
          return a;
        });
    BinnedSahBuilder(refs.get(), config).build(root, 0, 0, n, bounds, 0);
  });
  return bvh_concatenate(root, n, [&](std::size_t k) { return refs[k].id; });
}

}  // namespace

Bvh2 build_bvh_binned_sah(const std::vector<Bounds3f>& boxes, const BvhConfig& config) {
  return binned_sah(boxes.size(), [&boxes](std::size_t i) { return boxes[i]; }, config);
}

Bvh2 build_bvh_binned_sah(const Scene& scene, const BvhConfig& config) {
  return binned_sah(scene.primitive_count(),
                    [&scene](std::size_t i) { return scene.primitive_bounds(static_cast<unsigned>(i)); }, config);
}

}  // namespace raylab
