// Ray generators: Cauchy-Crofton statistics of isotropic lines, counts, validity, determinism,
// spec errors, and the edge/vertex rays against a watertight brute-force tracer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "geometry/input_error.h"
#include "geometry/triangle_kernels.h"
#include "rays/camera.h"
#include "rays/isotropic_lines.h"
#include "rays/ray_generators.h"
#include "rays/surface_rays.h"

namespace raylab {
namespace {

/// Entry and exit of the line o + t·d (t unrestricted) with a box, in double; false on a miss.
bool clip_line(const Ray& r, const Vec3d& lo, const Vec3d& hi, double& t0, double& t1) {
  t0 = -std::numeric_limits<double>::infinity();
  t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double o = r.org[a], d = r.dir[a];
    if (d == 0.0) {
      if (o < lo[a] || o > hi[a]) return false;
      continue;
    }
    double tn = (lo[a] - o) / d, tf = (hi[a] - o) / d;
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
  }
  return t0 < t1;
}

/// A closed, outward-oriented box mesh with shared vertices.
TriangleMesh box_mesh(const Vec3f& lo, const Vec3f& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

Scene cube_scene() {
  Scene s;
  s.spec = "test-cube";
  s.mesh = box_mesh({0, 0, 0}, {1, 1, 1});
  return s;
}

/// Brute-force first hit with a triangle kernel, for triangles and spheres.
template <class Kernel>
Hit brute_force(const Scene& s, const Ray& ray) {
  auto ctx = Kernel::prepare(ray);
  Hit best;
  TriangleHit th;
  for (unsigned i = 0; i < s.mesh.size(); ++i)
    if (Kernel::intersect(ctx, i, s.mesh.vertex(i, 0), s.mesh.vertex(i, 1), s.mesh.vertex(i, 2), th))
      best = Hit{th.t, th.u, th.v, i, kInvalidId};
  for (unsigned k = 0; k < s.spheres.size(); ++k) {
    const auto id = static_cast<unsigned>(s.mesh.size() + k);
    if (Kernel::intersect_sphere(ctx, id, s.spheres[k], th)) best = Hit{th.t, th.u, th.v, id, kInvalidId};
  }
  return best;
}

FirstHitFunction tracer(const Scene& s) {
  return [&s](const Ray& r) { return brute_force<MollerTrumboreKernel>(s, r); };
}

bool same_bits(const std::vector<Ray>& a, const std::vector<Ray>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)) == 0;
}

TEST(RaysIsotropicLines, CroftonSurfaceRatioAndMeanChord) {
  const std::size_t n = 200000;
  const auto lines = isotropic_lines({0.5, 0.5, 0.5}, std::sqrt(3.0) / 2.0, n, 12345);
  ASSERT_EQ(lines.size(), n);
  std::size_t hit_cube = 0, hit_half = 0;
  double sum = 0.0, sum2 = 0.0;
  for (const Ray& r : lines) {
    ASSERT_TRUE(is_valid(r));
    ASSERT_NEAR(length(Vec3d(r.dir)), 1.0, 1e-6);
    double t0, t1;
    if (!clip_line(r, {0, 0, 0}, {1, 1, 1}, t0, t1)) continue;
    ASSERT_GE(t0, -1e-6) << "the ray starts inside the bounding sphere";
    ++hit_cube;
    const double chord = (t1 - t0) * length(Vec3d(r.dir));
    sum += chord;
    sum2 += chord * chord;
    if (clip_line(r, {0, 0, 0}, {0.5, 1, 1}, t0, t1)) ++hit_half;
  }
  // P(meet cube | meet ball) = area(cube) / area(sphere) = 6 / (3π) ≈ 0.64.
  const double m = static_cast<double>(hit_cube);
  EXPECT_NEAR(m / n, 6.0 / (3.0 * std::numbers::pi), 3.0 * std::sqrt(0.64 * 0.36 / n));
  // Crofton: P(meet half box | meet cube) = area ratio 4/6.
  const double p = 2.0 / 3.0;
  EXPECT_NEAR(hit_half / m, p, 3.0 * std::sqrt(p * (1 - p) / m));
  // Mean chord = 4V/S = 2/3.
  const double mean = sum / m;
  const double sd = std::sqrt(std::max(0.0, sum2 / m - mean * mean));
  EXPECT_NEAR(mean, 2.0 / 3.0, 3.0 * sd / std::sqrt(m));
}

TEST(RaysIsotropicLines, DeterministicPerSeed) {
  const auto a = isotropic_lines({1, 2, 3}, 2.0, 1000, 7);
  EXPECT_TRUE(same_bits(a, isotropic_lines({1, 2, 3}, 2.0, 1000, 7)));
  EXPECT_FALSE(same_bits(a, isotropic_lines({1, 2, 3}, 2.0, 1000, 8)));
}

TEST(RaysCamera, CentrePixelLooksAtTheBoxCentre) {
  const Bounds3f box({-1, 2, 3}, {3, 4, 9});
  const Camera cam = frame_camera(box);
  const Ray r = camera_ray(cam, 50.0, 50.0, 100, 100);
  const Vec3d to_centre = normalize(Vec3d(box.center()) - Vec3d(r.org));
  EXPECT_GT(dot(normalize(Vec3d(r.dir)), to_centre), 1.0 - 1e-6);
  // The top row looks up, the left column looks left.
  EXPECT_GT(dot(Vec3d(camera_ray(cam, 50.0, 0.5, 100, 100).dir), cam.up), 0.0);
  EXPECT_LT(dot(Vec3d(camera_ray(cam, 0.5, 50.0, 100, 100).dir), cam.right), 0.0);
  EXPECT_THROW(frame_camera(Bounds3f()), InputError);
}

TEST(RaysGenerators, CountsAreExactAndRaysValid) {
  const Scene scene = cube_scene();
  const auto trace = tracer(scene);
  for (const char* spec : {"diffuse:1000", "shadow:777", "ao:500", "lines:1234", "edges:300", "vertices:301",
                           "touching:200", "grazing:201", "primary:100", "diffuse:1", "lines:1"}) {
    const auto rays = generate_rays(spec, scene, trace);
    const std::string s = spec;
    EXPECT_EQ(rays.size(), static_cast<std::size_t>(std::stoul(s.substr(s.find(':') + 1)))) << spec;
    for (const Ray& r : rays) ASSERT_TRUE(is_valid(r)) << spec;
  }
  EXPECT_EQ(generate_rays("primary:50", scene, trace).size(), 49u) << "rounded to a 7x7 image";
  EXPECT_EQ(generate_rays("primary:2", scene, trace).size(), 1u);
}

TEST(RaysGenerators, DeterministicPerSeed) {
  const Scene scene = cube_scene();
  const auto trace = tracer(scene);
  for (const std::string name : {"diffuse", "shadow", "ao", "lines", "edges", "vertices", "touching", "grazing"}) {
    const auto a = generate_rays(name + ":200", scene, trace);
    EXPECT_TRUE(same_bits(a, generate_rays(name + ":200,seed=1", scene, trace))) << name << ": default seed is 1";
    EXPECT_FALSE(same_bits(a, generate_rays(name + ":200,seed=2", scene, trace))) << name;
  }
  EXPECT_TRUE(same_bits(generate_rays("primary:64", scene, trace), generate_rays("primary:64", scene, trace)));
}

TEST(RaysGenerators, PrimaryIsScanlineOrder) {
  const Scene scene = cube_scene();
  const auto rays = generate_rays("primary:16,fov=60,from=0;0;1", scene, {});
  const Camera cam = frame_camera(scene.bounds(), 60.0, {0, 0, 1});
  for (int i = 0; i < 16; ++i) {
    const Ray r = camera_ray(cam, i % 4 + 0.5, i / 4 + 0.5, 4, 4);
    EXPECT_EQ(std::memcmp(&r, &rays[i], sizeof(Ray)), 0) << i;
  }
}

TEST(RaysGenerators, InsideCameraLooksAtTheCentreFromInsideTheBox) {
  const Scene scene = cube_scene();
  const Vec3d from(1.0, 0.6, 1.4);
  const Camera cam = inside_camera(scene.bounds(), 45.0, from);
  // The ray centre + s·from/|from| leaves the unit cube at s = 0.5 / (1.4/|from|); the eye is 0.9 of the way.
  const Vec3d expected = Vec3d(0.5) + normalize(from) * (kInsideCameraFraction * 0.5 / normalize(from).z);
  EXPECT_NEAR(cam.eye.x, expected.x, 1e-12);
  EXPECT_NEAR(cam.eye.y, expected.y, 1e-12);
  EXPECT_NEAR(cam.eye.z, expected.z, 1e-12);
  EXPECT_LT(cam.eye.z, 1.0);
  EXPECT_NEAR(dot(cam.forward, -normalize(from)), 1.0, 1e-12);
  const auto primary = generate_rays("primary:64,camera=inside", scene, {});
  ASSERT_EQ(primary.size(), 64u);
  for (const Ray& r : primary) EXPECT_TRUE(scene.bounds().contains(r.org));
  // From inside a closed cube every bounce hits a face; from outside (the default) it cannot hit the convex cube.
  const auto trace = tracer(scene);
  for (const Ray& r : generate_rays("diffuse:300,camera=inside", scene, trace)) EXPECT_TRUE(trace(r).valid());
  for (const Ray& r : generate_rays("diffuse:300", scene, trace)) EXPECT_FALSE(trace(r).valid());
}

TEST(RaysGenerators, SurfaceRaysLeaveTheVisibleSide) {
  const Scene scene = cube_scene();
  const auto trace = tracer(scene);
  const Bounds3f box = scene.bounds();
  for (const char* spec : {"diffuse:500", "ao:500"}) {
    for (const Ray& r : generate_rays(spec, scene, trace)) {
      EXPECT_FALSE(box.contains(r.org) && r.org.x > 0 && r.org.x < 1 && r.org.y > 0 && r.org.y < 1 && r.org.z > 0 &&
                   r.org.z < 1)
          << "origin inside the cube";
      EXPECT_FALSE(trace(r).valid()) << spec << ": a ray leaving a convex body cannot hit it";
    }
  }
  // The light is above the cube: the top face (y = 1) is lit; the visible side faces are lit too.
  for (const Ray& r : generate_rays("shadow:500", scene, trace)) {
    EXPECT_EQ(r.tmax, kShadowTmax);
    EXPECT_GT(r.dir.y, 0.0f);
  }
}

// Surface rays leave a scene and its copy scaled by a power of two (exactly representable, so
// every coordinate scales without rounding) from the same points, scaled: the offset off the
// surface scales with the scene (offset_ray.h). With Wächter and Binder's fixed near-origin offset
// of 1/65536, the cube's faces at coordinate 0 put the scaled copies' origins elsewhere.
TEST(RaysGenerators, SurfaceRaysScaleWithTheScene) {
  const Scene unit = cube_scene();
  const auto unit_trace = tracer(unit);
  for (const float k : {0x1p-14f, 0x1p14f}) {
    Scene scaled;
    scaled.spec = "test-cube-scaled";
    scaled.mesh = box_mesh({0, 0, 0}, {k, k, k});
    const auto scaled_trace = tracer(scaled);
    for (const char* spec : {"diffuse:300", "ao:300", "shadow:300", "diffuse:300,camera=inside"}) {
      const auto a = generate_rays(spec, unit, unit_trace), b = generate_rays(spec, scaled, scaled_trace);
      ASSERT_EQ(a.size(), b.size()) << spec;
      const bool direction_scales = std::string(spec).starts_with("shadow");
      for (std::size_t i = 0; i < a.size(); ++i)
        for (int axis = 0; axis < 3; ++axis) {
          ASSERT_EQ(b[i].org[axis], a[i].org[axis] * k) << spec << ", scale " << k << ", ray " << i << ", axis " << axis;
          ASSERT_EQ(b[i].dir[axis], direction_scales ? a[i].dir[axis] * k : a[i].dir[axis]) << spec << ", ray " << i;
        }
    }
  }
}

TEST(RaysGenerators, EdgeAndVertexRaysHitAClosedMeshWatertight) {
  const Scene scene = cube_scene();
  for (const char* spec : {"edges:2000", "vertices:2000"}) {
    for (const Ray& r : generate_rays(spec, scene, {})) {
      const Hit h = brute_force<WatertightKernel>(scene, r);
      ASSERT_TRUE(h.valid()) << spec;
      EXPECT_NEAR(h.t, 1.0f, 1e-4f) << spec;
    }
  }
  // Vertex rays aim exactly at a vertex: o + d is the vertex up to one rounding.
  for (const Ray& r : generate_rays("vertices:200", scene, {})) {
    const Vec3d p = Vec3d(r.org) + Vec3d(r.dir);
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(std::abs(p[a]) < 1e-6 || std::abs(p[a] - 1.0) < 1e-6) << p[a];
  }
}

TEST(RaysGenerators, EdgeRaysOnATriangleSoupWeldVertices) {
  // The same cube as a soup: every triangle has its own vertices.
  const TriangleMesh indexed = box_mesh({0, 0, 0}, {1, 1, 1});
  Scene soup;
  for (std::size_t t = 0; t < indexed.size(); ++t) {
    const auto base = static_cast<std::uint32_t>(soup.mesh.vertices.size());
    for (int c = 0; c < 3; ++c) soup.mesh.vertices.push_back(indexed.vertex(t, c));
    soup.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  for (const Ray& r : generate_rays("edges:500", soup, {}))
    ASSERT_TRUE(brute_force<WatertightKernel>(soup, r).valid());
}

TEST(RaysGenerators, BadSpecsThrow) {
  const Scene scene = cube_scene();
  const auto trace = tracer(scene);
  for (const char* spec : {"bogus:10", "diffuse", "diffuse:0", "diffuse:268435457", "diffuse:x", "diffuse:10,foo=1",
                           "lines:10,fov=30", "primary:10,seed=3", "diffuse:10,seed=-1", "primary:10,fov=0",
                           "primary:10,from=1;2", "primary:10,from=0;0;0", "lines:10,20", "file:",
                           "file:/nonexistent/rays.txt", "primary:10,camera=behind", "lines:10,camera=inside"}) {
    EXPECT_THROW(generate_rays(spec, scene, trace), InputError) << spec;
  }
  try {
    generate_rays("bogus:10", scene, trace);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bogus"), std::string::npos) << e.what();
  }
  EXPECT_THROW(generate_rays("lines:10", Scene{}, trace), InputError) << "empty scene";
}

TEST(RaysGenerators, InvisibleSceneThrowsInsteadOfLooping) {
  const Scene scene = cube_scene();
  const FirstHitFunction miss = [](const Ray&) { return Hit{}; };
  for (const char* spec : {"diffuse:1000", "shadow:10", "ao:1"}) {
    try {
      generate_rays(spec, scene, miss);
      ADD_FAILURE() << spec << " did not throw";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not visible"), std::string::npos) << e.what();
    }
  }
  // Looking away from the scene is the same: only the spec's camera decides.
  EXPECT_THROW(generate_rays("diffuse:10", scene, {}), InputError) << "no tracer";
}

TEST(RaysGenerators, FeatureRaysNeedTriangles) {
  Scene spheres;
  spheres.spheres.push_back({{0, 0, 0}, 1.0f});
  EXPECT_THROW(generate_rays("edges:10", spheres, {}), InputError);
  EXPECT_THROW(generate_rays("vertices:10", spheres, {}), InputError);
  auto base = std::make_shared<Scene>(cube_scene());
  Scene inst;
  inst.bases = {base};
  inst.instances = {{AffineTransform::identity(), 0}, {AffineTransform::translation({3, 0, 0}), 0}};
  EXPECT_THROW(generate_rays("edges:10", inst, {}), InputError);
  // Lines work on any scene.
  EXPECT_EQ(generate_rays("lines:10", spheres, {}).size(), 10u);
}

TEST(RaysGenerators, DiffuseOnSpheresAndInstances) {
  Scene spheres;
  spheres.spheres.push_back({{0, 0, 0}, 1.0f});
  spheres.spheres.push_back({{3, 0, 0}, 0.5f});
  const auto rays = generate_rays("diffuse:300", spheres, tracer(spheres));
  ASSERT_EQ(rays.size(), 300u);
  const auto trace_spheres = tracer(spheres);
  for (const Ray& r : rays) {
    const Hit h = trace_spheres(r);
    const unsigned own = r.org.x > 1.5f ? 1u : 0u;
    EXPECT_TRUE(!h.valid() || h.prim != own) << "a ray leaving a sphere cannot hit it again";
    // Offset outward by at most 256 ulps per axis (Wächter & Binder).
    const double dist = length(Vec3d(r.org) - Vec3d(spheres.spheres[own].center));
    EXPECT_GT(dist, spheres.spheres[own].radius);
    EXPECT_LT(dist, spheres.spheres[own].radius + 1e-4);
  }

  // Instanced cubes: a brute-force tracer over instances.
  auto base = std::make_shared<Scene>(cube_scene());
  Scene inst;
  inst.bases = {base};
  inst.instances = {{AffineTransform::identity(), 0},
                    {AffineTransform::translation({3, 0, 0}) * AffineTransform::scaling({1, 2, 0.5}), 0}};
  const FirstHitFunction trace = [&](const Ray& r) {
    Hit best;
    for (unsigned k = 0; k < inst.instances.size(); ++k) {
      Ray local = inst.instances[k].transform.inverse().apply(r);
      local.tmax = best.t < r.tmax ? best.t : r.tmax;
      Hit h = brute_force<MollerTrumboreKernel>(*base, local);
      if (h.valid()) {
        h.instance = k;
        best = h;
      }
    }
    return best;
  };
  for (const Ray& r : generate_rays("diffuse:300", inst, trace)) {
    const Hit h = trace(r);
    // A bounce may reach the other cube, never its own.
    if (h.valid()) {
      const Vec3f p = r.org;
      EXPECT_EQ(h.instance, p.x > 2.0f ? 0u : 1u);
    }
  }
}

TEST(RaysGenerators, DocsNameEveryGenerator) {
  const auto names = ray_generator_names();
  for (const char* n : {"primary", "diffuse", "shadow", "ao", "lines", "edges", "vertices", "file"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  for (const auto& d : ray_generator_docs()) EXPECT_FALSE(d.summary.empty()) << d.name;
}

}  // namespace
}  // namespace raylab
