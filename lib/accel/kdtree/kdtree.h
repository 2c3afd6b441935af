#pragma once
/// `kdtree`: the lecture's kd-tree over a scene's triangles and spheres (kdtree_build.h for the
/// builders, kdtree_traversal.h for traversal), with the watertight ray-triangle kernel.
#include <memory>

#include "accel/common/accel_factory.h"
#include "accel/kdtree/kdtree_build.h"
#include "accel/kdtree/kdtree_traversal.h"

namespace raylab {

class KdTree final : public AggregateBase<KdTree> {
 public:
  /// `scene` must not be instanced.
  KdTree(std::shared_ptr<const Scene> scene, const KdTreeConfig& config);

  std::string name() const override { return "kdtree"; }
  AccelStats stats() const override;
  Bounds3f bounds() const override { return data_.bounds; }
  std::optional<std::uint64_t> structure_hash() const override;

  /// The built tree. Its `prims` are released (empty) once the stack traversal reads packed
  /// leaves, which carry their primitive ids: build_kdtree gives the full data.
  const KdTreeData& data() const { return data_; }
  const KdTreeConfig& config() const { return config_; }

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
    const KdTreeView view{data_.nodes.data(), data_.prims.data(), scene_.get(), data_.bounds,
                          tris_.empty() ? nullptr : tris_.data(), lines_.empty() ? nullptr : lines_.front().node,
                          packets_.empty() ? nullptr : packets_.data()};
    if (config_.traversal == KdTraversal::stack)
      return config_.mailbox ? kd_traverse_lines<K, kAnyHit, true>(view, ray, hit, counters)
                             : kd_traverse_lines<K, kAnyHit, false>(view, ray, hit, counters);
    return config_.mailbox ? kd_traverse_recursive<K, kAnyHit, true>(view, ray, hit, counters)
                           : kd_traverse_recursive<K, kAnyHit, false>(view, ray, hit, counters);
  }

  std::shared_ptr<const Scene> scene_;
  KdTreeConfig config_;
  KdTreeData data_;
  std::uint64_t hash_ = 0;  ///< of data_.nodes and data_.prims as built
  // Only the arrays the configured traversal reads are kept (stats() counts them all):
  std::vector<KdTriangle> tris_;   ///< recursive: the triangles by primitive id (kdtree_triangle_soup.h)
  std::vector<KdNodeLine> lines_;  ///< stack: data_.nodes in cache lines
  std::vector<TrianglePacket> packets_;  ///< stack: the leaves of lines_ packed 4-wide (kd_pack_leaves)
};

/// The factory entry: parameters, accuracy bound and oracle variants.
AccelKind make_kdtree_kind();

/// Reads a KdTreeConfig from a spec's parameters (shared with the experiments).
KdTreeConfig read_kdtree_config(SpecReader& reader);

}  // namespace raylab
