// The certified kernel (geometry/certified_kernel.h) against the exact kernel and the exact
// oracle: rays built so that the float decision is wrong (a touching ray the watertight kernel
// misses, two hits whose float order is wrong) are decided right, random and adversarial
// configurations agree with ExactFirstHit, and the exact path is taken only where the float
// filter cannot decide.
#include <gtest/gtest.h>

#include <cmath>

#include "accel/bvh/packed_triangles_simd.h"
#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "geometry/certified_kernel.h"
#include "geometry/exact_contact.h"
#include "geometry/float_mode.h"
#include "geometry/input_error.h"
#include "rays/feature_rays.h"
#include "rays/offset_ray.h"
#include "rays/random.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

struct Tri {
  Vec3f a, b, c;
};

/// The first hit among `tris` by `Kernel`: its index, or -1.
template <class Kernel>
int first_hit(const Ray& ray, const std::vector<Tri>& tris) {
  auto ctx = Kernel::prepare(ray);
  int best = -1;
  TriangleHit h;
  for (std::size_t i = 0; i < tris.size(); ++i)
    if (Kernel::intersect(ctx, static_cast<unsigned>(i), tris[i].a, tris[i].b, tris[i].c, h)) best = static_cast<int>(i);
  return best;
}

/// Whether triangle i's first contact with `ray` is exactly at the exact first hit among `tris`
/// (i = -1: no triangle is met).
bool exactly_first(const Ray& ray, const std::vector<Tri>& tris, int i) {
  ExactFirstHit all(ray);
  for (std::size_t k = 0; k < tris.size(); ++k) all.offer_triangle(static_cast<unsigned>(k), tris[k].a, tris[k].b, tris[k].c);
  if (i < 0) return !all.has_hit();
  ExactFirstHit one(ray);
  if (!all.has_hit() || !one.offer_triangle(0, tris[i].a, tris[i].b, tris[i].c)) return false;
  return one.compare_time(all) == 0;
}

// A ray exactly through a vertex of a closed mesh, outside the vertex's tangent cone, touches the
// surface there: the exact answer is a hit at the vertex. The watertight kernel decides it by the
// rounding of the shear (the vertex's sheared coordinates are not exactly 0) and misses some.
TEST(CertifiedKernel, FindsTouchingRaysTheWatertightKernelMisses) {
  const FloatModeScope ftz(true);
  const auto scene = make_scene("sphere:n=2000");
  const auto rays = touching_vertex_rays(scene->mesh, 400, 0.02, 7);
  std::vector<Tri> tris;
  for (std::size_t t = 0; t < scene->mesh.size(); ++t)
    tris.push_back({scene->mesh.vertex(t, 0), scene->mesh.vertex(t, 1), scene->mesh.vertex(t, 2)});
  std::size_t watertight_wrong = 0;
  for (const Ray& ray : rays) {
    ExactContactClassifier cls(ray);
    for (const Tri& t : tris) cls.offer_triangle(t.a, t.b, t.c);
    ASSERT_EQ(cls.contact(), Contact::touching);
    const int certified = first_hit<CertifiedKernel>(ray, tris);
    EXPECT_TRUE(exactly_first(ray, tris, certified)) << "certified kernel wrong on a touching ray";
    watertight_wrong += !exactly_first(ray, tris, first_hit<WatertightKernel>(ray, tris));
  }
  EXPECT_GT(watertight_wrong, 0u) << "no touching ray fooled the watertight kernel: the test shows nothing";
  std::cout << "[ touching ] watertight wrong on " << watertight_wrong << " of " << rays.size() << " rays, certified on 0\n";
}

// Two triangles cross the ray within a few float ulps of t of each other, tilted differently:
// the float t of each is rounded independently, and for some rays the float order is the wrong
// one. The certified kernel's t intervals overlap there, so it orders them exactly.
TEST(CertifiedKernel, OrdersHitsWhoseFloatOrderIsWrong) {
  const FloatModeScope ftz(true);
  Rng rng(11);
  std::size_t wrong_order = 0, cases = 0;
  for (int k = 0; k < 20000 && wrong_order < 20; ++k) {
    const Vec3d p(rng.uniform() * 100.0, rng.uniform() * 100.0, rng.uniform() * 100.0);
    auto tilted = [&](double tilt) {
      const Vec3d n = normalize(Vec3d(tilt, 0.3 * tilt, 1.0));
      const Vec3d u = normalize(cross(n, Vec3d(1, 0, 0))), v = cross(n, u);
      return Tri{Vec3f(p + u * 7.0), Vec3f(p - u * 3.0 + v * 6.0), Vec3f(p - u * 4.0 - v * 5.0)};
    };
    const std::vector<Tri> tris = {tilted(0.9 * rng.uniform()), tilted(-0.9 * rng.uniform())};
    const Vec3d w = normalize(Vec3d(0.3 * rng.uniform(), 0.3 * rng.uniform(), -1.0));
    const Vec3d target = p + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, 0.0) * 1e-3;
    const Ray ray{Vec3f(target - w * 50.0), Vec3f(w), 0.0f, INFINITY};
    const int watertight = first_hit<WatertightKernel>(ray, tris);
    if (watertight < 0) continue;
    ++cases;
    EXPECT_TRUE(exactly_first(ray, tris, first_hit<CertifiedKernel>(ray, tris))) << "ray " << k;
    wrong_order += !exactly_first(ray, tris, watertight);
  }
  EXPECT_GT(wrong_order, 0u) << "the float order was never wrong in " << cases << " cases: the test shows nothing";
  std::cout << "[ order ] watertight took the farther hit on " << wrong_order << " of " << cases << " rays\n";
}

/// Six triangles around a shared vertex (every other one sharing an edge as well) and four loose
/// ones, at `scale` and offset by up to `offset` units, with a ray aimed by `kind` at the shared
/// vertex exactly (0), at an edge's midpoint rounded (1) or at a random point: the configurations on
/// which float kernels fail. False when no float ray passes exactly through the vertex.
bool shared_feature_case(Rng& rng, double scale, double offset, int kind, std::vector<Tri>& tris, Ray& ray) {
  const Vec3d shift = Vec3d(rng.uniform(), rng.uniform(), rng.uniform()) * offset;
  auto point = [&] { return Vec3f((Vec3d(rng.uniform(), rng.uniform(), rng.uniform()) + shift) * scale); };
  const Vec3f shared0 = point(), shared1 = point();
  for (int t = 0; t < 6; ++t) tris.push_back({shared0, t % 2 ? shared1 : point(), point()});
  for (int t = 0; t < 4; ++t) tris.push_back({point(), point(), point()});
  const Tri& on = tris[rng.below(tris.size())];
  const Vec3f target = kind == 0 ? shared0 : kind == 1 ? Vec3f(Vec3d(on.a) * 0.5 + Vec3d(on.b) * 0.5) : point();
  const Vec3d w(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
  if (kind == 0) return ray_exactly_through(target, w, 3.0 * scale, ray);
  ray = Ray{Vec3f(Vec3d(target) - w * (3.0 * scale)), Vec3f(w * (3.0 * scale)), 0.0f, INFINITY};
  return true;
}

// Random triangles and rays, many aimed exactly at vertices and edges, in a tiny, a unit and a
// huge coordinate range, with FTZ/DAZ on: the certified kernel's first hit is always the exact one.
TEST(CertifiedKernel, AgreesWithTheExactFirstHitOnRandomAndFeatureAimedRays) {
  const FloatModeScope ftz(true);
  Rng rng(3);
  std::size_t rays = 0, exact_paths = 0;
  for (const double scale : {1e-30, 1e-6, 1.0, 1e6, 1e30}) {
    for (int k = 0; k < 400; ++k) {
      std::vector<Tri> tris;
      Ray ray;
      if (!shared_feature_case(rng, scale, k % 3 == 0 ? 1e3 : 1.0, k % 4, tris, ray)) continue;
      if (k % 5 == 0) ray.tmax = 1.0f;  // the hit at an interval end
      ++rays;
      auto ctx = CertifiedKernel::prepare(ray);
      int best = -1;
      TriangleHit h;
      for (std::size_t i = 0; i < tris.size(); ++i)
        if (CertifiedKernel::intersect(ctx, static_cast<unsigned>(i), tris[i].a, tris[i].b, tris[i].c, h))
          best = static_cast<int>(i);
      exact_paths += ctx.exact != nullptr;
      EXPECT_TRUE(exactly_first(ray, tris, best)) << "scale " << scale << ", ray " << k << " (kind " << k % 4 << ")";
    }
  }
  EXPECT_GT(exact_paths, 0u);
  EXPECT_LT(exact_paths, rays) << "the float filter certified nothing";
}

/// `tris` packed in order, kPacketWidth to a packet (unused lanes as pack_leaf leaves them).
std::vector<TrianglePacket> packed(const std::vector<Tri>& tris) {
  std::vector<TrianglePacket> out((tris.size() + kPacketWidth - 1) / kPacketWidth);
  for (auto& p : out)
    for (int l = 0; l < kPacketWidth; ++l) {
      p.prim[l] = kInvalidId;
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) p.v[k][a][l] = NAN;
    }
  for (std::size_t i = 0; i < tris.size(); ++i) {
    TrianglePacket& p = out[i / kPacketWidth];
    const int l = static_cast<int>(i % kPacketWidth);
    p.prim[l] = static_cast<std::uint32_t>(i);
    const Vec3f* v[3] = {&tris[i].a, &tris[i].b, &tris[i].c};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p.v[k][a][l] = (*v[k])[a];
  }
  return out;
}

// The packed test (two packets as one 8-lane test, then a 4-lane one), whose depth bounds reject
// and certify most lanes in float and which visits lanes nearest first: on the same random and
// feature-aimed configurations, near and far from the origin, the first hit is the exact one, and
// an any-hit query finds a hit exactly when there is one in [tmin, tmax].
TEST(CertifiedKernel, PackedLanesAgreeWithTheExactFirstHit) {
  const FloatModeScope ftz(true);
  Rng rng(5);
  std::size_t rays = 0, hits = 0;
  for (const double scale : {1e-30, 1e-4, 1.0, 1e4, 1e30}) {
    for (int k = 0; k < 300; ++k) {
      std::vector<Tri> tris;
      Ray ray;
      if (!shared_feature_case(rng, scale, k % 3 == 0 ? 1e4 : 1.0, k % 3, tris, ray)) continue;
      if (k % 4 == 0) ray.tmax = 1.0f;
      if (k % 7 == 0) ray.tmin = 0.5f;  // the origin half-way to the target: hits behind it are rejected
      ++rays;
      const std::vector<TrianglePacket> packets = packed(tris);
      auto ctx = CertifiedKernel::prepare(ray);
      const PacketKernel<CertifiedKernel>::Ray pr(ctx);
      TriangleHit h;
      int best = -1;
      const int lane8 = PacketKernel<CertifiedKernel>::intersect_lanes<false, 8>(ctx, pr, packets.data(), h);
      if (lane8 >= 0) best = lane8;
      const int lane4 = PacketKernel<CertifiedKernel>::intersect<false>(ctx, pr, packets[2], h);
      if (lane4 >= 0) best = 8 + lane4;
      if (best >= 0) {
        EXPECT_EQ(ctx.prim, static_cast<unsigned>(best));
      }
      hits += best >= 0;
      EXPECT_TRUE(exactly_first(ray, tris, best)) << "scale " << scale << ", ray " << k << " (kind " << k % 3 << ")";
      auto any = CertifiedKernel::prepare(ray);
      const bool blocked = PacketKernel<CertifiedKernel>::intersect_lanes<true, 8>(any, pr, packets.data(), h) >= 0 ||
                           PacketKernel<CertifiedKernel>::intersect<true>(any, pr, packets[2], h) >= 0;
      EXPECT_EQ(blocked, best >= 0) << "any-hit, scale " << scale << ", ray " << k;
    }
  }
  EXPECT_GT(hits, rays / 10);
}

// Rays that start on a large triangle (secondary rays: origin offset off the surface as the lab's
// ray generators do, Wächter and Binder 2019, or not offset, or exactly in an axis-aligned
// triangle's plane), leaving or entering it, grazing included, near the origin, 10^4 from it and
// at 10^-4: scalar and packed tests give the exact first hit, and the triangle the ray starts on
// is rejected (the ray leaves it) or hit (the ray enters it) without the double stage on most
// rays (CertifiedKernel::plane_crossing_t), where the float filter's enclosure of its t straddles 0.
TEST(CertifiedKernel, RaysStartingOnALargeTriangleGetTheExactFirstHit) {
  const FloatModeScope ftz(true);
  Rng rng(17);
  std::size_t leaving = 0, leaving_double_stage = 0, entering = 0, entering_double_stage = 0, hits = 0, rays = 0;
  for (const double scale : {1e-4, 1.0, 1e4}) {
    for (const double offset : {0.0, 1e4}) {
      for (int k = 0; k < 400; ++k) {
        const int kind = k % 4;  // 0 offset above, leaving; 1 offset below, entering; 2 on a z plane; 3 not offset
        const Vec3d shift = Vec3d(rng.uniform(), rng.uniform(), rng.uniform()) * (offset * scale);
        auto corner = [&] { return Vec3f(shift + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * (20.0 * scale)); };
        Tri big{corner(), corner(), corner()};
        if (kind == 2) big.b.z = big.c.z = big.a.z;
        const Vec3d n0 = cross(Vec3d(big.b) - Vec3d(big.a), Vec3d(big.c) - Vec3d(big.a));
        if (!(dot(n0, n0) > 0.0)) continue;
        const Vec3d n = normalize(n0);
        const double wa = rng.uniform(), wb = rng.uniform() * (1.0 - wa);
        const Vec3f on(Vec3d(big.a) * (1.0 - wa - wb) + Vec3d(big.b) * wa + Vec3d(big.c) * wb);
        // A direction into the side `side` of the plane, grazing on every fifth ray.
        const double side = kind == 1 ? -1.0 : (rng.uniform() < 0.5 ? 1.0 : -1.0);
        const Vec3d tangent = normalize(cross(n, Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5)));
        const double lift = k % 5 == 0 ? 1e-3 : 0.1 + rng.uniform();
        const Vec3d w = normalize(tangent + n * (side * lift));
        Vec3f org = on;
        if (kind == 0) org = offset_ray_origin(on, Vec3f(n * side), float(20.0 * scale));
        if (kind == 1) org = offset_ray_origin(on, Vec3f(n * -side), float(20.0 * scale));
        const Tri before{corner(), corner(), corner()}, after{corner(), corner(), corner()};
        const std::vector<Tri> tris = {before, big, after};
        const Ray ray{org, Vec3f(w), 0.0f, k % 3 == 0 ? float(5.0 * scale) : INFINITY};
        ++rays;
        interval_stage_taken_on_this_thread() = false;
        const int scalar = first_hit<CertifiedKernel>(ray, tris);
        if (kind == 0 && k % 5 != 0) {
          ++leaving;
          leaving_double_stage += interval_stage_taken_on_this_thread();
        }
        if (kind == 1 && k % 5 != 0) {
          ++entering;
          entering_double_stage += interval_stage_taken_on_this_thread();
        }
        EXPECT_TRUE(exactly_first(ray, tris, scalar)) << "scale " << scale << ", offset " << offset << ", ray " << k;
        hits += scalar >= 0;
        const std::vector<TrianglePacket> packets = packed(tris);
        auto ctx = CertifiedKernel::prepare(ray);
        TriangleHit h;
        const int lane = PacketKernel<CertifiedKernel>::intersect<false>(ctx, PacketKernel<CertifiedKernel>::Ray(ctx), packets[0], h);
        EXPECT_TRUE(exactly_first(ray, tris, lane)) << "packed, scale " << scale << ", offset " << offset << ", ray " << k;
      }
    }
  }
  EXPECT_GT(hits, rays / 4) << "the rays entering the triangle hit it";
  EXPECT_LT(leaving_double_stage, leaving / 10) << "the triangle a ray leaves needed the double stage";
  EXPECT_LT(entering_double_stage, entering / 10) << "the triangle a ray enters needed the double stage";
  std::cout << "[ start on a triangle ] " << rays << " rays, " << hits << " hits; double stage on " << leaving_double_stage
            << " of " << leaving << " leaving and " << entering_double_stage << " of " << entering << " entering rays\n";
}

// Any-hit (occlusion) queries whose segment ends at the occluder: a segment aimed at a point of
// a triangle, with tmax the float at, just before or just after the crossing (and tmin likewise
// from the other side), must be blocked by the packed test exactly when the scalar certified
// kernel finds a hit, near the origin, 10^4 from it and at 10^-4, for 4- and 8-lane tests.
TEST(CertifiedKernel, PackedAnyHitAtTheSegmentEndsAgreesWithTheScalarKernel) {
  const FloatModeScope ftz(true);
  Rng rng(29);
  std::size_t rays = 0, blocked_rays = 0, open_rays = 0;
  for (const double scale : {1e-4, 1.0, 1e4}) {
    for (const double offset : {0.0, 1e4}) {
      for (int k = 0; k < 300; ++k) {
        const Vec3d shift = Vec3d(rng.uniform(), rng.uniform(), rng.uniform()) * (offset * scale);
        auto point = [&] { return Vec3f(shift + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * (4.0 * scale)); };
        std::vector<Tri> tris;
        for (int i = 0; i < 8; ++i) tris.push_back({point(), point(), point()});
        const Tri& target = tris[k % 8];
        const double wa = 0.05 + 0.9 * rng.uniform(), wb = (1.0 - wa) * (0.05 + 0.9 * rng.uniform());
        const Vec3f aim(Vec3d(target.a) * (1.0 - wa - wb) + Vec3d(target.b) * wa + Vec3d(target.c) * wb);
        const Vec3f org = point() + Vec3f(0.0f, 0.0f, float(8.0 * scale));
        const std::vector<TrianglePacket> packets = packed(tris);
        for (const float end : {std::nextafter(1.0f, 0.0f), 1.0f, std::nextafter(1.0f, 2.0f), 0.5f}) {
          for (const bool at_tmin : {false, true}) {
            // At tmin the segment runs back from the aim point: the crossing is its start.
            const Ray ray = at_tmin ? Ray{org, aim - org, end, 4.0f} : Ray{org, aim - org, 0.0f, end};
            ++rays;
            const bool expected = first_hit<CertifiedKernel>(ray, tris) >= 0;
            auto ctx8 = CertifiedKernel::prepare(ray);
            const PacketKernel<CertifiedKernel>::Ray pr(ctx8);
            TriangleHit h;
            const bool blocked8 = PacketKernel<CertifiedKernel>::intersect_lanes<true, 8>(ctx8, pr, packets.data(), h) >= 0;
            auto ctx4 = CertifiedKernel::prepare(ray);
            const bool blocked4 = PacketKernel<CertifiedKernel>::intersect<true>(ctx4, pr, packets[0], h) >= 0 ||
                                  PacketKernel<CertifiedKernel>::intersect<true>(ctx4, pr, packets[1], h) >= 0;
            EXPECT_EQ(blocked8, expected) << "8 lanes, scale " << scale << ", offset " << offset << ", ray " << k
                                          << ", end " << end << (at_tmin ? " (tmin)" : " (tmax)");
            EXPECT_EQ(blocked4, expected) << "4 lanes, scale " << scale << ", offset " << offset << ", ray " << k
                                          << ", end " << end << (at_tmin ? " (tmin)" : " (tmax)");
            blocked_rays += expected;
            open_rays += !expected;
          }
        }
      }
    }
  }
  EXPECT_GT(blocked_rays, rays / 4);
  EXPECT_GT(open_rays, rays / 20);
}

// The stage counters: a ray whose float filter decides everything reaches neither the double
// stage nor the exact path; a ray exactly through a vertex reaches both.
TEST(CertifiedKernel, CountsRaysThatReachedTheDoubleStage) {
  const auto scene = make_scene("sphere:n=2000");
  const auto accel = make_accelerator("bvh:kernel=certified", scene);
  const std::vector<Ray> vertex_rays = make_ray_set("touching:64", scene), primary = make_ray_set("primary:1024", scene);
  const RayCounters v = trace_rays(*accel, vertex_rays, TraceOptions{1, true, false}).counters;
  EXPECT_EQ(v.interval_stage, vertex_rays.size());
  const RayCounters p = trace_rays(*accel, primary, TraceOptions{1, true, false}).counters;
  EXPECT_LT(p.interval_stage, primary.size() / 20) << "primary rays mostly certify in float alone";
  EXPECT_LE(p.exact_fallbacks, p.interval_stage);
}

// Spheres: a ray tangent to a sphere touches it (decided exactly), and the roots of two spheres
// are ordered exactly against each other and against triangles.
TEST(CertifiedKernel, DecidesTangentSpheresAndOrdersRootsExactly) {
  const FloatModeScope ftz(true);
  const Sphere s{{0, 0, 0}, 1.0f};
  const Ray tangent{{1.0f, 0.0f, -5.0f}, {0, 0, 1}};  // touches (1, 0, 0)
  auto ctx = CertifiedKernel::prepare(tangent);
  TriangleHit h;
  ASSERT_TRUE(CertifiedKernel::intersect_sphere(ctx, 0, s, h));
  EXPECT_FLOAT_EQ(h.t, 5.0f);
  EXPECT_NE(ctx.exact, nullptr) << "a tangent ray cannot be certified in float";
  const Ray outside{{std::nextafter(1.0f, 2.0f), 0.0f, -5.0f}, {0, 0, 1}};
  auto ctx2 = CertifiedKernel::prepare(outside);
  EXPECT_FALSE(CertifiedKernel::intersect_sphere(ctx2, 0, s, h));
  // A triangle in the plane z = -1 (the sphere's first root along the axis is also z = -1).
  const Ray axis{{0.0f, 0.0f, -5.0f}, {0, 0, 1}};
  auto ctx3 = CertifiedKernel::prepare(axis);
  EXPECT_TRUE(CertifiedKernel::intersect_sphere(ctx3, 1, s, h));
  CertifiedKernel::intersect(ctx3, 2, {-1, -1, -1}, {2, -1, -1}, {-1, 2, -1}, h);  // a tie at t = 4
  EXPECT_TRUE(ctx3.prim == 1 || ctx3.prim == 2);
  EXPECT_FLOAT_EQ(ctx3.best.t, 4.0f);
  EXPECT_TRUE(CertifiedKernel::intersect_sphere(ctx3, 3, {{0, 0, -1.5f}, 0.25f}, h));  // first root at z = -1.75
  EXPECT_EQ(ctx3.prim, 3u);
}

// The counter: a ray that needed the exact path is counted once, however many exact decisions
// it made; a ray the float filter decided is not counted.
TEST(CertifiedKernel, CountsRaysThatTookTheExactPathOnce) {
  const auto scene = make_scene("sphere:n=2000");
  const auto accel = make_accelerator("bvh:kernel=certified", scene);
  // Touching rays pass exactly through a vertex: no float or double enclosure decides them.
  const std::vector<Ray> vertex_rays = make_ray_set("touching:64", scene), primary = make_ray_set("primary:1024", scene);
  const TraceResult v = trace_rays(*accel, vertex_rays, TraceOptions{1, true, false});
  EXPECT_EQ(v.counters.exact_fallbacks, vertex_rays.size()) << "every ray exactly through a vertex needs the exact path";
  const TraceResult p = trace_rays(*accel, primary, TraceOptions{1, true, false});
  EXPECT_LT(p.counters.exact_fallbacks, primary.size() / 50) << "primary rays mostly certify in float";
  const auto watertight = make_accelerator("bvh:kernel=watertight", scene);
  EXPECT_EQ(trace_rays(*watertight, vertex_rays, TraceOptions{1, true, false}).counters.exact_fallbacks, 0u);
}

// Invalid configurations of the certified kernel are input errors (one line, exit 2 in the tool).
TEST(CertifiedKernel, RequiresConservativeTraversal) {
  const auto scene = make_scene("sphere:n=64");
  EXPECT_THROW(make_accelerator("bvh:kernel=certified,robust=off", scene), InputError);
  EXPECT_THROW(make_accelerator("grid:kernel=certified,accept=first", scene), InputError);
  EXPECT_THROW(make_accelerator("kdtree:kernel=exact", scene), InputError);
  EXPECT_NO_THROW(make_accelerator("brute:kernel=certified", scene));
}

}  // namespace
}  // namespace raylab
