#include "accel/kdtree/kdtree_build.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include "accel/common/huge_pages.h"
#include "accel/kdtree/sah_sweep_events.h"
#include "accel/kdtree/sah_sweep_sort.h"
#include "geometry/input_error.h"

namespace raylab {

int kd_max_depth(const KdTreeConfig& config, std::size_t n) {
  if (config.max_depth > 0) return std::min(config.max_depth, 64);
  const double d = 8.0 + 1.3 * std::log2(static_cast<double>(std::max<std::size_t>(n, 1)));
  return std::min(64, static_cast<int>(std::lround(d)));
}

namespace {

class KdBuilderImpl {
 public:
  KdBuilderImpl(const Scene& scene, const KdTreeConfig& config, KdTreeData& out)
      : scene_(scene), config_(config), out_(out), kept_(scene.primitive_count() + kKeptPadding, 0) {}

  void build_root(std::vector<PrimRef> refs) {
    max_depth_ = kd_max_depth(config_, refs.size());
    root_sa_ = surface_area_d(out_.bounds);
    levels_.resize(static_cast<std::size_t>(max_depth_) + 2);
    Level& root = levels_[0];
    root.refs[0] = std::move(refs);
    const bool use_events = config_.builder == KdBuilder::sah && config_.sweep == KdSweep::events;
    if (use_events)
      for (int a = 0; a < 3; ++a) {
        root.events[0].axis[a].reserve(2 * root.refs[0].size());  // at most two per reference
        append_events(root.refs[0], a, root.events[0].axis[a]);
        sort_root_events(root.events[0].axis[a]);
      }
    build(root.refs[0], use_events ? &root.events[0] : nullptr, out_.bounds, 0);
  }

 private:
  /// The references and events of the two children of the node being split at depth d - 1 live
  /// in levels_[d]: a node at depth d writes only levels_[d + 1], so the right child's data stay
  /// intact while the left subtree is built.
  static constexpr std::size_t kReleaseAbove = 1u << 14;

  struct Level {
    std::vector<PrimRef> refs[2];
    NodeEvents events[2];
  };

  /// Room for `n` references in an empty list (a child gets at most its parent's n), so that it
  /// never grows by copying while filled; the room at least doubles, so a level's list is
  /// reallocated O(log N) times; new room of 4 MiB and more is asked for in huge pages.
  static void reserve_refs(std::vector<PrimRef>& refs, std::size_t n) {
    if (refs.capacity() >= n) return;
    refs.reserve(std::max(n, 2 * refs.capacity()));
    advise_huge_pages(refs.data(), refs.capacity() * sizeof(PrimRef));
  }

  double area_weight(const Bounds3f& box) const { return root_sa_ > 0.0 ? surface_area_d(box) / root_sa_ : 1.0; }

  void make_leaf(std::span<const PrimRef> refs, const Bounds3f& box, int depth) {
    const auto first = static_cast<std::uint32_t>(out_.prims.size());
    for (const PrimRef& r : refs) out_.prims.push_back(r.prim);
    std::sort(out_.prims.begin() + first, out_.prims.end());
    out_.nodes.push_back(KdNode::make_leaf(first, static_cast<std::uint32_t>(refs.size())));
    out_.sah_cost += config_.cost.leaf(refs.size()) * area_weight(box);
    ++out_.leaves;
    out_.depth = std::max(out_.depth, depth);
  }

  /// The split to make, or an invalid candidate for a leaf.
  SplitCandidate choose(std::span<const PrimRef> refs, const NodeEvents* events, const Bounds3f& box) {
    const std::size_t n = refs.size();
    SplitCandidate c;
    switch (config_.builder) {
      case KdBuilder::sah:
        c = events ? find_split_events(*events, box, n, config_.cost) : find_split_sort(refs, box, config_.cost);
        if (c.valid() && !(c.cost < config_.cost.leaf(n))) c = {};
        return c;
      case KdBuilder::midpoint:
      case KdBuilder::median: {
        if (n <= static_cast<std::size_t>(config_.leaf_size)) return c;
        const int a = box.largest_axis();
        if (!(box.lo[a] < box.hi[a])) return c;
        float pos = 0.5f * (box.lo[a] + box.hi[a]);
        if (config_.builder == KdBuilder::median) {
          std::vector<float> centres(n);
          for (std::size_t i = 0; i < n; ++i) centres[i] = 0.5f * (refs[i].box.lo[a] + refs[i].box.hi[a]);
          std::nth_element(centres.begin(), centres.begin() + n / 2, centres.end());
          if (centres[n / 2] > box.lo[a] && centres[n / 2] < box.hi[a]) pos = centres[n / 2];
        }
        if (!(pos > box.lo[a] && pos < box.hi[a])) return c;
        c.axis = a;
        c.pos = pos;
        return c;
      }
    }
    return c;
  }

  /// Builds the subtree of a node at `depth` whose references are `refs` (and, for the event
  /// sweep, whose sorted events are `events`); both must live outside levels_[depth + 1], and
  /// both are consumed.
  void build(std::vector<PrimRef>& refs, NodeEvents* events, const Bounds3f& box, int depth) {
    const std::size_t n = refs.size();
    SplitCandidate split;
    if (n > 0 && depth < max_depth_) split = choose(refs, events, box);
    if (!split.valid()) {
      make_leaf(refs, box, depth);
      return;
    }
    const int a = split.axis;
    const float s = split.pos;
    const Bounds3f lbox = box.below(a, s), rbox = box.above(a, s);

    Level& next = levels_[static_cast<std::size_t>(depth) + 1];
    if (split.empty_child >= 0) {
      // An empty-space cut-off: the references, and their sorted events, pass unchanged to the
      // other child, as the split below would produce them.
      const int full = 1 - split.empty_child;
      next.refs[full].swap(refs);
      if (events) std::swap(next.events[full], *events);
      out_.sah_cost += config_.cost.c_trav * area_weight(box);
      const auto index = static_cast<std::uint32_t>(out_.nodes.size());
      out_.nodes.push_back(KdNode::make_interior(a, s));
      if (full == 1) make_leaf({}, lbox, depth + 1);
      else build(next.refs[0], events ? &next.events[0] : nullptr, lbox, depth + 1);
      out_.nodes[index].set_above_child(static_cast<std::uint32_t>(out_.nodes.size()));
      if (full == 0) make_leaf({}, rbox, depth + 1);
      else build(next.refs[1], events ? &next.events[1] : nullptr, rbox, depth + 1);
      return;
    }
    std::vector<PrimRef>& left = next.refs[0];
    std::vector<PrimRef>& right = next.refs[1];
    std::vector<PrimRef>& left_straddlers = left_straddlers_;
    std::vector<PrimRef>& right_straddlers = right_straddlers_;
    left.clear();
    right.clear();
    reserve_refs(left, n);
    reserve_refs(right, n);
    left_straddlers.clear();
    right_straddlers.clear();
    // The parent events each child keeps, per axis (one if planar along the axis, else two).
    std::size_t kept_l[3] = {0, 0, 0}, kept_r[3] = {0, 0, 0};
    auto count_kept = [](const PrimRef& r, KeptEvents bits, int child, std::size_t(&k)[3]) {
      for (int b = 0; b < 3; ++b)
        if ((bits >> (2 * b + child)) & 1u) k[b] += r.box.lo[b] == r.box.hi[b] ? 1 : 2;
    };
    for (const PrimRef& r : refs) {
      if (r.box.hi[a] < s) {
        left.push_back(r);
        kept_[r.prim] = kKeepAllLower;
        count_kept(r, kKeepAllLower, 0, kept_l);
      } else if (r.box.lo[a] > s) {
        right.push_back(r);
        kept_[r.prim] = kKeepAllUpper;
        count_kept(r, kKeepAllUpper, 1, kept_r);
      } else {
        bool in_l, in_r;
        ref_meets_children(scene_, r, box, a, s, config_.clip, in_l, in_r);
        Bounds3f in_lbox, in_rbox;
        if (in_l && in_r)
          ref_bounds_in_children(scene_, r, box, a, s, config_.clip, in_lbox, in_rbox);
        else if (in_l)
          in_lbox = ref_bounds_in(scene_, r, lbox, config_.clip);
        else if (in_r)
          in_rbox = ref_bounds_in(scene_, r, rbox, config_.clip);
        KeptEvents bits = 0;
        if (in_l) {
          left_straddlers.push_back({in_lbox, r.prim});
          const KeptEvents kl = kept_events(r.box, in_lbox, 0);
          count_kept(r, kl, 0, kept_l);
          bits |= kl;
        }
        if (in_r) {
          right_straddlers.push_back({in_rbox, r.prim});
          const KeptEvents kr = kept_events(r.box, in_rbox, 1);
          count_kept(r, kr, 1, kept_r);
          bits |= kr;
        }
        kept_[r.prim] = bits;
      }
    }
    // midpoint and median stop when a split separates nothing.
    if (config_.builder != KdBuilder::sah && left.size() + left_straddlers.size() == n &&
        right.size() + right_straddlers.size() == n) {
      make_leaf(refs, box, depth);
      return;
    }
    if (events)
      split_events(*events, kept_, left_straddlers, right_straddlers, kept_l, kept_r, next.events[0], next.events[1],
                   split_scratch_);
    left.insert(left.end(), left_straddlers.begin(), left_straddlers.end());
    right.insert(right.end(), right_straddlers.begin(), right_straddlers.end());
    // The node's own lists are dead now; large ones are freed (there are few such nodes), so
    // that the memory held along the current path stays close to the pending right children.
    if (n > kReleaseAbove) {
      std::vector<PrimRef>().swap(refs);
      if (events) *events = NodeEvents{};
    }

    out_.sah_cost += config_.cost.c_trav * area_weight(box);
    const auto index = static_cast<std::uint32_t>(out_.nodes.size());
    out_.nodes.push_back(KdNode::make_interior(a, s));
    build(left, events ? &next.events[0] : nullptr, lbox, depth + 1);
    out_.nodes[index].set_above_child(static_cast<std::uint32_t>(out_.nodes.size()));
    build(right, events ? &next.events[1] : nullptr, rbox, depth + 1);
  }

  const Scene& scene_;
  const KdTreeConfig& config_;
  KdTreeData& out_;
  std::vector<KeptEvents> kept_;  ///< by primitive id (and kKeptPadding more), for split_events
  std::vector<Level> levels_;
  std::vector<PrimRef> left_straddlers_, right_straddlers_;
  SplitEventsScratch split_scratch_;
  int max_depth_ = 0;
  double root_sa_ = 0.0;
};

}  // namespace

KdTreeData build_kdtree(const Scene& scene, const KdTreeConfig& config) {
  if (scene.primitive_count() >= SplitEvent::kMaxPrims)
    throw InputError("kdtree: the scene has " + std::to_string(scene.primitive_count()) +
                     " primitives; the kd-tree builds at most 2^30 - 1");
  KdTreeData data;
  data.bounds = scene.bounds();
  KdBuilderImpl builder(scene, config, data);
  builder.build_root(make_root_refs(scene));
  return data;
}

}  // namespace raylab
