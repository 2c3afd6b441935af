#include "accel/bvh/bvh_optimize.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "accel/bvh/bvh_build.h"
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

Bounds3f merged(Bounds3f a, const Bounds3f& b) {
  a.extend(b);
  return a;
}

bool same_box(const Bounds3f& a, const Bounds3f& b) {
  return a.lo.x == b.lo.x && a.lo.y == b.lo.y && a.lo.z == b.lo.z && a.hi.x == b.hi.x && a.hi.y == b.hi.y &&
         a.hi.z == b.hi.z;
}

/// The tree as linked nodes (indices of the input's node array), so that subtrees can move.
struct LinkedTree {
  std::vector<Bounds3f> box;
  std::vector<std::uint32_t> parent, left, right;  ///< left = right = kNone at leaves
  std::uint32_t root = 0;
};

class Reinserter {
 public:
  explicit Reinserter(const Bvh2& bvh) : input_(bvh) {
    const std::size_t n = bvh.nodes.size();
    t_.box.resize(n);
    t_.parent.assign(n, kNone);
    t_.left.assign(n, kNone);
    t_.right.assign(n, kNone);
    for (std::uint32_t i = 0; i < n; ++i) {
      const Bvh2Node& node = bvh.nodes[i];
      t_.box[i] = node.box;
      if (node.is_leaf()) continue;
      t_.left[i] = node.first;
      t_.right[i] = node.first + 1;
      t_.parent[node.first] = t_.parent[node.first + 1] = i;
      interior_.push_back(i);
    }
    last_chosen_.assign(n, -kCooldownPasses - 1);
    // Interior boxes as the union of their children (builders may leave SBVH parents larger),
    // children before parents: every child has a larger index than its parent.
    for (auto it = interior_.rbegin(); it != interior_.rend(); ++it)
      t_.box[*it] = merged(t_.box[t_.left[*it]], t_.box[t_.right[*it]]);
  }

  bool is_leaf(std::uint32_t i) const { return t_.left[i] == kNone; }

  /// Σ SA over interior nodes: the only part of the SAH cost that reinsertion changes.
  double interior_area() const {
    double sum = 0.0;
    for (std::uint32_t i : interior_) sum += surface_area_d(t_.box[i]);
    return sum;
  }

  int depth() const {
    int deepest = 0;
    std::vector<std::pair<std::uint32_t, int>> todo = {{t_.root, 0}};
    while (!todo.empty()) {
      const auto [i, d] = todo.back();
      todo.pop_back();
      deepest = std::max(deepest, d);
      if (is_leaf(i)) continue;
      todo.push_back({t_.left[i], d + 1});
      todo.push_back({t_.right[i], d + 1});
    }
    return deepest;
  }

  /// One pass: for the interior nodes of largest inefficiency M_comb = M_sum·M_min·M_area
  /// (Bittner et al. 2013: the node's area over its children's mean area, over their least
  /// area, and the node's area), most inefficient first, each child, the larger first, moves
  /// where the cost drops most (move()). Returns the number of subtrees moved.
  std::size_t pass() {
    std::vector<std::pair<double, std::uint32_t>> candidates;
    candidates.reserve(interior_.size());
    ++pass_;
    for (std::uint32_t i : interior_) {
      if (i == t_.root || pass_ - last_chosen_[i] <= kCooldownPasses) continue;
      const double a = surface_area_d(t_.box[i]);
      if (!(a > 0.0)) continue;
      const double al = surface_area_d(t_.box[t_.left[i]]), ar = surface_area_d(t_.box[t_.right[i]]);
      const double tiny = a * 1e-12;
      const double m_sum = a / std::max(0.5 * (al + ar), tiny), m_min = a / std::max(std::min(al, ar), tiny);
      candidates.push_back({m_sum * m_min * a, i});
    }
    const auto batch = std::min(candidates.size(),
                                std::max<std::size_t>(1, static_cast<std::size_t>(kBatchFraction * interior_.size())));
    auto worse_first = [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); };
    std::nth_element(candidates.begin(), candidates.begin() + batch, candidates.end(), worse_first);
    candidates.resize(batch);
    std::sort(candidates.begin(), candidates.end(), worse_first);
    std::size_t moves = 0;
    for (const auto& c : candidates) {
      if (c.second == t_.root) continue;  // a node of the batch may have become the root
      const std::uint32_t n = c.second;
      const std::uint32_t a = t_.left[n], b = t_.right[n];
      const bool larger_first = surface_area_d(t_.box[a]) >= surface_area_d(t_.box[b]);
      moves += move(larger_first ? a : b);
      moves += move(larger_first ? b : a);
      last_chosen_[n] = pass_;
    }
    return moves;
  }

  /// How much the moves so far lowered Σ SA over the interior nodes (as the searches computed it).
  double saved() const { return saved_; }

  /// The tree laid out as the builders lay it out: depth first, siblings adjacent, each node's
  /// children placed before either child's subtree. Leaves keep their `first` and `count`.
  Bvh2 emit() const {
    Bvh2 out;
    out.primitive_count = input_.primitive_count;
    out.prims = input_.prims;
    out.nodes.resize(input_.nodes.size());
    std::uint32_t next = 1;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo = {{t_.root, 0u}};  // (node, slot)
    while (!todo.empty()) {
      const auto [i, slot] = todo.back();
      todo.pop_back();
      if (is_leaf(i)) {
        out.nodes[slot] = input_.nodes[i];
        continue;
      }
      out.nodes[slot].box = t_.box[i];
      out.nodes[slot].first = next;
      out.nodes[slot].count = 0;
      todo.push_back({t_.right[i], next + 1});
      todo.push_back({t_.left[i], next});
      next += 2;
    }
    return out;
  }

 private:
  void replace_child(std::uint32_t p, std::uint32_t old_child, std::uint32_t new_child) {
    (t_.left[p] == old_child ? t_.left[p] : t_.right[p]) = new_child;
    t_.parent[new_child] = p;
  }

  /// Recomputes the boxes from `i` up to the root, stopping where a box is unchanged; returns
  /// the change of Σ SA over those nodes.
  double refit_from(std::uint32_t i) {
    double change = 0.0;
    for (; i != kNone; i = t_.parent[i]) {
      const Bounds3f b = merged(t_.box[t_.left[i]], t_.box[t_.right[i]]);
      if (same_box(b, t_.box[i])) break;
      change += surface_area_d(b) - surface_area_d(t_.box[i]);
      t_.box[i] = b;
    }
    return change;
  }

  /// Moves subtree `x` (not the root) where Σ SA over the interior nodes drops most, if it drops:
  /// x's parent p leaves the tree (x's sibling takes its place), and becomes x's new parent at
  /// the position best_position() finds, or at the old one when that is no better. Returns whether x moved.
  bool move(std::uint32_t x) {
    const std::uint32_t p = t_.parent[x];
    const std::uint32_t sibling = t_.left[p] == x ? t_.right[p] : t_.left[p];
    double gain = surface_area_d(t_.box[p]);
    if (p == t_.root) {
      t_.root = sibling;
      t_.parent[sibling] = kNone;
    } else {
      const std::uint32_t g = t_.parent[p];
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
  /// position found. Returns that increase and stores the node in *best.
  double best_position(std::uint32_t x, std::uint32_t* best) {
    const Bounds3f bx = t_.box[x];
    const double ax = surface_area_d(bx);
    double best_cost = std::numeric_limits<double>::infinity();
    using Entry = std::pair<double, std::uint32_t>;  // (induced cost, node): ties by index, for determinism
    heap_.clear();
    heap_.push_back({0.0, t_.root});
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
      const auto [induced, t] = heap_.back();
      heap_.pop_back();
      if (induced + ax >= best_cost) break;
      const double direct = surface_area_d(merged(t_.box[t], bx));
      if (induced + direct < best_cost) {
        best_cost = induced + direct;
        *best = t;
      }
      if (is_leaf(t)) continue;
      const double below = induced + direct - surface_area_d(t_.box[t]);
      if (below + ax >= best_cost) continue;
      for (std::uint32_t c : {t_.left[t], t_.right[t]}) {
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
    const std::uint32_t above = t_.parent[t];
    t_.box[q] = merged(t_.box[t], t_.box[x]);
    const int axis = t_.box[q].largest_axis();
    const bool x_first = t_.box[x].center()[axis] < t_.box[t].center()[axis];
    t_.left[q] = x_first ? x : t;
    t_.right[q] = x_first ? t : x;
    t_.parent[t] = t_.parent[x] = q;
    if (above == kNone) {
      t_.root = q;
      t_.parent[q] = kNone;
    } else {
      replace_child(above, t, q);
      refit_from(above);
    }
  }

  const Bvh2& input_;
  LinkedTree t_;
  std::vector<std::uint32_t> interior_;
  std::vector<std::pair<double, std::uint32_t>> heap_;
  std::vector<int> last_chosen_;  ///< the pass that last chose each node (-kCooldownPasses - 1: none)
  int pass_ = 0;
  double saved_ = 0.0;
};

}  // namespace

BvhOptimizeStats optimize_bvh_reinsertion(Bvh2& bvh, const BvhSahCost& cost, int max_passes, double budget_seconds) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  BvhOptimizeStats stats;
  stats.cost_before = stats.cost_after = bvh_sah_cost(bvh, cost);
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  // Fewer than two interior nodes leave nothing to move.
  if (bvh.nodes.size() < 5 || !(stats.cost_before > 0.0)) {
    stats.seconds = elapsed();
    return stats;
  }
  Reinserter r(bvh);
  const double initial = r.interior_area();
  double anchor = initial;
  int stale = 0;
  while ((max_passes <= 0 || stats.passes < max_passes) && (budget_seconds <= 0.0 || elapsed() < budget_seconds)) {
    stats.moves += r.pass();
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
    bvh = r.emit();
    stats.cost_after = bvh_sah_cost(bvh, cost);
  }
  stats.seconds = elapsed();
  return stats;
}

}  // namespace raylab
