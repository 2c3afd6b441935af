#pragma once
/// `bvh`: the lecture's bounding volume hierarchy over a scene's triangles and spheres
/// (bvh_build.h for the builders; bvh_traversal.h traverses the binary tree, width=2;
/// wide_bvh_traversal.h the 4- or 8-wide tree collapsed from it, with packed leaves, or indexed
/// ones that gather their vertices from a copy of the leaves' vertices). The default pairs Ize's
/// conservative box test with the certified kernel, whose closest() bound is raised past the
/// rounding of the box entries (certified_kernel.h), so no box the exact ray touches before the
/// exact first hit is pruned; `kernel=watertight` pairs the same test with the watertight kernel;
/// `robust=off` is the fast variant.
#include <algorithm>
#include <memory>

#include "accel/bvh/bvh_build.h"
#include "accel/bvh/bvh_traversal.h"
#include "accel/bvh/packed_triangles_simd.h"
#include "accel/bvh/quantized_wide_node.h"
#include "accel/bvh/wide_bvh_traversal.h"
#include "accel/common/accel_factory.h"
#include "scene/scene_primitives.h"

namespace raylab {

class Bvh final : public AggregateBase<Bvh> {
 public:
  /// `scene` must not be instanced.
  Bvh(std::shared_ptr<const Scene> scene, const BvhConfig& config);

  std::string name() const override { return "bvh"; }
  AccelStats stats() const override;
  Bounds3f bounds() const override { return bounds_; }
  std::optional<std::uint64_t> structure_hash() const override;

  const Bvh2& tree() const { return tree_; }
  /// The traversed wide trees: filled only when config().width is 4 or 8 respectively, and
  /// config().nodes is full (wide4, wide8) or quantized (quantized4, quantized8).
  const WideBvh<4>& wide4() const { return wide4_; }
  const WideBvh<8>& wide8() const { return wide8_; }
  const QuantizedWideBvh<4>& quantized4() const { return quantized4_; }
  const QuantizedWideBvh<8>& quantized8() const { return quantized8_; }
  /// The wide tree's leaves when config().leaves is indexed (its packets are then empty).
  const IndexedLeaves& indexed() const { return indexed_; }
  const BvhConfig& config() const { return config_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    const bool found = !config_.robust ? trace<MollerTrumboreKernel, false, false>(ray, hit, counters)
                       : config_.kernel == KernelChoice::certified ? trace<CertifiedKernel, true, false>(ray, hit, counters)
                                                                   : trace<WatertightKernel, true, false>(ray, hit, counters);
    if (found) ray.tmax = hit.t;
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    Hit hit;
    if (config_.robust && config_.kernel == KernelChoice::certified)
      return trace<CertifiedKernel, true, true>(ray, hit, counters);
    const Ray closed = closed_for_any_hit(ray);
    return config_.robust ? trace<WatertightKernel, true, true>(closed, hit, counters)
                          : trace<MollerTrumboreKernel, false, true>(closed, hit, counters);
  }

 private:
  template <class Kernel, bool kRobust, bool kAnyHit, class Counters>
  bool trace(const Ray& ray, Hit& hit, Counters& counters) const {
    if (tree_.nodes.empty()) return false;
    const bool quantized = config_.nodes == BvhNodes::quantized;
    if (config_.leaves == BvhLeaves::indexed && config_.width != 2) {
      if (config_.width == 8)
        return quantized ? trace_wide_indexed<Kernel, kRobust, kAnyHit>(quantized8_, ray, hit, counters)
                         : trace_wide_indexed<Kernel, kRobust, kAnyHit>(wide8_, ray, hit, counters);
      return quantized ? trace_wide_indexed<Kernel, kRobust, kAnyHit>(quantized4_, ray, hit, counters)
                       : trace_wide_indexed<Kernel, kRobust, kAnyHit>(wide4_, ray, hit, counters);
    }
    if (config_.width == 8)
      return quantized ? trace_wide<Kernel, kRobust, kAnyHit>(quantized8_, ray, hit, counters)
                       : trace_wide<Kernel, kRobust, kAnyHit>(wide8_, ray, hit, counters);
    if (config_.width == 4)
      return quantized ? trace_wide<Kernel, kRobust, kAnyHit>(quantized4_, ray, hit, counters)
                       : trace_wide<Kernel, kRobust, kAnyHit>(wide4_, ray, hit, counters);
    typename Kernel::Context ctx = Kernel::prepare(ray);
    const Scene& scene = *scene_;
    const std::uint32_t* prims = tree_.prims.data();
    float closest = Kernel::closest(ctx);
    return traverse_bvh2<kRobust, kAnyHit>(
        tree_.nodes.data(), ray, closest, counters, [&](std::uint32_t first, std::uint32_t count, float& t) {
          bool found = false;
          for (std::uint32_t i = first; i < first + count; ++i) {
            if (intersect_scene_primitive<Kernel>(scene, prims[i], ctx, hit, counters)) {
              found = true;
              if constexpr (kAnyHit) return true;
            }
          }
          t = Kernel::closest(ctx);
          return found;
        });
  }

  template <class Kernel, bool kRobust, bool kAnyHit, int N, class Node, class Counters>
  [[gnu::noinline]] bool trace_wide(const WideBvh<N, Node>& wide, const Ray& ray, Hit& hit, Counters& counters) const {
    // Kept out of line (one function per kernel, node type and width): inlined into trace()
    // beside the quantized instantiations it made the certified BVH8 primary rays 1.13-1.18x the
    // watertight kernel's (exp_certainty quick, camel and elephant x 1e4 offset; 1.05-1.07 out of line).
    // For closest-hit queries the kernel's per-ray setup (three divisions for the watertight
    // shear) waits for the first leaf: many rays (diffuse rays leaving a convex part) reach none.
    // Shadow rays mostly do, and measure faster with the setup done up front.
    typename Kernel::Context ctx{};
    typename PacketKernel<Kernel>::Ray packet_ray{};
    bool prepared = kAnyHit;
    if constexpr (kAnyHit) {
      prepare_context<Kernel>(ctx, ray);
      packet_ray = typename PacketKernel<Kernel>::Ray(ctx);
    }
    const Scene& scene = *scene_;
    const TrianglePacket* packets = wide.packets.data();
    float closest = initial_closest<Kernel>(ray);
    return traverse_wide_bvh<N, kRobust, kAnyHit>(
        wide.nodes.data(), packets, ray, closest, counters, [&](std::uint32_t first, std::uint32_t count, float& t) {
          if (!prepared) {
            prepare_context<Kernel>(ctx, ray);  // ctx's closest is ray.tmax: no leaf has hit yet
            packet_ray = typename PacketKernel<Kernel>::Ray(ctx);
            prepared = true;
          }
          const bool found =
              intersect_packed_leaf<Kernel, kAnyHit>(scene, ctx, packet_ray, packets + first, count, hit, counters);
          t = Kernel::closest(ctx);
          return found;
        });
  }

  /// trace_wide with indexed leaves: each leaf's packets are gathered from indexed_.vertices two at
  /// a time (the paired test's width) into packets on the stack, then tested as packed ones. Out of line
  /// for the reason trace_wide is; `wide`'s packets are empty, its leaves refer to indexed_. The
  /// context setup repeats trace_wide's on purpose: shared through an inlined helper taking the leaf
  /// test as a lambda, it took the default's throughput on bunny00 from 0.82-0.97 of Embree's to
  /// 0.75-0.84 (`raylab sweep`, primary, diffuse and shadow rays, medians of 3 measurements).
  template <class Kernel, bool kRobust, bool kAnyHit, int N, class Node, class Counters>
  [[gnu::noinline]] bool trace_wide_indexed(const WideBvh<N, Node>& wide, const Ray& ray, Hit& hit,
                                            Counters& counters) const {
    typename Kernel::Context ctx{};
    typename PacketKernel<Kernel>::Ray packet_ray{};
    bool prepared = kAnyHit;
    if constexpr (kAnyHit) {
      prepare_context<Kernel>(ctx, ray);
      packet_ray = typename PacketKernel<Kernel>::Ray(ctx);
    }
    const Scene& scene = *scene_;
    const IndexedPacket* ids = indexed_.packets.data();
    const Vec3f* vertices = indexed_.vertices.data();
    float closest = initial_closest<Kernel>(ray);
    return traverse_wide_bvh<N, kRobust, kAnyHit>(
        wide.nodes.data(), ids, ray, closest, counters, [&](std::uint32_t first, std::uint32_t count, float& t) {
          if (!prepared) {
            prepare_context<Kernel>(ctx, ray);
            packet_ray = typename PacketKernel<Kernel>::Ray(ctx);
            prepared = true;
          }
          bool found = false;
          alignas(32) TrianglePacket gathered[2];
          for (std::uint32_t i = first; i < first + count; i += 2) {
            const std::uint32_t n = std::min<std::uint32_t>(2, first + count - i);
            for (std::uint32_t k = 0; k < n; ++k) gather_packet(scene, vertices, ids[i + k], gathered[k]);
            if (intersect_packed_leaf<Kernel, kAnyHit>(scene, ctx, packet_ray, gathered, n, hit, counters)) {
              found = true;
              if constexpr (kAnyHit) break;
            }
          }
          t = Kernel::closest(ctx);
          return found;
        });
  }

  std::shared_ptr<const Scene> scene_;
  BvhConfig config_;
  Bvh2 tree_;
  WideBvh<4> wide4_;  ///< filled when config_.width == 4 and config_.nodes is full
  WideBvh<8> wide8_;  ///< filled when config_.width == 8 and config_.nodes is full
  QuantizedWideBvh<4> quantized4_;  ///< filled when config_.width == 4 and config_.nodes is quantized
  QuantizedWideBvh<8> quantized8_;  ///< filled when config_.width == 8 and config_.nodes is quantized
  IndexedLeaves indexed_;  ///< the wide tree's leaves when config_.leaves is indexed
  Bounds3f bounds_;
  double build_sah_cost_ = 0.0;
};

/// Reads a BvhConfig from a spec's parameters (shared with the experiments).
BvhConfig read_bvh_config(SpecReader& reader);

/// The factory entry: parameters, accuracy bound and oracle variants.
AccelKind make_bvh_kind();

}  // namespace raylab
