#include "accel/bvh/wide_bvh.h"

#include "accel/common/huge_pages.h"
#include "accel/common/tracer.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>

namespace raylab {

namespace {

/// Trees of at least this many binary nodes are collapsed by parallel tasks (when more than one
/// thread is allowed): the SAH cost pass solves the subtrees below its top kSahParallelDepth
/// levels as tasks, and the emission writes the subtrees below its top kEmitParallelDepth wide
/// levels as tasks. Each task's output depends on its subtree alone, and every subtree is written
/// at offsets fixed before it is emitted, so the wide tree is the same with any thread count.
constexpr std::size_t kParallelMinNodes = std::size_t{1} << 16;
constexpr int kSahParallelDepth = 6;
constexpr int kEmitParallelDepth = 2;

/// The wide nodes and packets of the subtree that replaces a binary node.
struct WideSize {
  std::uint32_t nodes = 0, packets = 0;
  WideSize operator+(const WideSize& o) const { return {nodes + o.nodes, packets + o.packets}; }
};

/// The spheres among binary leaf `leaf`'s primitives; 0 without a look in a scene that has none.
std::uint32_t leaf_spheres(const Bvh2& tree, const Scene& scene, const Bvh2Node& leaf) {
  std::uint32_t spheres = 0;
  if (!scene.spheres.empty())
    for (std::uint32_t k = 0; k < leaf.count; ++k) spheres += scene.is_sphere(tree.prims[leaf.first + k]);
  return spheres;
}

/// The wide SAH over the collapses of a binary tree (Ylitie, Karras and Laine 2017, §3.1). For a
/// binary node n of box area A(n) and k in [1, N], cost(n, k) is the least SAH cost of n's
/// subtree placed in at most k lanes of one wide node:
///   cost(n, 1) = min(c_packet·A(n)·packets(n) if n may be a leaf, c_node·A(n) + split(n, N)),
///   cost(n, k) = min(cost(n, k - 1), split(n, k)),
///   split(n, k) = min over i in [1, k) of cost(left(n), i) + cost(right(n), k - i),
/// where a binary leaf is always a leaf, and an interior node may be one when its subtree holds
/// at most max_leaf_primitives primitives (packets(n): its triangles and spheres each in whole
/// packets, as pack_leaf packs them).
///
/// The costs flow up the recursion; each node stores only its decisions and the size of the wide
/// subtree that replaces it, for the emission.
template <int N>
class SahCollapse {
 public:
  /// The decisions for binary node n.
  struct Decision {
    std::uint8_t lanes[N];  ///< the lanes cost(n, k) takes (index k - 1): 1 (n itself), or j >= 2 (split(n, j))
    std::uint8_t left[N];   ///< index j - 1, j >= 2: the lanes of split(n, j) given to the left child
    bool leaf;              ///< in one lane, n is a leaf
    WideSize wide;          ///< the wide subtree that replaces n (a binary leaf: one node holding it)
  };

  SahCollapse(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options, bool parallel)
      : tree_(tree),
        scene_(scene),
        options_(options),
        decisions_(std::make_unique_for_overwrite<Decision[]>(tree.nodes.size())) {
    // Every decision is written before it is read (solve visits each node once). Huge pages: in
    // 4 KiB pages, the first writes to a per-node table fault for as long as the collapse takes
    // (bench_bvh_build, 1.2·10^6 triangles).
    advise_huge_pages(decisions_.get(), tree.nodes.size() * sizeof(Decision));
    solve(0, parallel ? 0 : kSahParallelDepth);
  }

  const Decision& operator[](std::uint32_t node) const { return decisions_[node]; }

 private:
  /// Index k - 1: cost(n, k), and the size of the lanes it takes (n as a leaf: its packets).
  struct Costs {
    float cost[N];
    WideSize size[N];
    std::uint32_t triangles, spheres;
  };

  Costs solve(std::uint32_t index, int depth) {
    const Bvh2Node& node = tree_.nodes[index];
    Decision& d = decisions_[index];
    const float area = node.box.surface_area();
    Costs c;
    if (node.is_leaf()) {
      c.spheres = leaf_spheres(tree_, scene_, node);
      c.triangles = node.count - c.spheres;
      const float leaf = leaf_cost(area, c);
      const WideSize packets{0, leaf_packets(c)};
      for (int k = 0; k < N; ++k) c.cost[k] = leaf, c.size[k] = packets, d.lanes[k] = 1, d.left[k] = 0;
      d.leaf = true;
      d.wide = {1, packets.packets};
      return c;
    }
    Costs l, r;
    if (depth < kSahParallelDepth) {
      tbb::parallel_invoke([&] { l = solve(node.first, depth + 1); }, [&] { r = solve(node.first + 1, depth + 1); });
    } else {
      l = solve(node.first, depth + 1);
      r = solve(node.first + 1, depth + 1);
    }
    c.triangles = l.triangles + r.triangles;
    c.spheres = l.spheres + r.spheres;
    float split[N + 1];
    d.left[0] = 0;
    for (int j = 2; j <= N; ++j) {
      // Selects rather than branches: which i wins is data-dependent and poorly predicted.
      float best = l.cost[0] + r.cost[j - 2];
      std::uint8_t best_i = 1;
      for (int i = 2; i < j; ++i) {
        const float s = l.cost[i - 1] + r.cost[j - i - 1];
        best_i = s < best ? static_cast<std::uint8_t>(i) : best_i;
        best = s < best ? s : best;
      }
      split[j] = best;
      d.left[j - 1] = best_i;
    }
    const auto split_size = [&](int j) { return l.size[d.left[j - 1] - 1] + r.size[j - d.left[j - 1] - 1]; };
    const float interior = static_cast<float>(options_.cost.c_node) * area + split[N];
    const float as_leaf = c.triangles + c.spheres <= options_.max_leaf_primitives
                              ? leaf_cost(area, c)
                              : std::numeric_limits<float>::infinity();
    d.leaf = as_leaf < interior;
    d.wide = WideSize{1, 0} + split_size(N);
    c.cost[0] = d.leaf ? as_leaf : interior;
    c.size[0] = d.leaf ? WideSize{0, leaf_packets(c)} : d.wide;
    d.lanes[0] = 1;
    for (int k = 2; k <= N; ++k) {
      const bool split_k = split[k] < c.cost[k - 2];
      c.cost[k - 1] = split_k ? split[k] : c.cost[k - 2];
      d.lanes[k - 1] = split_k ? static_cast<std::uint8_t>(k) : d.lanes[k - 2];
      c.size[k - 1] = split_k ? split_size(k) : c.size[k - 2];
    }
    return c;
  }

  static std::uint32_t leaf_packets(const Costs& c) {
    return static_cast<std::uint32_t>(packed_leaf_packets(c.triangles, c.spheres));
  }

  float leaf_cost(float area, const Costs& c) const {
    return static_cast<float>(options_.cost.c_packet) * area * static_cast<float>(leaf_packets(c));
  }

  const Bvh2& tree_;
  const Scene& scene_;
  const WideCollapseOptions& options_;
  std::unique_ptr<Decision[]> decisions_;
};

/// Writes the wide tree of a collapse into arrays sized for it: each wide node, then its
/// children's subtrees in lane order, depth first (a child's whole subtree before the next
/// child's; its packets likewise).
template <int N>
class Collapser {
 public:
  Collapser(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options, bool parallel)
      : tree_(tree), scene_(scene), parallel_(parallel) {
    if (options.method == BvhCollapse::sah) {
      sah_.emplace(tree, scene, options, parallel);
    } else {
      greedy_sizes_ = std::make_unique_for_overwrite<WideSize[]>(tree.nodes.size());
      greedy_size(0);
    }
  }

  /// Sizes `out`'s arrays and writes the whole wide tree into them, its root at node 0.
  void emit_tree(WideBvh<N>& out) {
    const WideSize total = wide_size(0);
    if (total.packets > WideRef::kFirstMask + 1)
      throw std::length_error("wide BVH: packet array too large for the reference encoding");
    out.nodes.resize(total.nodes);
    out.packets.resize(total.packets);
    out.root_box = tree_.nodes[0].box;
    out_ = &out;
    std::vector<std::uint32_t> merged;
    emit(0, 0, 0, parallel_ ? 0 : kEmitParallelDepth, merged);
  }

 private:
  /// A lane of a wide node: binary node `node`, as a leaf (a binary leaf, or its subtree merged)
  /// or as the wide node replacing it.
  struct Child {
    std::uint32_t node;
    bool leaf;
  };

  WideSize wide_size(std::uint32_t index) const { return sah_ ? (*sah_)[index].wide : greedy_sizes_[index]; }

  /// The lanes of the wide node replacing binary node `index`; a binary leaf (at the root) is
  /// its only lane.
  int children(std::uint32_t index, Child (&kids)[N]) const {
    const Bvh2Node& node = tree_.nodes[index];
    if (node.is_leaf()) {
      kids[0] = {index, true};
      return 1;
    }
    if (!sah_) return greedy_children(node, kids);
    int n = 0;
    const int left = (*sah_)[index].left[N - 1];
    place(node.first, left, kids, n);
    place(node.first + 1, N - left, kids, n);
    return n;
  }

  /// Writes the wide node replacing binary node `index` at node `slot`, and its subtree's other
  /// nodes from slot + 1 and its packets from `first_packet`; `merged` holds a merged leaf's
  /// references while it is packed.
  void emit(std::uint32_t index, std::uint32_t slot, std::uint32_t first_packet, int depth,
            std::vector<std::uint32_t>& merged) {
    Child kids[N];
    const int n = children(index, kids);
    std::uint32_t refs[N], packets[N];
    std::uint32_t next_slot = slot + 1, next_packet = first_packet;
    for (int i = 0; i < n; ++i) {
      packets[i] = next_packet;
      if (kids[i].leaf) {
        refs[i] = leaf(kids[i].node, next_packet, merged);
        next_packet += WideRef::count(refs[i]);
      } else {
        const WideSize size = wide_size(kids[i].node);
        refs[i] = next_slot;
        next_slot += size.nodes;
        next_packet += size.packets;
      }
    }
    WideBvhNode<N>& w = out_->nodes[slot];
    for (int i = 0; i < N; ++i) {
      const Bounds3f b = i < n ? tree_.nodes[kids[i].node].box : Bounds3f{};
      for (int a = 0; a < 3; ++a) {
        w.bounds[a][i] = b.lo[a];
        w.bounds[3 + a][i] = b.hi[a];
      }
      w.child[i] = i < n ? refs[i] : 0u;
    }
    w.used = static_cast<std::uint32_t>(n);
    if (depth < kEmitParallelDepth) {
      tbb::parallel_for(0, n, [&](int i) {
        std::vector<std::uint32_t> own;
        if (!kids[i].leaf) emit(kids[i].node, refs[i], packets[i], depth + 1, own);
      });
      return;
    }
    for (int i = 0; i < n; ++i)
      if (!kids[i].leaf) emit(kids[i].node, refs[i], packets[i], depth + 1, merged);
  }

  /// The binary node's two children, then the interior child of largest area opened, repeatedly.
  int greedy_children(const Bvh2Node& node, Child (&kids)[N]) const {
    int n = 0;
    kids[n++] = {node.first, tree_.nodes[node.first].is_leaf()};
    kids[n++] = {node.first + 1, tree_.nodes[node.first + 1].is_leaf()};
    while (n < N) {
      int widest = -1;
      float widest_area = -1.0f;
      for (int i = 0; i < n; ++i) {
        if (kids[i].leaf) continue;
        const float area = tree_.nodes[kids[i].node].box.surface_area();
        if (area > widest_area) {
          widest_area = area;
          widest = i;
        }
      }
      if (widest < 0) break;
      const std::uint32_t first = tree_.nodes[kids[widest].node].first;
      kids[widest] = {first, tree_.nodes[first].is_leaf()};
      kids[n++] = {first + 1, tree_.nodes[first + 1].is_leaf()};
    }
    return n;
  }

  /// Sets greedy_sizes_ for binary node `index` and the nodes below it that the greedy
  /// collapse turns into wide nodes; returns its size.
  WideSize greedy_size(std::uint32_t index) {
    Child kids[N];
    const int n = children(index, kids);
    WideSize size{1, 0};
    for (int i = 0; i < n; ++i)
      size = size + (kids[i].leaf ? WideSize{0, binary_leaf_packets(kids[i].node)} : greedy_size(kids[i].node));
    return greedy_sizes_[index] = size;
  }

  /// The packets pack_leaf makes for binary leaf `index`.
  std::uint32_t binary_leaf_packets(std::uint32_t index) const {
    const Bvh2Node& c = tree_.nodes[index];
    const std::uint32_t spheres = leaf_spheres(tree_, scene_, c);
    return static_cast<std::uint32_t>(packed_leaf_packets(c.count - spheres, spheres));
  }

  /// Appends the lanes the SAH collapse gives binary node `index` within at most `lanes` lanes.
  void place(std::uint32_t index, int lanes, Child (&kids)[N], int& n) const {
    const auto& e = (*sah_)[index];
    const int used = e.lanes[lanes - 1];
    if (used == 1) {
      kids[n++] = {index, e.leaf};
      return;
    }
    const int left = e.left[used - 1];
    place(tree_.nodes[index].first, left, kids, n);
    place(tree_.nodes[index].first + 1, used - left, kids, n);
  }

  /// Packs the references of binary node `index`'s subtree into one leaf from packet `first`.
  std::uint32_t leaf(std::uint32_t index, std::uint32_t first, std::vector<std::uint32_t>& merged) const {
    const Bvh2Node& c = tree_.nodes[index];
    std::span<const std::uint32_t> prims(tree_.prims.data() + c.first, c.count);
    if (!c.is_leaf()) {
      merged.clear();
      gather(index, merged);
      prims = merged;
    }
    const std::uint32_t count = pack_leaf(scene_, prims, out_->packets.data() + first);
    if (count > WideRef::kMaxLeafPackets)
      throw std::length_error("wide BVH: leaf too large for the reference encoding");
    return WideRef::leaf(first, count);
  }

  void gather(std::uint32_t index, std::vector<std::uint32_t>& merged) const {
    const Bvh2Node& c = tree_.nodes[index];
    if (c.is_leaf()) {
      merged.insert(merged.end(), tree_.prims.begin() + c.first, tree_.prims.begin() + c.first + c.count);
      return;
    }
    gather(c.first, merged);
    gather(c.first + 1, merged);
  }

  const Bvh2& tree_;
  const Scene& scene_;
  const bool parallel_;
  std::optional<SahCollapse<N>> sah_;
  std::unique_ptr<WideSize[]> greedy_sizes_;  ///< BvhCollapse::greedy: the sizes of the nodes it turns into wide nodes
  WideBvh<N>* out_ = nullptr;
};

}  // namespace

template <int N>
WideBvh<N> collapse_bvh(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options) {
  WideBvh<N> out;
  if (tree.nodes.empty()) return out;
  const int threads = resolve_thread_count(options.threads);
  const bool parallel = threads > 1 && tree.nodes.size() >= kParallelMinNodes;
  const auto collapse = [&] { Collapser<N>(tree, scene, options, parallel).emit_tree(out); };
  if (parallel) tbb::task_arena(threads).execute(collapse);
  else collapse();
  return out;
}

template WideBvh<4> collapse_bvh<4>(const Bvh2&, const Scene&, const WideCollapseOptions&);
template WideBvh<8> collapse_bvh<8>(const Bvh2&, const Scene&, const WideCollapseOptions&);

template <int N>
double wide_sah_cost(const WideBvh<N>& wide, const WideCollapseOptions& options) {
  const double root_area = wide.root_box.surface_area();
  if (wide.nodes.empty() || !(root_area > 0)) return 0.0;
  double cost = options.cost.c_node * root_area;
  for (const WideBvhNode<N>& node : wide.nodes)
    for (int i = 0; i < static_cast<int>(node.used); ++i) {
      const double area = node.box(i).surface_area();
      cost += WideRef::is_leaf(node.child[i]) ? options.cost.c_packet * area * WideRef::count(node.child[i])
                                              : options.cost.c_node * area;
    }
  return cost / root_area;
}

template double wide_sah_cost<4>(const WideBvh<4>&, const WideCollapseOptions&);
template double wide_sah_cost<8>(const WideBvh<8>&, const WideCollapseOptions&);

}  // namespace raylab
