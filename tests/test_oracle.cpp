// The one parameterised oracle suite (after CGAL's AABB_tree Tree_vs_naive and Embree's verify):
// every accelerator the factory knows, with its default parameters (the certified kernel wherever
// a kernel is chosen) and its listed variants (kernel=watertight among them), against the exact
// oracle on random, procedural, degenerate and closed meshes, far from the origin and tiny, with
// rays of every generator: touching and grazing rays on closed meshes included. The oracle classifies every ray (contact_classes.h)
// and each accelerator is held to its own stated AccuracyBound per class, counted as
// `raylab trace --check exact` counts it (accel/common/hit_comparison.h): by the tolerance rule,
// or, for methods stated exact (the exact and certified kernels), by the exact rule with 0
// mismatches allowed. An accelerator registered in the factory later is run here without any
// change to this file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <optional>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "accel/exact/contact_classes.h"
#include "cost/model_file.h"
#include "gltf_writer.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

/// Scenes: random soups, closed meshes, spheres, the lecture's procedural cases, instances, a
/// real CGAL mesh, `degenerate`, built by hand below, `gltf-instances`, a glTF 2.0 file
/// written below and read through Assimp: several bases under several transforms (non-uniform
/// scales among them) beside flat geometry, two `transformed:` scenes (far from the origin, tiny),
/// and the scenes where log N fails.
const std::vector<std::string> kScenes = {
    "soup:n=3000",
    "sphere:n=2000",
    "sphereflake:depth=2",
    "sphereflake:depth=1,as=triangles",
    "grass:blades=400",
    "walls:n=12,angle=30",
    "stadium:object=(sphere:n=800),ratio=50",
    "instances:of=(sphere:n=400),count=6",
    "decimated:of=cgal:bunny00,faces=4000",
    "degenerate",
    "gltf-instances",
    "transformed:of=(sphere:n=800),rotate=1;2;3:37,scale=100,translate=1e5:-3e4:2e5",
    "transformed:of=cgal:anchor,rotate=x:50,scale=1e-6",
    // The scenes where log N fails (procedural.h), small.
    "dust:n=2000",
    "needles:n=256",
    "fan:n=256",
    "row:n=256",
};

const std::vector<std::string> kRaySpecs = {"primary:4096", "diffuse:2048", "shadow:2048", "lines:4096",
                                            "edges:2048",   "vertices:2048", "touching:256", "grazing:256"};

/// Shared edges and vertices, a zero-area triangle, a repeated-vertex triangle, duplicated
/// and coplanar overlapping triangles, a fan of high valence, and identical bounds.
std::shared_ptr<const Scene> degenerate_scene() {
  auto s = std::make_shared<Scene>();
  s->spec = "degenerate";
  auto& m = s->mesh;
  auto add = [&](Vec3f a, Vec3f b, Vec3f c) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {a, b, c});
    m.triangles.push_back({base, base + 1, base + 2});
  };
  add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  add({1, 0, 0}, {1, 1, 0}, {0, 1, 0});  // shares the diagonal edge
  add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});  // duplicate
  add({0.25f, 0.25f, 0}, {2, 0.25f, 0}, {0.25f, 2, 0});  // coplanar, overlapping
  add({0, 0, 1}, {1, 1, 1}, {2, 2, 1});  // collinear: zero area
  add({0, 0, 2}, {0, 0, 2}, {1, 0, 2});  // repeated vertex
  const int fan = 64;                    // high-valence fan around (3, 0.5, 0.5)
  for (int i = 0; i < fan; ++i) {
    const double a0 = 2 * M_PI * i / fan, a1 = 2 * M_PI * (i + 1) / fan;
    add({3, 0.5f, 0.5f}, {3 + 0.5f * float(std::cos(a0)), 0.5f + 0.5f * float(std::sin(a0)), 0.3f},
        {3 + 0.5f * float(std::cos(a1)), 0.5f + 0.5f * float(std::sin(a1)), 0.3f});
  }
  return s;
}

/// A sphere under three nodes, a cube under two (instances), a random soup used once (flattened).
std::shared_ptr<const Scene> gltf_instances_scene() {
  test::GltfDocument doc;
  doc.meshes = {make_scene("sphere:n=400")->mesh, make_scene("walls:n=1")->mesh, make_scene("soup:n=200")->mesh};
  using test::quaternion;
  using test::trs_node;
  const std::array<double, 4> none = {0, 0, 0, 1};
  doc.nodes = {trs_node(0, {0, 0, 0}),
               trs_node(0, {3, 0.5, 0}, none, {1, 2, 0.5}),
               trs_node(-1, {-3, 0, 1}, quaternion({1, 2, 3}, 0.8), {1, 1, 1}, {3, 4}),
               trs_node(0, {0, 0, 0}, none, {0.7, 0.7, 0.7}),
               trs_node(1, {0, -2, 0}, none, {0.2, 0.2, 0.2}),
               trs_node(1, {0, 2, 2}, quaternion({0, 1, 0}, 1.2), {0.3, 0.1, 0.3}),
               trs_node(2, {0, 0, -3}, none, {2, 2, 2})};
  doc.roots = {0, 1, 2, 5, 6};
  const std::string path = (std::filesystem::temp_directory_path() / ("raylab_oracle_" + std::to_string(::getpid()) + ".gltf")).string();
  test::write_gltf(path, doc);
  auto scene = make_scene(path);
  std::filesystem::remove(path);
  return scene;
}

std::shared_ptr<const Scene> scene_for(const std::string& spec) {
  static std::map<std::string, std::shared_ptr<const Scene>> cache;
  auto& s = cache[spec];
  if (!s) s = spec == "degenerate" ? degenerate_scene() : spec == "gltf-instances" ? gltf_instances_scene() : make_scene(spec);
  return s;
}

struct Reference {
  std::vector<Ray> rays;
  TraceResult exact;
  /// The oracle's classes of the rays, made when a comparison first needs them (a run without
  /// mismatches is within every bound whatever the classes).
  std::optional<std::vector<RayContact>> classes;
};

Reference& reference_for(const std::string& scene_spec, const std::string& ray_spec) {
  static std::map<std::pair<std::string, std::string>, Reference> cache;
  auto key = std::make_pair(scene_spec, ray_spec);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  Reference ref;
  const auto scene = scene_for(scene_spec);
  ref.rays = make_ray_set(ray_spec, scene);
  const auto oracle = make_accelerator("exact", scene);
  ref.exact = trace_rays(*oracle, ref.rays, TraceOptions{0, false, is_any_hit_ray_spec(ray_spec)});
  return cache.emplace(key, std::move(ref)).first->second;
}

/// Feature-aimed rays need a mesh of the scene's own (not instanced, not spheres only); the
/// touching and grazing generators are run on the closed meshes.
bool applicable(const std::string& scene_spec, const std::string& ray_spec) {
  if (!is_feature_ray_spec(ray_spec)) return true;
  const auto scene = scene_for(scene_spec);
  if (scene->instanced() || scene->mesh.size() == 0) return false;
  const std::string name = parse_spec(ray_spec).name;
  return (name != "touching" && name != "grazing") || describe(*scene).closed;
}

std::vector<std::string> all_accel_specs() {
  std::vector<std::string> specs;
  for (const auto& kind : accelerator_kinds()) {
    specs.push_back(kind.name);
    for (const auto& v : kind.oracle_variants) specs.push_back(kind.name + ":" + v);
  }
  return specs;
}

using OracleParam = std::tuple<std::string, std::string>;  // accelerator spec, scene spec

class OracleSuite : public ::testing::TestWithParam<OracleParam> {};

TEST_P(OracleSuite, AgreesWithTheExactOracleWithinItsStatedBound) {
  const auto& [accel_spec, scene_spec] = GetParam();
  const auto scene = scene_for(scene_spec);
  const auto accel = make_accelerator(accel_spec, scene, model_build_context());
  const AccuracyBound bound = accuracy_bound(accel_spec);
  const double diagonal = length(Vec3d(scene->bounds().diagonal()));
  for (const auto& ray_spec : kRaySpecs) {
    if (!applicable(scene_spec, ray_spec)) continue;
    Reference& ref = reference_for(scene_spec, ray_spec);
    const bool any_hit = is_any_hit_ray_spec(ray_spec);
    const TraceResult got = trace_rays(*accel, ref.rays, TraceOptions{0, false, any_hit});
    auto compare = [&](const std::vector<RayContact>* classes) {
      return any_hit       ? compare_occlusion(got.blocked, ref.exact.blocked, classes)
             : bound.exact ? compare_hits_exact(*scene, ref.rays, got.hits, ref.exact.hits, classes)
                           : compare_hits(ref.rays, got.hits, ref.exact.hits, diagonal, classes);
    };
    HitComparison c = compare(nullptr);
    if (c.mismatches > 0) {
      if (!ref.classes) ref.classes = classify_contacts(scene, ref.rays);
      c = compare(&*ref.classes);
    }
    std::string why;
    EXPECT_TRUE(within_bound(bound, c, is_feature_ray_spec(ray_spec), &why))
        << accel_spec << " on " << scene_spec << " with " << ray_spec << ": " << why << " (" << c.false_hits
        << " false hits, " << c.missed_hits << " missed, " << c.wrong_t << " wrong t, " << c.ties << " ties of "
        << c.rays << " rays; bound: " << bound.statement << "); first mismatching ray "
        << (c.first_mismatches.empty() ? -1 : static_cast<long>(c.first_mismatches[0]));
    // Camera rays must see the scene, or the comparison proves little. (Diffuse and shadow rays
    // off a convex closed object legitimately hit nothing.)
    if (parse_spec(ray_spec).name == "primary") {
      EXPECT_GT(ref.exact.hit_count, 0u) << ray_spec << " on " << scene_spec;
    }
  }
}

std::string param_name(const ::testing::TestParamInfo<OracleParam>& info) {
  std::string s = std::get<0>(info.param) + "__" + std::get<1>(info.param);
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(EveryAccelerator, OracleSuite,
                         ::testing::Combine(::testing::ValuesIn(all_accel_specs()), ::testing::ValuesIn(kScenes)),
                         param_name);

}  // namespace
}  // namespace raylab
