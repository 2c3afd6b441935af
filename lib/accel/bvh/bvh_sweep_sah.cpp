/// Full-sweep SAH builder (the lecture's "sweep build"; MacDonald and Booth 1990, Wald, Boulos
/// and Shirley 2007 §4): at each node, every split between consecutive centroids on each of the
/// three axes is evaluated with Cost = N_A·S_A + N_B·S_B.
///
/// The references are sorted by centroid once per axis (ties by id); a split stably partitions
/// the three orders, so each stays sorted within every node. Work: O(N log N) for the sort plus
/// O(N) per tree level (three sweeps and two stable partitions), O(N log N) for trees of
/// logarithmic depth. Serial.
#include <algorithm>
#include <numeric>

#include "accel/bvh/bvh_build_ref.h"
#include "accel/bvh/bvh_builders.h"
#include "accel/bvh/bvh_object_binning.h"
#include "accel/bvh/bvh_subtree.h"

namespace raylab {
namespace {

class SweepSahBuilder {
 public:
  SweepSahBuilder(const std::vector<Bounds3f>& boxes, const BvhConfig& config)
      : config_(config), n_(boxes.size()), boxes_(n_), left_(n_), right_area_(n_ + 1), scratch_(n_) {
    for (std::size_t i = 0; i < n_; ++i) boxes_[i] = bvh_build_box(boxes[i]);
    for (int a = 0; a < 3; ++a) {
      order_[a].resize(n_);
      std::iota(order_[a].begin(), order_[a].end(), 0u);
      std::vector<float> c(n_);
      for (std::size_t i = 0; i < n_; ++i) c[i] = boxes_[i].lo[a] + boxes_[i].hi[a];
      std::sort(order_[a].begin(), order_[a].end(),
                [&c](std::uint32_t x, std::uint32_t y) { return c[x] < c[y] || (c[x] == c[y] && x < y); });
    }
  }

  Bvh2 build() {
    BvhSubtree root;
    build_node(root, 0, 0, n_, 0);
    return bvh_concatenate(root, n_, [this](std::size_t k) { return order_[0][k]; });
  }

 private:
  struct Sweep {
    int axis = -1;
    std::size_t left_count = 0;
    double cost = std::numeric_limits<double>::infinity();  ///< N_A·S_A + N_B·S_B, half areas
  };

  /// Best split of order_[axis][begin, begin + n) into a prefix and a suffix.
  void sweep_axis(int axis, std::size_t begin, std::size_t n, Sweep& best, Bounds3f& node_box) {
    const std::uint32_t* ids = order_[axis].data() + begin;
    Bounds3f acc;
    for (std::size_t i = n; i-- > 1;) {
      acc.extend(boxes_[ids[i]]);
      right_area_[i] = bvh_half_area(acc);
    }
    acc.extend(boxes_[ids[0]]);
    node_box = acc;
    acc = Bounds3f();
    for (std::size_t i = 1; i < n; ++i) {
      acc.extend(boxes_[ids[i - 1]]);
      const double cost = double(bvh_half_area(acc)) * double(bvh_leaf_units(i, config_.cost.leaf_block)) +
                          right_area_[i] * double(bvh_leaf_units(n - i, config_.cost.leaf_block));
      if (cost < best.cost) best = {axis, i, cost};
    }
  }

  void make_leaf(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n) {
    out.nodes[slot].first = static_cast<std::uint32_t>(begin);
    out.nodes[slot].count = static_cast<std::uint32_t>(n);
  }

  void build_node(BvhSubtree& out, std::uint32_t slot, std::size_t begin, std::size_t n, int depth) {
    Sweep best;
    Bounds3f box;
    for (int a = 0; a < 3; ++a) sweep_axis(a, begin, n, best, box);
    out.nodes[slot].box = box;
    if (n == 1) return make_leaf(out, slot, begin, n);
    const bool small = n <= static_cast<std::size_t>(config_.max_leaf_size);
    const double half_area = bvh_half_area(box);
    if (depth >= kBvhMaxDepth - 32 || !(half_area > 0.0)) {
      // Median split on the presorted order of the box's largest axis.
      if (small) return make_leaf(out, slot, begin, n);
      best = {box.largest_axis(), n / 2, 0.0};
    } else if (small && !(bvh_split_cost(config_.cost, best.cost, half_area) <
                          bvh_leaf_cost(config_.cost, n))) {
      return make_leaf(out, slot, begin, n);
    }
    const std::uint32_t* chosen = order_[best.axis].data() + begin;
    for (std::size_t i = 0; i < n; ++i) left_[chosen[i]] = i < best.left_count;
    for (int a = 0; a < 3; ++a) {
      if (a == best.axis) continue;
      std::uint32_t* ids = order_[a].data() + begin;
      std::size_t l = 0, r = 0;
      for (std::size_t i = 0; i < n; ++i) (left_[ids[i]] ? ids[l++] : scratch_[r++]) = ids[i];
      std::copy(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(r), ids + l);
    }
    const auto child = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.resize(out.nodes.size() + 2);
    out.nodes[slot].first = child;
    out.nodes[slot].count = 0;
    build_node(out, child, begin, best.left_count, depth + 1);
    build_node(out, child + 1, begin + best.left_count, n - best.left_count, depth + 1);
  }

  const BvhConfig& config_;
  std::size_t n_;
  std::vector<Bounds3f> boxes_;
  std::vector<std::uint32_t> order_[3];
  std::vector<char> left_;
  std::vector<double> right_area_;
  std::vector<std::uint32_t> scratch_;
};

}  // namespace

Bvh2 build_bvh_sweep_sah(const std::vector<Bounds3f>& boxes, const BvhConfig& config) {
  if (boxes.empty()) return Bvh2{};
  return SweepSahBuilder(boxes, config).build();
}

}  // namespace raylab
