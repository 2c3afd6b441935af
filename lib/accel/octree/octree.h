#pragma once
/// `octree`: centre-split octree with the kd-tree's placement and split clipping, cost-based
/// termination and front-to-back traversal.
#include <memory>

#include "accel/common/accel_factory.h"
#include "accel/octree/octree_build.h"
#include "accel/octree/octree_traversal.h"

namespace raylab {

class Octree final : public AggregateBase<Octree> {
 public:
  /// `scene` must not be instanced.
  Octree(std::shared_ptr<const Scene> scene, const OctreeConfig& config);

  std::string name() const override { return "octree"; }
  AccelStats stats() const override;
  Bounds3f bounds() const override { return data_.bounds; }
  std::optional<std::uint64_t> structure_hash() const override;
  const OctreeData& data() const { return data_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    const bool found = dispatch<false>(ray, hit, counters);
    if (found) ray.tmax = hit.t;
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    Hit hit;
    return dispatch<true>(ray, hit, counters);
  }

 private:
  template <bool kAnyHit, class Counters>
  bool dispatch(const Ray& ray, Hit& hit, Counters& counters) const {
    if (config_.kernel == KernelChoice::certified) return traverse<CertifiedKernel, kAnyHit>(ray, hit, counters);
    return traverse<WatertightKernel, kAnyHit>(kAnyHit ? closed_for_any_hit(ray) : ray, hit, counters);
  }

  template <class K, bool kAnyHit, class Counters>
  bool traverse(const Ray& ray, Hit& hit, Counters& counters) const {
    const OctreeView view =
        packets_.empty() ? OctreeView{data_.nodes.data(), data_.prims.data(), scene_.get(), data_.bounds}
                         : OctreeView{packed_nodes_.data(), nullptr, scene_.get(), data_.bounds, packets_.data()};
    if (config_.traversal == OctreeTraversal::stack)
      return config_.mailbox ? octree_traverse_stack<K, kAnyHit, true>(view, ray, hit, counters)
                             : octree_traverse_stack<K, kAnyHit, false>(view, ray, hit, counters);
    if (config_.traversal == OctreeTraversal::revelles)
      return config_.mailbox ? octree_traverse_revelles<K, kAnyHit, true>(view, ray, hit, counters)
                             : octree_traverse_revelles<K, kAnyHit, false>(view, ray, hit, counters);
    return config_.mailbox ? octree_traverse_kd<K, kAnyHit, true>(view, ray, hit, counters)
                           : octree_traverse_kd<K, kAnyHit, false>(view, ray, hit, counters);
  }

  std::shared_ptr<const Scene> scene_;
  OctreeConfig config_;
  OctreeData data_;
  std::vector<OctNode> packed_nodes_;    ///< data_.nodes with leaves indexing packets_ (octree_pack_leaves)
  std::vector<TrianglePacket> packets_;  ///< the leaves' triangles, 4-wide; empty when the scene has a sphere
};

AccelKind make_octree_kind();
OctreeConfig read_octree_config(SpecReader& reader);

}  // namespace raylab
