#include "accel/exact/certified_instances.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "accel/bvh/bvh_build.h"
#include "accel/common/accel_factory.h"
#include "accel/exact/exact_oracle.h"
#include "geometry/certified_kernel.h"
#include "scene/ray_counters.h"

namespace raylab {

namespace {

using CK = CertifiedKernel;

/// A box in world space, in double.
struct WorldBox {
  std::array<double, 3> lo, hi;
};

/// The world box of `object_box` under `xf` (|A| the absolute linear part), widened so that it
/// holds every world vertex flatten_instances computes from a vertex in the box (header).
WorldBox world_box(const Bounds3f& object_box, const AffineTransform& xf,
                   const std::array<std::array<double, 3>, 3>& abs_linear) {
  WorldBox w;
  for (int i = 0; i < 3; ++i) {
    double centre = xf.m[i][3], half = 0.0, magnitude = std::abs(xf.m[i][3]);
    for (int j = 0; j < 3; ++j) {
      const double c = 0.5 * (double(object_box.lo[j]) + double(object_box.hi[j]));
      const double h = 0.5 * (double(object_box.hi[j]) - double(object_box.lo[j]));
      centre += xf.m[i][j] * c;
      half += abs_linear[i][j] * h;
      magnitude += abs_linear[i][j] * (std::abs(c) + h);
    }
    const double slack = 0x1p-22 * magnitude + 0x1p-125;
    w.lo[i] = centre - half - slack;
    w.hi[i] = centre + half + slack;
  }
  return w;
}

WorldBox world_box(const Bounds3f& b) {
  return {{double(b.lo.x), double(b.lo.y), double(b.lo.z)}, {double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
}

/// Whether the ray meets `box` at some t in [tmin, reach]; `entry` is a lower bound of where.
/// In double with the distances widened by a relative 2^-40 (each is within 2^-51 of exact).
bool meets(const Ray& ray, const WorldBox& box, double reach, double& entry) {
  double near = -std::numeric_limits<double>::infinity(), far = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double o = ray.org[i], d = ray.dir[i];
    if (d == 0.0) {
      if (o < box.lo[i] || o > box.hi[i]) return false;
      continue;
    }
    const double t1 = (box.lo[i] - o) / d, t2 = (box.hi[i] - o) / d;
    near = std::max(near, std::min(t1, t2));
    far = std::min(far, std::max(t1, t2));
  }
  near -= std::abs(near) * 0x1p-40;
  far += std::abs(far) * 0x1p-40;
  entry = near;
  return near <= far && far >= double(ray.tmin) && near <= reach;
}

}  // namespace

CertifiedInstances::CertifiedInstances(std::shared_ptr<const Scene> scene) : scene_(std::move(scene)) {
  const Scene& s = *scene_;
  require_valid_instances(s);
  require_spheres_stay_spheres(s);
  BvhConfig config;
  config.builder = BvhBuilder::binned;
  config.max_leaf_size = 4;
  trees_.reserve(s.bases.size() + 1);
  for (const auto& base : s.bases) trees_.push_back(build_bvh(*base, config));
  auto add_part = [&](const Scene* geometry, const Bvh2* tree, const AffineTransform& xf, unsigned instance) {
    Part p;
    p.geometry = geometry;
    p.tree = tree;
    p.object_to_world = xf;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p.abs_linear[i][j] = std::abs(xf.m[i][j]);
    p.sphere_scale = std::cbrt(std::abs(xf.determinant()));
    p.instance = instance;
    parts_.push_back(p);
  };
  if (s.primitive_count() > 0) {
    flat_part_ = s.flat_part();
    trees_.push_back(build_bvh(*flat_part_, config));
    add_part(flat_part_.get(), &trees_.back(), AffineTransform::identity(), kInvalidId);
  }
  for (std::size_t i = 0; i < s.instances.size(); ++i)
    add_part(s.bases[s.instances[i].base].get(), &trees_[s.instances[i].base], s.instances[i].transform,
             static_cast<unsigned>(i));
  // The top level over the parts' world boxes, rounded outward to float.
  std::vector<Bounds3f> boxes;
  boxes.reserve(parts_.size());
  for (const Part& p : parts_) {
    if (p.tree->nodes.empty()) {
      boxes.emplace_back();
      continue;
    }
    const WorldBox w = world_box(p.tree->nodes[0].box, p.object_to_world, p.abs_linear);
    Bounds3f b;
    for (int i = 0; i < 3; ++i) {
      b.lo[i] = std::nextafter(static_cast<float>(w.lo[i]), -std::numeric_limits<float>::infinity());
      b.hi[i] = std::nextafter(static_cast<float>(w.hi[i]), std::numeric_limits<float>::infinity());
    }
    boxes.push_back(b);
    bounds_.extend(b);
  }
  BvhConfig top = config;
  top.max_leaf_size = 2;
  top_ = build_bvh_over_boxes(boxes, top);
}

AccelStats CertifiedInstances::stats() const {
  AccelStats s;
  auto add = [&](const Bvh2& t) {
    s.bytes += t.nodes.size() * sizeof(Bvh2Node) + t.prims.size() * sizeof(std::uint32_t);
    s.nodes += t.nodes.size();
  };
  for (const Bvh2& t : trees_) add(t);
  add(top_);
  s.bytes += parts_.size() * sizeof(Part);
  return s;
}

template <bool kAnyHit, class Counters>
bool CertifiedInstances::trace(const Ray& ray, Hit& hit, Counters& counters) const {
  if (top_.nodes.empty()) return false;
  CK::Context ctx = CK::prepare(ray);
  // Each offer gets a fresh id: the kernel takes an id it holds as the same primitive offered
  // again, and (instance, primitive) pairs do not fit 32 bits at 3.1·10^9 triangles.
  unsigned next_id = 0;
  bool found = false;
  TriangleHit best{};
  unsigned best_prim = kInvalidId, best_instance = kInvalidId;

  struct Entry {
    std::uint32_t node;
    double entry;
  };
  // Near-first over a binary tree whose boxes come from `box_of(node)`; `leaf` returns true to stop.
  auto walk = [&](const Bvh2& tree, auto&& box_of, auto&& leaf) -> bool {
    Entry stack[kBvhMaxDepth + 2];
    int top = 0;
    double root_entry;
    if (!meets(ray, box_of(tree.nodes[0]), CK::closest(ctx), root_entry)) return false;
    stack[top++] = {0, root_entry};
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.entry > CK::closest(ctx)) continue;
      const Bvh2Node& node = tree.nodes[e.node];
      counters.node();
      if (node.is_leaf()) {
        counters.leaf();
        if (leaf(node)) return true;
        continue;
      }
      double t0, t1;
      const bool h0 = meets(ray, box_of(tree.nodes[node.first]), CK::closest(ctx), t0);
      const bool h1 = meets(ray, box_of(tree.nodes[node.first + 1]), CK::closest(ctx), t1);
      if (h0 && h1) {  // the nearer on top
        const bool first_nearer = t0 <= t1;
        stack[top++] = first_nearer ? Entry{node.first + 1, t1} : Entry{node.first, t0};
        stack[top++] = first_nearer ? Entry{node.first, t0} : Entry{node.first + 1, t1};
      } else if (h0) {
        stack[top++] = {node.first, t0};
      } else if (h1) {
        stack[top++] = {node.first + 1, t1};
      }
    }
    return false;
  };

  auto offer_part = [&](const Part& part) -> bool {
    if (part.tree->nodes.empty()) return false;
    const Scene& g = *part.geometry;
    const AffineTransform& xf = part.object_to_world;
    auto box_of = [&](const Bvh2Node& n) { return world_box(n.box, xf, part.abs_linear); };
    return walk(*part.tree, box_of, [&](const Bvh2Node& leaf) {
      for (std::uint32_t k = leaf.first; k < leaf.first + leaf.count; ++k) {
        const unsigned prim = part.tree->prims[k];
        counters.prim_test();
        TriangleHit th;
        bool won;
        if (g.is_sphere(prim)) {
          const Sphere& s = g.sphere(prim);
          won = CK::intersect_sphere(ctx, next_id++, Sphere{xf.apply_point(s.center), static_cast<float>(s.radius * part.sphere_scale)}, th);
        } else {
          const auto& tri = g.mesh.triangles[prim];
          const auto& v = g.mesh.vertices;
          won = CK::intersect(ctx, next_id++, xf.apply_point(v[tri[0]]), xf.apply_point(v[tri[1]]),
                              xf.apply_point(v[tri[2]]), th);
        }
        if (!won) continue;
        counters.prim_hit();
        found = true;
        best = th;
        best_prim = prim;
        best_instance = part.instance;
        if constexpr (kAnyHit) return true;
      }
      return false;
    });
  };

  walk(top_, [](const Bvh2Node& n) { return world_box(n.box); }, [&](const Bvh2Node& leaf) {
    for (std::uint32_t k = leaf.first; k < leaf.first + leaf.count; ++k)
      if (offer_part(parts_[top_.prims[k]])) return true;
    return false;
  });
  if (!found) return false;
  hit.t = best.t;
  hit.u = best.u;
  hit.v = best.v;
  hit.prim = best_prim;
  hit.instance = best_instance;
  return true;
}

template <class Counters>
bool CertifiedInstances::intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
  if (!trace<false>(ray, hit, counters)) return false;
  ray.tmax = hit.t;
  return true;
}

template <class Counters>
bool CertifiedInstances::occluded_impl(const Ray& ray, Counters& counters) const {
  Hit hit;
  return trace<true>(any_hit_ray<CK>(ray), hit, counters);
}

template bool CertifiedInstances::intersect_impl<NoCounters>(Ray&, Hit&, NoCounters&) const;
template bool CertifiedInstances::intersect_impl<RayCounters>(Ray&, Hit&, RayCounters&) const;
template bool CertifiedInstances::occluded_impl<NoCounters>(const Ray&, NoCounters&) const;
template bool CertifiedInstances::occluded_impl<RayCounters>(const Ray&, RayCounters&) const;

namespace {

AccelKind make_certified_instances_kind() {
  return {"certified-instances",
          "certified first hits for an instanced scene's flat copy without storing it (what kernel=certified uses "
          "beyond 2^26 primitives): a binned BVH per base, node boxes carried to world space per ray",
          {},
          [](std::shared_ptr<const Scene> scene, SpecReader&, const BuildContext&) -> std::unique_ptr<Aggregate> {
            return std::make_unique<CertifiedInstances>(std::move(scene));
          },
          [](SpecReader&) { return certified_accuracy("certified kernel on the flat copy's world vertices, conservative world boxes"); }};
}

const AccelRegistration certified_instances_registration(make_certified_instances_kind(), 75);

}  // namespace

}  // namespace raylab
