#pragma once
/// `bsp`: BSP tree with arbitrary planes (auto-partition plus axis-aligned candidates), exact
/// classification, front-to-back traversal.
#include <memory>

#include "accel/bsp/bsp_build.h"
#include "accel/bsp/bsp_traversal.h"
#include "accel/common/accel_factory.h"

namespace raylab {

class BspTree final : public AggregateBase<BspTree> {
 public:
  /// `scene` must not be instanced.
  BspTree(std::shared_ptr<const Scene> scene, const BspConfig& config);

  std::string name() const override { return "bsp"; }
  AccelStats stats() const override;
  Bounds3f bounds() const override { return data_.bounds; }
  std::optional<std::uint64_t> structure_hash() const override;
  const BspTreeData& data() const { return data_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    const BspTreeView view = traversal_view();
    const bool found = config_.kernel == KernelChoice::certified
                           ? bsp_traverse<CertifiedKernel, false>(view, ray, hit, counters)
                           : bsp_traverse<WatertightKernel, false>(view, ray, hit, counters);
    if (found) ray.tmax = hit.t;
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    Hit hit;
    const BspTreeView view = traversal_view();
    if (config_.kernel == KernelChoice::certified) return bsp_traverse<CertifiedKernel, true>(view, ray, hit, counters);
    return bsp_traverse<WatertightKernel, true>(view, closed_for_any_hit(ray), hit, counters);
  }

 private:
  BspTreeView traversal_view() const {
    if (packets_.empty()) return {data_.nodes.data(), data_.prims.data(), scene_.get(), data_.bounds};
    return {packed_nodes_.data(), nullptr, scene_.get(), data_.bounds, packets_.data()};
  }

  std::shared_ptr<const Scene> scene_;
  BspConfig config_;
  BspTreeData data_;
  std::vector<BspNode> packed_nodes_;    ///< data_.nodes with leaves indexing packets_ (bsp_pack_leaves)
  std::vector<TrianglePacket> packets_;  ///< the leaves' triangles, 4-wide; empty when the scene has a sphere
};

AccelKind make_bsp_kind();
BspConfig read_bsp_config(SpecReader& reader);

}  // namespace raylab
