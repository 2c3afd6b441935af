#include "accel/bvh/bvh_optimize.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "accel/bvh/bvh_build.h"
#include "accel/common/build_array_allocator.h"
#include "accel/kdtree/sah_cost.h"

namespace raylab {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Each pass chooses this fraction of the interior nodes (at least one), and skips the nodes
/// chosen in the last kCooldownPasses passes (so a round of 1/kBatchFraction passes chooses each
/// node about once): without that, moves rejected as no better are retried on the same nodes,
/// whose inefficiency they leave unchanged, and the passes stall (cgal:bunny00, width 2, binned:
/// without it, Σ SA of the interior nodes stopped 0.35% lower, after ten passes without progress;
/// with it, 2.8% lower).
constexpr double kBatchFraction = 0.02;
constexpr int kCooldownPasses = 50;
/// Convergence: the optimisation ends when kStalePasses passes in a row (a round) lowered the
/// interior area by less than kMinProgress (relative) in all.
constexpr int kStalePasses = 50;
constexpr double kMinProgress = 1e-3;

/// f(begin, end) over [0, n): in order on one thread, else in TBB tasks of kGrain elements.
/// Callers write each element alone, so the result does not depend on the thread count.
template <class F>
void for_blocks(std::size_t n, int threads, const F& f) {
  constexpr std::size_t kGrain = std::size_t{1} << 14;
  if (threads == 1 || n <= kGrain) {
    f(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
}

Bounds3f merged(Bounds3f a, const Bounds3f& b) {
  a.extend(b);
  return a;
}

bool same_box(const Bounds3f& a, const Bounds3f& b) {
  return a.lo.x == b.lo.x && a.lo.y == b.lo.y && a.lo.z == b.lo.z && a.hi.x == b.hi.x && a.hi.y == b.hi.y &&
         a.hi.z == b.hi.z;
}

/// A node of the tree as linked nodes (indexed as the input's node array), so that subtrees can
/// move: 32 bytes, what the search reads of a node in one cache line. An interior node holds its
/// children; a leaf (kLeafBit set in `left`) its primitive count and `first`, so that the tree can
/// be written back over the input's nodes.
struct LinkedNode {
  Bounds3f box;
  std::uint32_t left;   ///< left child, or kLeafBit | primitive count
  std::uint32_t right;  ///< right child, or the leaf's first reference
};
static_assert(sizeof(LinkedNode) == 32);
constexpr std::uint32_t kLeafBit = std::uint32_t{1} << 31;

class Reinserter {
 public:
  /// `bvh` has fewer than 2^31 nodes (optimize_bvh_reinsertion checks). `threads` as in
  /// optimize_bvh_reinsertion.
  Reinserter(const Bvh2& bvh, int threads) : threads_(threads) {
    const std::size_t n = bvh.nodes.size();
    // BuildArrays, in huge pages: a 4 KiB page fault costs ~3.5 ms per MB first written on this
    // VM (build_array_allocator.h).
    nodes_.resize(n);
    parent_.resize(n);
    last_chosen_.resize(n);
    parent_[0] = kNone;
    for_blocks(n, threads_, [&](std::size_t begin, std::size_t end) {
      for (auto i = static_cast<std::uint32_t>(begin); i < end; ++i) {
        const Bvh2Node& node = bvh.nodes[i];
        last_chosen_[i] = -kCooldownPasses - 1;
        nodes_[i].box = node.box;
        if (node.is_leaf()) {
          nodes_[i].left = kLeafBit | node.count;
          nodes_[i].right = node.first;
          continue;
        }
        nodes_[i].left = node.first;
        nodes_[i].right = node.first + 1;
        parent_[node.first] = parent_[node.first + 1] = i;
      }
    });
    interior_.reserve(n / 2 + 1);
    for (std::uint32_t i = 0; i < n; ++i)
      if (!bvh.nodes[i].is_leaf()) interior_.push_back(i);
    // Interior boxes as the union of their children (builders may leave SBVH parents larger),
    // children before parents: every child has a larger index than its parent.
    for (auto it = interior_.rbegin(); it != interior_.rend(); ++it)
      nodes_[*it].box = merged(nodes_[nodes_[*it].left].box, nodes_[nodes_[*it].right].box);
  }

  bool is_leaf(std::uint32_t i) const { return (nodes_[i].left & kLeafBit) != 0; }

  /// Σ SA over interior nodes: the only part of the SAH cost that reinsertion changes.
  double interior_area() const {
    double sum = 0.0;
    for (std::uint32_t i : interior_) sum += surface_area_d(nodes_[i].box);
    return sum;
  }

  int depth() const {
    int deepest = 0;
    std::vector<std::pair<std::uint32_t, int>> todo = {{root_, 0}};
    while (!todo.empty()) {
      const auto [i, d] = todo.back();
      todo.pop_back();
      deepest = std::max(deepest, d);
      if (is_leaf(i)) continue;
      todo.push_back({nodes_[i].right, d + 1});  // left first: the input's depth-first order
      todo.push_back({nodes_[i].left, d + 1});
    }
    return deepest;
  }

  /// One pass: for the interior nodes of largest inefficiency M_comb = M_sum·M_min·M_area
  /// (Bittner et al. 2013: the node's area over its children's mean area, over their least
  /// area, and the node's area), most inefficient first, each child, the larger first, moves
  /// where the cost drops most (move()). `out_of_time` is asked every kDeadlineStride nodes; once
  /// it says yes, the pass ends. Returns the number of subtrees moved.
  template <class OutOfTime>
  std::size_t pass(const OutOfTime& out_of_time) {
    ++pass_;
    // Every interior node's M_comb at its place in interior_, -1 for a node not eligible (M_comb
    // > 0 for every eligible one), which the compaction below drops.
    candidates_.resize(interior_.size());
    for_blocks(interior_.size(), threads_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const std::uint32_t i = interior_[k];
        candidates_[k] = {-1.0, i};
        if (i == root_ || pass_ - last_chosen_[i] <= kCooldownPasses) continue;
        const LinkedNode& node = nodes_[i];
        const double a = surface_area_d(node.box);
        if (!(a > 0.0)) continue;
        const double al = surface_area_d(nodes_[node.left].box), ar = surface_area_d(nodes_[node.right].box);
        const double tiny = a * 1e-12;
        const double m_sum = a / std::max(0.5 * (al + ar), tiny), m_min = a / std::max(std::min(al, ar), tiny);
        candidates_[k].first = m_sum * m_min * a;
      }
    });
    const auto not_eligible = [](const auto& c) { return !(c.first > 0.0); };
    candidates_.erase(std::remove_if(candidates_.begin(), candidates_.end(), not_eligible), candidates_.end());
    const auto batch = std::min(candidates_.size(),
                                std::max<std::size_t>(1, static_cast<std::size_t>(kBatchFraction * interior_.size())));
    auto worse_first = [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); };
    std::nth_element(candidates_.begin(), candidates_.begin() + batch, candidates_.end(), worse_first);
    candidates_.resize(batch);
    std::sort(candidates_.begin(), candidates_.end(), worse_first);
    std::size_t moves = 0;
    for (std::size_t k = 0; k < candidates_.size(); ++k) {
      if (k % kDeadlineStride == kDeadlineStride - 1 && out_of_time()) break;
      const std::uint32_t n = candidates_[k].second;
      if (n == root_) continue;  // a node of the batch may have become the root
      const std::uint32_t a = nodes_[n].left, b = nodes_[n].right;
      const bool larger_first = surface_area_d(nodes_[a].box) >= surface_area_d(nodes_[b].box);
      moves += move(larger_first ? a : b);
      moves += move(larger_first ? b : a);
      last_chosen_[n] = pass_;
    }
    return moves;
  }

  /// How much the moves so far lowered Σ SA over the interior nodes (as the searches computed it).
  double saved() const { return saved_; }

  /// Writes the tree over `out`'s nodes (the input's, of the same count) as the builders lay it
  /// out: depth first, siblings adjacent, each node's children placed before either child's
  /// subtree. Leaves keep their `first` and `count`, so `out.prims` stays as it is.
  void emit(Bvh2& out) const {
    std::uint32_t next = 1;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo = {{root_, 0u}};  // (node, slot)
    while (!todo.empty()) {
      const auto [i, slot] = todo.back();
      todo.pop_back();
      const LinkedNode& node = nodes_[i];
      Bvh2Node& written = out.nodes[slot];
      written.box = node.box;
      if (is_leaf(i)) {
        written.first = node.right;
        written.count = node.left & ~kLeafBit;
        continue;
      }
      written.first = next;
      written.count = 0;
      todo.push_back({node.right, next + 1});
      todo.push_back({node.left, next});
      next += 2;
    }
  }

 private:
  /// The nodes asked whether the time budget is spent, in a pass.
  static constexpr std::size_t kDeadlineStride = 64;

  void replace_child(std::uint32_t p, std::uint32_t old_child, std::uint32_t new_child) {
    (nodes_[p].left == old_child ? nodes_[p].left : nodes_[p].right) = new_child;
    parent_[new_child] = p;
  }

  /// Recomputes the boxes from `i` up to the root, stopping where a box is unchanged; returns
  /// the change of Σ SA over those nodes.
  double refit_from(std::uint32_t i) {
    double change = 0.0;
    for (; i != kNone; i = parent_[i]) {
      LinkedNode& node = nodes_[i];
      const Bounds3f b = merged(nodes_[node.left].box, nodes_[node.right].box);
      if (same_box(b, node.box)) break;
      change += surface_area_d(b) - surface_area_d(node.box);
      node.box = b;
    }
    return change;
  }

  /// Moves subtree `x` (not the root) where Σ SA over the interior nodes drops most, if it drops:
  /// x's parent p leaves the tree (x's sibling takes its place), and becomes x's new parent at
  /// the position best_position() finds, or at the old one when that is no better. Returns whether x moved.
  bool move(std::uint32_t x) {
    const std::uint32_t p = parent_[x];
    const std::uint32_t sibling = nodes_[p].left == x ? nodes_[p].right : nodes_[p].left;
    double gain = surface_area_d(nodes_[p].box);
    if (p == root_) {
      root_ = sibling;
      parent_[sibling] = kNone;
    } else {
      const std::uint32_t g = parent_[p];
      replace_child(g, p, sibling);
      gain -= refit_from(g);
    }
    std::uint32_t target = sibling;
    const double cost = best_position(x, &target);
    // The old position costs `gain` again: moves that do not lower the cost by more than rounding
    // go back, so that no pass raises the cost.
    if (!(cost < gain * (1.0 - 1e-9))) target = sibling;
    link(x, p, target);
    if (target == sibling) return false;
    saved_ += gain - cost;
    return true;
  }

  /// The position for subtree `x` (out of the tree) that least increases Σ SA over the interior
  /// nodes, by branch and bound (Bittner et al. 2013): making x the sibling of node t costs
  /// SA(t ∪ x) for their new parent plus the growth SA(a ∪ x) − SA(a) of each ancestor a of t
  /// (the induced cost); nodes are visited in order of induced cost, and a subtree is pruned when
  /// its induced cost plus SA(x), a lower bound of any position in it, is no better than the best
  /// position found. Returns that increase and stores the node in *best. Inlined into move():
  /// GCC 12 left it a call, 7-10% slower on trees of 10^4-10^5 nodes.
  [[gnu::always_inline]] inline double best_position(std::uint32_t x, std::uint32_t* best) {
    const Bounds3f bx = nodes_[x].box;
    const double ax = surface_area_d(bx);
    double best_cost = std::numeric_limits<double>::infinity();
    using Entry = std::pair<double, std::uint32_t>;  // (induced cost, node): ties by index, for determinism
    heap_.clear();
    heap_.push_back({0.0, root_});
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
      const auto [induced, t] = heap_.back();
      heap_.pop_back();
      if (induced + ax >= best_cost) break;
      const LinkedNode& node = nodes_[t];
      const double direct = surface_area_d(merged(node.box, bx));
      if (induced + direct < best_cost) {
        best_cost = induced + direct;
        *best = t;
      }
      if (is_leaf(t)) continue;
      const double below = induced + direct - surface_area_d(node.box);
      if (below + ax >= best_cost) continue;
      for (std::uint32_t c : {node.left, node.right}) {
        heap_.push_back({below, c});
        std::push_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
      }
    }
    return best_cost;
  }

  /// Makes `q` the parent of `x` and `t` in t's place. As the builders' splits do, the child whose
  /// box centre lies lower along q's longest axis comes first: any-hit traversal visits children
  /// in stored order (wide_bvh_traversal.h).
  void link(std::uint32_t x, std::uint32_t q, std::uint32_t t) {
    const std::uint32_t above = parent_[t];
    LinkedNode& node = nodes_[q];
    node.box = merged(nodes_[t].box, nodes_[x].box);
    const int axis = node.box.largest_axis();
    const bool x_first = nodes_[x].box.center()[axis] < nodes_[t].box.center()[axis];
    node.left = x_first ? x : t;
    node.right = x_first ? t : x;
    parent_[t] = parent_[x] = q;
    if (above == kNone) {
      root_ = q;
      parent_[q] = kNone;
    } else {
      replace_child(above, t, q);
      refit_from(above);
    }
  }

  BuildArray<LinkedNode> nodes_;
  BuildArray<std::uint32_t> parent_;
  BuildArray<std::uint32_t> interior_;
  BuildArray<int> last_chosen_;  ///< the pass that last chose each node (-kCooldownPasses - 1: none)
  BuildArray<std::pair<double, std::uint32_t>> candidates_;  ///< a pass's (inefficiency, node)
  std::vector<std::pair<double, std::uint32_t>> heap_;
  int threads_ = 1;
  std::uint32_t root_ = 0;
  int pass_ = 0;
  double saved_ = 0.0;
};

}  // namespace

BvhOptimizeStats optimize_bvh_reinsertion(Bvh2& bvh, const BvhSahCost& cost, int max_passes, double budget_seconds,
                                          int threads) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  BvhOptimizeStats stats;
  stats.cost_before = stats.cost_after = bvh_sah_cost(bvh, cost);
  // Fewer than two interior nodes leave nothing to move; 2^31 nodes and more do not fit
  // LinkedNode (a tree of 2^30 leaves, 64 GiB of nodes).
  if (bvh.nodes.size() < 5 || bvh.nodes.size() >= kLeafBit || !(stats.cost_before > 0.0)) {
    stats.seconds = seconds_since(start);
    return stats;
  }
  Reinserter r(bvh, threads);
  const double initial = r.interior_area();
  double anchor = initial;
  int stale = 0;
  // The budget is the passes' (bvh_config.h): its clock starts after the set-up.
  const auto passes_start = Clock::now();
  auto out_of_time = [&] { return budget_seconds > 0.0 && seconds_since(passes_start) >= budget_seconds; };
  while ((max_passes <= 0 || stats.passes < max_passes) && !out_of_time()) {
    stats.moves += r.pass(out_of_time);
    ++stats.passes;
    if (initial - r.saved() < anchor * (1.0 - kMinProgress)) {
      anchor = initial - r.saved();
      stale = 0;
    } else if (++stale >= kStalePasses) {
      break;
    }
  }
  // Every move lowers the cost, so the last tree is the best. It replaces the input unless it is
  // deeper than kBvhMaxDepth, or better only by rounding (the emitted tree sums in another order).
  if (r.interior_area() < initial * (1.0 - 1e-9) && r.depth() <= kBvhMaxDepth) {
    r.emit(bvh);
    stats.cost_after = bvh_sah_cost(bvh, cost);
  }
  stats.seconds = seconds_since(start);
  return stats;
}

}  // namespace raylab
