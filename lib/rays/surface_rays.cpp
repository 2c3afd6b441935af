#include "rays/surface_rays.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "rays/offset_ray.h"
#include "rays/random.h"
#include "rays/sampling.h"

namespace raylab {
namespace {

/// Point and (unnormalised, unoriented) normal of a hit in the space of the scene that holds
/// the primitive.
void local_surface(const Scene& s, const Ray& local_ray, const Hit& hit, Vec3d& p, Vec3d& n) {
  if (hit.prim >= s.primitive_count()) throw std::logic_error("surface_at: hit names a primitive the scene lacks");
  if (!s.is_sphere(hit.prim)) {
    const Vec3d p0(s.mesh.vertex(hit.prim, 0)), p1(s.mesh.vertex(hit.prim, 1)), p2(s.mesh.vertex(hit.prim, 2));
    const Vec3d e1 = p1 - p0, e2 = p2 - p0;
    p = p0 + e1 * static_cast<double>(hit.u) + e2 * static_cast<double>(hit.v);
    n = cross(e1, e2);
  } else {
    const Sphere& sp = s.sphere(hit.prim);
    const Vec3d c(sp.center);
    const Vec3d q = Vec3d(local_ray.org) + Vec3d(local_ray.dir) * static_cast<double>(hit.t);
    n = q - c;
    const double len = length(n);
    p = len > 0.0 ? c + n * (static_cast<double>(sp.radius) / len) : q;
  }
}

}  // namespace

SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit) {
  Vec3d p, n;
  if (hit.instance != kInvalidId) {
    if (hit.instance >= scene.instances.size())
      throw std::logic_error("surface_at: hit names an instance the scene lacks");
    const AffineTransform& xf = scene.instances[hit.instance].transform;
    const AffineTransform inv = xf.inverse();
    local_surface(scene.base_of(hit.instance), inv.apply(ray), hit, p, n);
    p = xf.apply_point(p);
    // Normals map by the inverse transpose of the linear part.
    n = Vec3d(inv.m[0][0] * n.x + inv.m[1][0] * n.y + inv.m[2][0] * n.z,
              inv.m[0][1] * n.x + inv.m[1][1] * n.y + inv.m[2][1] * n.z,
              inv.m[0][2] * n.x + inv.m[1][2] * n.y + inv.m[2][2] * n.z);
  } else {
    local_surface(scene, ray, hit, p, n);
  }
  const double len = length(n);
  n = len > 0.0 && std::isfinite(len) ? n / len : -normalize(Vec3d(ray.dir));
  if (dot(n, Vec3d(ray.dir)) > 0.0) n = -n;
  return {Vec3f(p), Vec3f(n)};
}

std::vector<SurfacePoint> visible_points(const Scene& scene, const Camera& camera, std::size_t n,
                                         const FirstHitFunction& trace) {
  std::vector<SurfacePoint> points;
  if (n == 0) return points;
  const double budget = std::max(16.0 * static_cast<double>(n), 65536.0);
  auto side = static_cast<std::size_t>(std::ceil(std::sqrt(2.0 * static_cast<double>(n))));
  for (;;) {
    points.clear();
    const int w = static_cast<int>(side);
    for (int j = 0; j < w; ++j)
      for (int i = 0; i < w; ++i) {
        const Ray ray = camera_ray(camera, i + 0.5, j + 0.5, w, w);
        const Hit hit = trace(ray);
        if (hit.valid()) points.push_back(surface_at(scene, ray, hit));
      }
    if (points.size() >= n || 4.0 * static_cast<double>(side) * static_cast<double>(side) > budget) break;
    side *= 2;
  }
  const std::size_t h = points.size();
  if (h == 0) return points;
  std::vector<SurfacePoint> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    out.push_back(h >= n ? points[static_cast<std::size_t>((static_cast<unsigned __int128>(i) * h) / n)] : points[i % h]);
  return out;
}

Vec3d light_point(const Bounds3f& scene_bounds, double u1, double u2) {
  const Bounds3d b(Vec3d(scene_bounds.lo), Vec3d(scene_bounds.hi));
  const double diag = length(b.diagonal());
  const Vec3d c = b.center();
  return {c.x + (u1 - 0.5) * 0.5 * diag, b.hi.y + 0.5 * diag, c.z + (u2 - 0.5) * 0.5 * diag};
}

std::vector<Ray> surface_rays(SurfaceRayKind kind, const Scene& scene, const Camera& camera, std::size_t n,
                              std::uint64_t seed, const FirstHitFunction& trace) {
  const std::vector<SurfacePoint> points = visible_points(scene, camera, n, trace);
  std::vector<Ray> rays;
  if (points.empty()) return rays;
  rays.reserve(n);
  const Bounds3f bounds = scene.bounds();
  const double diagonal = length(Vec3d(bounds.diagonal()));
  const float ao_tmax = static_cast<float>(0.1 * diagonal);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Rng rng(seed);
  for (const SurfacePoint& sp : points) {
    const Vec3f org = offset_ray_origin(sp.p, sp.n, static_cast<float>(diagonal));
    const double u1 = rng.uniform(), u2 = rng.uniform();
    switch (kind) {
      case SurfaceRayKind::diffuse:
      case SurfaceRayKind::ambient_occlusion: {
        Vec3f d(Frame(Vec3d(sp.n)).to_world(sample_cosine_hemisphere(u1, u2)));
        if (d == Vec3f(0.0f)) d = sp.n;
        rays.push_back(Ray{org, d, 0.0f, kind == SurfaceRayKind::diffuse ? kInf : ao_tmax});
        break;
      }
      case SurfaceRayKind::shadow: {
        Vec3f d(light_point(bounds, u1, u2) - Vec3d(org));
        if (d == Vec3f(0.0f)) d = sp.n;
        rays.push_back(Ray{org, d, 0.0f, kShadowTmax});
        break;
      }
    }
  }
  return rays;
}

}  // namespace raylab
