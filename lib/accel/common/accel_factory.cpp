#include "accel/common/accel_factory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "accel/brute/brute_force.h"
#include "accel/bvh/primitive_bvh.h"
#include "accel/common/ray_sets.h"
#include "accel/embree/embree_accel.h"
#include "accel/exact/certified_instances.h"
#include "accel/exact/exact_oracle.h"
#include "accel/grid/grid_spec.h"
#include "accel/grid/uniform_grid.h"
#include "accel/nested_grid/nested_grid.h"
#include "geometry/exact_predicates.h"
#include "geometry/input_error.h"
#include "scene/transformed_primitive.h"

namespace raylab {
namespace {

/// Builds `make(base)` once per base and places it under each of its instances' transforms, and
/// `make(flat part)` on the flat geometry, all in a BVH top level (PrimitiveBvh).
std::unique_ptr<Aggregate> over_instances(const Scene& scene,
                                          const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make) {
  require_valid_instances(scene);
  std::vector<std::shared_ptr<const Primitive>> inner;
  inner.reserve(scene.bases.size());
  for (const auto& base : scene.bases) inner.push_back(make(base));
  std::vector<std::shared_ptr<const Primitive>> prims;
  prims.reserve(scene.instances.size() + 1);
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    prims.push_back(std::make_shared<TransformedPrimitive>(inner[scene.instances[i].base], scene.instances[i].transform,
                                                           static_cast<unsigned>(i)));
  // Its accelerators write hits with instance = kInvalidId (scene_primitives.h), naming the flat geometry.
  if (scene.primitive_count() > 0) prims.push_back(make(scene.flat_part()));
  return std::make_unique<PrimitiveBvh>(std::move(prims));
}

std::unique_ptr<Aggregate> make_brute(std::shared_ptr<const Scene> scene, const std::string& kernel) {
  if (scene->instanced())
    return make_instanced_for_kernel(kernel == "certified" ? KernelChoice::certified : KernelChoice::watertight, *scene,
                                     [&](std::shared_ptr<const Scene> base) { return make_brute(std::move(base), kernel); });
  if (kernel == "mt") return std::make_unique<BruteForce<MollerTrumboreKernel>>(std::move(scene));
  if (kernel == "exact") return std::make_unique<BruteForce<ExactKernel>>(std::move(scene));
  if (kernel == "certified") return std::make_unique<BruteForce<CertifiedKernel>>(std::move(scene));
  return std::make_unique<BruteForce<WatertightKernel>>(std::move(scene));
}

const std::vector<std::string> kKernels = {"certified", "watertight", "mt", "exact"};
const std::vector<std::string> kQualities = {"low", "medium", "high"};

EmbreeConfig read_embree(SpecReader& r, bool robust) {
  EmbreeConfig c;
  const std::string q = r.get_choice("quality", "medium", kQualities);
  c.quality = q == "low" ? EmbreeConfig::Quality::low
                         : (q == "high" ? EmbreeConfig::Quality::high : EmbreeConfig::Quality::medium);
  c.robust = robust;
  return c;
}

std::vector<AccelKind> make_registry() {
  std::vector<AccelKind> kinds;
  kinds.push_back(
      {"brute",
       "every ray against every primitive (|Image| x |Objects|)",
       {{"kernel", "certified",
         "ray-triangle kernel: certified (float with a forward error bound, exact CGAL fallback) | watertight (Woop et "
         "al. 2013) | mt (Moller-Trumbore) | exact (CGAL)"}},
       [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) {
         return make_brute(std::move(scene), r.get_choice("kernel", "certified", kKernels));
       },
       [](SpecReader& r) -> AccuracyBound {
         const std::string k = r.get_choice("kernel", "certified", kKernels);
         if (k == "mt") {
           AccuracyBound b = float_accuracy(
               0.5, 1e-3,
               "Moller-Trumbore is not watertight: crossing rays through shared edges and vertices may slip through "
               "(bound: 50% of edge/vertex-aimed crossing rays, 0.1% of other crossing rays); touching, on-surface and "
               "ill-conditioned rays: no agreement claimed");
           b.kernel = "mt";
           return b;
         }
         if (k == "exact") return exact_accuracy("exact kernel");
         if (k == "certified") return certified_accuracy("certified kernel");
         return watertight_accuracy("watertight kernel");
       },
       {"kernel=mt", "kernel=exact", "kernel=watertight"}});
  kinds.push_back({"exact",
                   "the exact oracle: CGAL AABB-tree candidates, exact predicates, exact first-hit order",
                   {},
                   [](std::shared_ptr<const Scene> scene, SpecReader&, const BuildContext&) {
                     return make_exact_oracle(std::move(scene));
                   },
                   [](SpecReader&) -> AccuracyBound { return exact_accuracy("exact by construction"); }});
  kinds.push_back({"embree",
                   "Intel Embree 3 (rtcIntersect1/rtcOccluded1), the speed baseline",
                   {{"quality", "medium", "rtcSetSceneBuildQuality: low | medium | high"}},
                   [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) {
                     return make_embree_accel(std::move(scene), read_embree(r, false));
                   },
                   [](SpecReader& r) -> AccuracyBound {
                     r.get_choice("quality", "medium", kQualities);
                     return float_accuracy(0.6, 1e-3,
                                           "Embree's default intersector is not watertight: documented to miss rays "
                                           "aimed at edges and vertices (bound: 60% of edge/vertex-aimed crossing "
                                           "rays, 0.1% of other crossing rays); touching, on-surface and "
                                           "ill-conditioned rays: no agreement claimed");
                   },
                   {"quality=high"}});
  kinds.push_back({"embree-robust",
                   "Intel Embree 3 with RTC_SCENE_FLAG_ROBUST (watertight along edges)",
                   {{"quality", "medium", "rtcSetSceneBuildQuality: low | medium | high"}},
                   [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) {
                     return make_embree_accel(std::move(scene), read_embree(r, true));
                   },
                   [](SpecReader& r) -> AccuracyBound {
                     r.get_choice("quality", "medium", kQualities);
                     return float_accuracy(0.1, 1e-3,
                                           "Embree's robust mode is watertight along edges but still misses some rays "
                                           "aimed exactly at vertices (bound: 10% of edge/vertex-aimed crossing rays, "
                                           "0.1% of other crossing rays); touching, on-surface and ill-conditioned "
                                           "rays (where it also hits zero-area triangles): no agreement claimed");
                   }});
  kinds.push_back(
      {"grid",
       "the lecture's uniform grid: d·∛n cells, 3D-DDA (Amanatides & Woo 1987), in-cell acceptance, mailboxes",
       grid_cell_params(),
       [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) -> std::unique_ptr<Aggregate> {
         const GridConfig c = read_grid_config(r);
         auto make = [c](std::shared_ptr<const Scene> s) -> std::unique_ptr<Aggregate> {
           return std::make_unique<UniformGrid>(std::move(s), c);
         };
         return scene->instanced() ? make_instanced_for_kernel(c.kernel, *scene, make) : make(std::move(scene));
       },
       [](SpecReader& r) { return grid_accuracy(read_grid_config(r)); },
       {"place=exact", "place=bbox", "mailbox=off", "accept=first", "d=0.5", "d=8", "kernel=watertight",
        "kernel=watertight,place=exact,mailbox=off", "kernel=watertight,place=bbox"}});
  kinds.push_back(
      {"nested-grid",
       "grids in crowded cells (the lecture's nested grid) or the two-level grid of Kalojanov et al. 2011",
       nested_grid_params(),
       [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) -> std::unique_ptr<Aggregate> {
         const NestedGridConfig c = read_nested_grid_config(r);
         auto make = [c](std::shared_ptr<const Scene> s) -> std::unique_ptr<Aggregate> {
           return std::make_unique<NestedGrid>(std::move(s), c);
         };
         return scene->instanced() ? make_instanced_for_kernel(c.cells.kernel, *scene, make) : make(std::move(scene));
       },
       [](SpecReader& r) { return grid_accuracy(read_nested_grid_config(r).cells); },
       {"mode=two-level", "place=exact", "place=bbox", "mailbox=off", "accept=first", "threshold=4,depth=3",
        "kernel=watertight"}});
  return kinds;
}

}  // namespace

std::unique_ptr<Aggregate> make_instanced_aggregate(
    const Scene& scene, const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make) {
  return over_instances(scene, make);
}

std::unique_ptr<Aggregate> make_instanced_for_kernel(
    KernelChoice kernel, const Scene& scene,
    const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make) {
  if (kernel != KernelChoice::certified) return over_instances(scene, make);
  // The flat copy under the requested structure while the exact oracle would hold it; beyond, the
  // same answers from the bases alone (certified_instances.h).
  if (scene.total_primitive_count() <= kExactOracleMaxPrimitives) return make_over_flattened_instances(scene, make);
  return std::make_unique<CertifiedInstances>(std::make_shared<const Scene>(scene));
}

RayBucket ray_bucket(const RayContact& c) {
  if (c.ill_conditioned) return RayBucket::ill_conditioned;
  if (c.contact == Contact::touching) return RayBucket::touching;
  if (c.contact == Contact::on_surface) return RayBucket::on_surface;
  return RayBucket::crossing;
}

const char* ray_bucket_name(RayBucket b) {
  switch (b) {
    case RayBucket::crossing: return "crossing";
    case RayBucket::touching: return "touching";
    case RayBucket::on_surface: return "on_surface";
    case RayBucket::ill_conditioned: return "ill_conditioned";
  }
  return "?";
}

double AccuracyBound::max_mismatch_rate(RayBucket bucket, bool feature_rays) const {
  switch (bucket) {
    case RayBucket::crossing: return feature_rays ? crossing_features : crossing_other;
    case RayBucket::touching: return touching;
    case RayBucket::on_surface: return on_surface;
    case RayBucket::ill_conditioned: return ill_conditioned;
  }
  return 0.0;
}

std::size_t allowed_mismatches(const AccuracyBound& bound, RayBucket b, bool feature_rays, std::size_t rays) {
  // Rounded up: a bucket of a few rays may hold one mismatch under any non-zero rate.
  return static_cast<std::size_t>(std::ceil(bound.max_mismatch_rate(b, feature_rays) * static_cast<double>(rays)));
}

bool within_bound(const AccuracyBound& bound, const HitComparison& c, bool feature_rays, std::string* why) {
  bool ok = true;
  for (int k = 0; k < kRayBuckets; ++k) {
    const auto b = static_cast<RayBucket>(k);
    const std::size_t allowed = allowed_mismatches(bound, b, feature_rays, c.bucket_rays[k]);
    if (c.bucket_mismatches[k] <= allowed) continue;
    ok = false;
    if (why)
      *why += std::string(*why == "" ? "" : "; ") + ray_bucket_name(b) + ": " + std::to_string(c.bucket_mismatches[k]) +
              " of " + std::to_string(c.bucket_rays[k]) + " rays mismatch, " + std::to_string(allowed) + " allowed";
  }
  return ok;
}

AccuracyBound float_accuracy(double crossing_features, double crossing_other, std::string statement) {
  AccuracyBound b;
  b.crossing_features = crossing_features;
  b.crossing_other = crossing_other;
  b.touching = b.on_surface = b.ill_conditioned = 1.0;
  b.statement = std::move(statement);
  return b;
}

AccuracyBound watertight_accuracy(const std::string& how) {
  AccuracyBound b = float_accuracy(0.0, 0.0,
                                   "crossing rays: exact agreement (" + how +
                                       "), at shared edges and vertices of closed and open meshes alike; touching, "
                                       "on-surface and ill-conditioned rays: decided by float rounding, no agreement "
                                       "claimed (measured in the report)");
  b.kernel = "watertight";
  return b;
}

AccuracyBound exact_accuracy(const std::string& how) {
  AccuracyBound b;
  b.exact = true;
  b.statement = "every class (crossing, touching, on-surface, ill-conditioned): the exact oracle's first hit (" + how +
                "): the same primitive, or one at the same exact t";
  b.kernel = "exact";
  return b;
}

AccuracyBound certified_accuracy(const std::string& how) {
  AccuracyBound b = exact_accuracy(how);
  b.kernel = "certified";
  return b;
}

AccuracyBound kernel_accuracy(KernelChoice kernel, const std::string& how) {
  if (kernel == KernelChoice::certified) return certified_accuracy("certified kernel, conservative traversal");
  return watertight_accuracy("watertight kernel, " + how);
}

namespace {

struct PendingRegistrations {
  std::vector<std::pair<int, AccelKind>> kinds;
  bool sealed = false;
};

PendingRegistrations& pending_registrations() {
  static PendingRegistrations pending;
  return pending;
}

}  // namespace

AccelRegistration::AccelRegistration(AccelKind kind, int order) {
  PendingRegistrations& p = pending_registrations();
  if (p.sealed) throw std::logic_error("AccelRegistration of '" + kind.name + "' after the registry was read");
  p.kinds.emplace_back(order, std::move(kind));
}

const std::vector<AccelKind>& accelerator_kinds() {
  static const std::vector<AccelKind> kinds = [] {
    std::vector<AccelKind> all = make_registry();
    PendingRegistrations& p = pending_registrations();
    p.sealed = true;
    std::stable_sort(p.kinds.begin(), p.kinds.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [order, kind] : p.kinds) all.push_back(std::move(kind));
    return all;
  }();
  return kinds;
}

const AccelKind& find_accelerator_kind(const std::string& name) {
  std::string names;
  for (const auto& k : accelerator_kinds()) {
    if (k.name == name) return k;
    names += (names.empty() ? "" : ", ") + k.name;
  }
  throw InputError("unknown accelerator '" + name + "' (valid: " + names + ")");
}

std::unique_ptr<Aggregate> make_accelerator(const std::string& spec, std::shared_ptr<const Scene> scene,
                                            const BuildContext& context) {
  SpecReader reader(parse_spec(spec));
  const AccelKind& kind = find_accelerator_kind(reader.spec().name);
  reader.reject_unknown_keys(kind.params);
  if (scene && scene->instanced()) require_valid_instances(*scene);
  if (!scene || scene->total_primitive_count() == 0) throw InputError("accelerator '" + spec + "': the scene is empty");
  auto accel = kind.build(std::move(scene), reader, context);
  reader.finish(kind.params);
  return accel;
}

std::string canonical_spec(const std::string& spec) {
  SpecReader reader(parse_spec(spec));
  const AccelKind& kind = find_accelerator_kind(reader.spec().name);
  reader.reject_unknown_keys(kind.params);
  const auto wrapped = [](const std::string& v) {
    const bool bare = v.empty() || v.find_first_of(",: ") == std::string::npos || (v.front() == '(' && v.back() == ')');
    return bare ? v : "(" + v + ")";
  };
  std::string out = kind.name;
  char sep = ':';
  for (const auto& p : reader.spec().positional) {
    out += sep + wrapped(p);
    sep = ',';
  }
  for (const auto& doc : kind.params) {
    std::string value = doc.default_value;
    for (const auto& [key, given] : reader.spec().params)
      if (key == doc.key) value = given;
    if (value.empty()) continue;
    out += sep + doc.key + "=" + wrapped(value);
    sep = ',';
  }
  return out;
}

AccuracyBound accuracy_bound(const std::string& spec) {
  SpecReader reader(parse_spec(spec));
  const AccelKind& kind = find_accelerator_kind(reader.spec().name);
  AccuracyBound b = kind.accuracy(reader);
  reader.finish(kind.params);
  return b;
}

void validate_accelerator_spec(const std::string& spec) {
  {
    // Unknown keys first: their message lists the valid ones.
    SpecReader reader(parse_spec(spec));
    reader.reject_unknown_keys(find_accelerator_kind(reader.spec().name).params);
  }
  accuracy_bound(spec);
}

}  // namespace raylab
