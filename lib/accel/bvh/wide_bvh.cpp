#include "accel/bvh/wide_bvh.h"

#include "accel/common/huge_pages.h"

#include <limits>
#include <span>
#include <stdexcept>

namespace raylab {

namespace {

template <int N>
class Collapser {
 public:
  Collapser(const Bvh2& tree, const Scene& scene, WideBvh<N>& out) : tree_(tree), scene_(scene), out_(out) {}

  /// Emits the wide node replacing binary node `index` and returns its index in out_.nodes.
  /// A binary leaf at the root becomes a wide node with one leaf child.
  std::uint32_t emit(std::uint32_t index) {
    const std::uint32_t self = static_cast<std::uint32_t>(out_.nodes.size());
    out_.nodes.emplace_back();
    std::uint32_t kids[N];
    int n = 0;
    const Bvh2Node& node = tree_.nodes[index];
    if (node.is_leaf()) {
      kids[n++] = index;
    } else {
      kids[n++] = node.first;
      kids[n++] = node.first + 1;
      while (n < N) {
        int widest = -1;
        float widest_area = -1.0f;
        for (int i = 0; i < n; ++i) {
          const Bvh2Node& c = tree_.nodes[kids[i]];
          if (c.is_leaf()) continue;
          const float area = c.box.surface_area();
          if (area > widest_area) {
            widest_area = area;
            widest = i;
          }
        }
        if (widest < 0) break;
        const std::uint32_t opened = kids[widest];
        kids[widest] = tree_.nodes[opened].first;
        kids[n++] = tree_.nodes[opened].first + 1;
      }
    }
    std::uint32_t refs[N];
    for (int i = 0; i < n; ++i) {
      const Bvh2Node& c = tree_.nodes[kids[i]];
      refs[i] = c.is_leaf() ? leaf(c) : emit(kids[i]);
    }
    WideBvhNode<N>& w = out_.nodes[self];
    for (int i = 0; i < N; ++i) {
      const Bounds3f b = i < n ? tree_.nodes[kids[i]].box : Bounds3f{};
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
  std::uint32_t leaf(const Bvh2Node& c) {
    const std::size_t first = out_.packets.size();
    const std::uint32_t count =
        pack_leaf(scene_, std::span<const std::uint32_t>(tree_.prims.data() + c.first, c.count), out_.packets);
    if (count > WideRef::kMaxLeafPackets || first + count > WideRef::kFirstMask + 1)
      throw std::length_error("wide BVH: leaf or packet array too large for the reference encoding");
    return WideRef::leaf(static_cast<std::uint32_t>(first), count);
  }

  const Bvh2& tree_;
  const Scene& scene_;
  WideBvh<N>& out_;
};

}  // namespace

template <int N>
WideBvh<N> collapse_bvh(const Bvh2& tree, const Scene& scene) {
  WideBvh<N> out;
  if (tree.nodes.empty()) return out;
  // Reserved once and never shrunk: a shrink copies the whole array into freshly faulted pages,
  // which measured ~5% of the build. Each wide node replaces at least one binary interior node
  // (at most one node for a binary leaf at the root); the packet count is exact.
  std::size_t packets = 0;
  for (const Bvh2Node& n : tree.nodes) {
    if (!n.is_leaf()) continue;
    std::size_t spheres = 0;
    for (std::uint32_t k = 0; k < n.count; ++k) spheres += scene.is_sphere(tree.prims[n.first + k]);
    packets += (n.count - spheres + kPacketWidth - 1) / kPacketWidth + (spheres + kPacketWidth - 1) / kPacketWidth;
  }
  out.nodes.reserve(tree.nodes.size() / 2 + 1);
  out.packets.reserve(packets);
  advise_huge_pages(out.nodes.data(), out.nodes.capacity() * sizeof(WideBvhNode<N>));
  advise_huge_pages(out.packets.data(), out.packets.capacity() * sizeof(TrianglePacket));
  out.root_box = tree.nodes[0].box;
  Collapser<N>(tree, scene, out).emit(0);
  return out;
}

template WideBvh<4> collapse_bvh<4>(const Bvh2&, const Scene&);
template WideBvh<8> collapse_bvh<8>(const Bvh2&, const Scene&);

}  // namespace raylab
