#include "accel/bvh/wide_bvh.h"

#include "accel/common/huge_pages.h"
#include "accel/common/tracer.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>

namespace raylab {

namespace {

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
/// The costs flow up the recursion; only each node's decisions are stored for the emission. The
/// subtrees below the top kParallelDepth levels are solved as parallel tasks when the tree has at
/// least kParallelMinNodes nodes; a node's decisions depend on its subtree alone, so they are the
/// same with any thread count.
template <int N>
class SahCollapse {
 public:
  /// The decisions for binary node n.
  struct Decision {
    std::uint8_t lanes[N];  ///< the lanes cost(n, k) takes (index k - 1): 1 (n itself), or j >= 2 (split(n, j))
    std::uint8_t left[N];   ///< index j - 1, j >= 2: the lanes of split(n, j) given to the left child
    bool leaf;              ///< in one lane, n is a leaf
  };

  static constexpr int kParallelDepth = 6;
  static constexpr std::size_t kParallelMinNodes = std::size_t{1} << 16;

  SahCollapse(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options)
      : tree_(tree),
        scene_(scene),
        options_(options),
        has_spheres_(!scene.spheres.empty()),
        decisions_(std::make_unique_for_overwrite<Decision[]>(tree.nodes.size())) {
    // Every decision is written before it is read (solve visits each node once). Huge pages: in
    // 4 KiB pages, the first writes to a per-node table fault for as long as the collapse takes
    // (bench_bvh_build, 1.2·10^6 triangles).
    advise_huge_pages(decisions_.get(), tree.nodes.size() * sizeof(Decision));
    const int threads = resolve_thread_count(options.threads);
    if (threads > 1 && tree.nodes.size() >= kParallelMinNodes) {
      tbb::task_arena(threads).execute([&] { solve(0, 0); });
    } else {
      solve(0, kParallelDepth);
    }
  }

  const Decision& operator[](std::uint32_t node) const { return decisions_[node]; }

 private:
  /// cost(n, k) at index k - 1, and the primitives of n's subtree.
  struct Costs {
    float cost[N];
    std::uint32_t triangles, spheres;
  };

  Costs solve(std::uint32_t index, int depth) {
    const Bvh2Node& node = tree_.nodes[index];
    Decision& d = decisions_[index];
    const float area = node.box.surface_area();
    Costs c;
    if (node.is_leaf()) {
      c.spheres = 0;
      if (has_spheres_)
        for (std::uint32_t k = 0; k < node.count; ++k) c.spheres += scene_.is_sphere(tree_.prims[node.first + k]);
      c.triangles = node.count - c.spheres;
      const float leaf = leaf_cost(area, c);
      for (int k = 0; k < N; ++k) c.cost[k] = leaf, d.lanes[k] = 1, d.left[k] = 0;
      d.leaf = true;
      return c;
    }
    Costs l, r;
    if (depth < kParallelDepth) {
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
    const float interior = static_cast<float>(options_.c_node) * area + split[N];
    const float as_leaf = c.triangles + c.spheres <= options_.max_leaf_primitives
                              ? leaf_cost(area, c)
                              : std::numeric_limits<float>::infinity();
    d.leaf = as_leaf < interior;
    c.cost[0] = d.leaf ? as_leaf : interior;
    d.lanes[0] = 1;
    for (int k = 2; k <= N; ++k) {
      const bool split_k = split[k] < c.cost[k - 2];
      c.cost[k - 1] = split_k ? split[k] : c.cost[k - 2];
      d.lanes[k - 1] = split_k ? static_cast<std::uint8_t>(k) : d.lanes[k - 2];
    }
    return c;
  }

  float leaf_cost(float area, const Costs& c) const {
    return static_cast<float>(options_.c_packet) * area * static_cast<float>(packed_leaf_packets(c.triangles, c.spheres));
  }

  const Bvh2& tree_;
  const Scene& scene_;
  const WideCollapseOptions& options_;
  const bool has_spheres_;
  std::unique_ptr<Decision[]> decisions_;
};

template <int N>
class Collapser {
 public:
  Collapser(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options, WideBvh<N>& out)
      : tree_(tree), scene_(scene), out_(out) {
    if (options.method == BvhCollapse::sah) sah_.emplace(tree, scene, options);
  }

  /// Emits the wide node replacing binary node `index` and returns its index in out_.nodes.
  /// A binary leaf at the root becomes a wide node with one leaf child.
  std::uint32_t emit(std::uint32_t index) {
    const std::uint32_t self = static_cast<std::uint32_t>(out_.nodes.size());
    out_.nodes.emplace_back();
    Child kids[N];
    int n = 0;
    const Bvh2Node& node = tree_.nodes[index];
    if (node.is_leaf()) {
      kids[n++] = {index, true};
    } else if (sah_) {
      const int left = (*sah_)[index].left[N - 1];
      place(node.first, left, kids, n);
      place(node.first + 1, N - left, kids, n);
    } else {
      n = greedy_children(node, kids);
    }
    std::uint32_t refs[N];
    for (int i = 0; i < n; ++i) refs[i] = kids[i].leaf ? leaf(kids[i].node) : emit(kids[i].node);
    WideBvhNode<N>& w = out_.nodes[self];
    for (int i = 0; i < N; ++i) {
      const Bounds3f b = i < n ? tree_.nodes[kids[i].node].box : Bounds3f{};
      for (int a = 0; a < 3; ++a) {
        w.bounds[a][i] = b.lo[a];
        w.bounds[3 + a][i] = b.hi[a];
      }
      w.child[i] = i < n ? refs[i] : 0u;
    }
    w.used = static_cast<std::uint32_t>(n);
    return self;
  }

 private:
  /// A lane of a wide node: binary node `node`, as a leaf (a binary leaf, or its subtree merged)
  /// or as the wide node replacing it.
  struct Child {
    std::uint32_t node;
    bool leaf;
  };

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

  /// Packs the references of binary node `index`'s subtree into one leaf.
  std::uint32_t leaf(std::uint32_t index) {
    const Bvh2Node& c = tree_.nodes[index];
    std::span<const std::uint32_t> prims(tree_.prims.data() + c.first, c.count);
    if (!c.is_leaf()) {
      merged_.clear();
      gather(index);
      prims = merged_;
    }
    const std::size_t first = out_.packets.size();
    const std::uint32_t count = pack_leaf(scene_, prims, out_.packets);
    if (count > WideRef::kMaxLeafPackets || first + count > WideRef::kFirstMask + 1)
      throw std::length_error("wide BVH: leaf or packet array too large for the reference encoding");
    return WideRef::leaf(static_cast<std::uint32_t>(first), count);
  }

  void gather(std::uint32_t index) {
    const Bvh2Node& c = tree_.nodes[index];
    if (c.is_leaf()) {
      merged_.insert(merged_.end(), tree_.prims.begin() + c.first, tree_.prims.begin() + c.first + c.count);
      return;
    }
    gather(c.first);
    gather(c.first + 1);
  }

  const Bvh2& tree_;
  const Scene& scene_;
  WideBvh<N>& out_;
  std::optional<SahCollapse<N>> sah_;
  std::vector<std::uint32_t> merged_;  ///< a merged leaf's references
};

}  // namespace

template <int N>
WideBvh<N> collapse_bvh(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options) {
  WideBvh<N> out;
  if (tree.nodes.empty()) return out;
  // Reserved once and never shrunk: a shrink copies the whole array into freshly faulted pages,
  // which measured ~5% of the build. Each wide node replaces at least one binary interior node
  // (at most one node for a binary leaf at the root); the packets are at most those of the
  // binary leaves packed one by one (a merged leaf may fill its packets better).
  std::size_t packets = 0;
  const bool has_spheres = !scene.spheres.empty();
  for (const Bvh2Node& n : tree.nodes) {
    if (!n.is_leaf()) continue;
    std::size_t spheres = 0;
    if (has_spheres)
      for (std::uint32_t k = 0; k < n.count; ++k) spheres += scene.is_sphere(tree.prims[n.first + k]);
    packets += packed_leaf_packets(n.count - spheres, spheres);
  }
  out.nodes.reserve(tree.nodes.size() / 2 + 1);
  out.packets.reserve(packets);
  advise_huge_pages(out.nodes.data(), out.nodes.capacity() * sizeof(WideBvhNode<N>));
  advise_huge_pages(out.packets.data(), out.packets.capacity() * sizeof(TrianglePacket));
  out.root_box = tree.nodes[0].box;
  Collapser<N>(tree, scene, options, out).emit(0);
  return out;
}

template WideBvh<4> collapse_bvh<4>(const Bvh2&, const Scene&, const WideCollapseOptions&);
template WideBvh<8> collapse_bvh<8>(const Bvh2&, const Scene&, const WideCollapseOptions&);

template <int N>
double wide_sah_cost(const WideBvh<N>& wide, const WideCollapseOptions& options) {
  const double root_area = wide.root_box.surface_area();
  if (wide.nodes.empty() || !(root_area > 0)) return 0.0;
  double cost = options.c_node * root_area;
  for (const WideBvhNode<N>& node : wide.nodes)
    for (int i = 0; i < static_cast<int>(node.used); ++i) {
      const double area = node.box(i).surface_area();
      cost += WideRef::is_leaf(node.child[i]) ? options.c_packet * area * WideRef::count(node.child[i])
                                              : options.c_node * area;
    }
  return cost / root_area;
}

template double wide_sah_cost<4>(const WideBvh<4>&, const WideCollapseOptions&);
template double wide_sah_cost<8>(const WideBvh<8>&, const WideCollapseOptions&);

}  // namespace raylab
