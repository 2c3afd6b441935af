#include "accel/exact/ray_conditioning.h"

#include <algorithm>
#include <cmath>

#include "rays/feature_rays.h"

namespace raylab {
namespace {

constexpr double kU = 0x1p-24;  ///< float unit roundoff

/// The watertight kernel's sheared projection along d, in double: a point q maps to 2D
/// coordinates relative to the ray (which maps to the origin) and to its parameter along the ray.
struct Projection {
  int kx, ky, kz;
  double sx, sy, inv_dz;
  Vec3d o;
  explicit Projection(const Ray& r) : o(r.org) {
    kz = max_abs_axis(r.dir);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    sx = double(r.dir[kx]) / r.dir[kz];
    sy = double(r.dir[ky]) / r.dir[kz];
    inv_dz = 1.0 / r.dir[kz];
  }
  struct P {
    double x, y, t, z;  ///< 2D coordinates, parameter, |q - o| along the dominant axis
  };
  P map(const Vec3f& q) const {
    const Vec3d a = Vec3d(q) - o;
    return {a[kx] - sx * a[kz], a[ky] - sy * a[kz], a[kz] * inv_dz, std::abs(a[kz])};
  }
};

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

/// The certified kernel's edge-function bound (certified_kernel.h) in double, for the triangle
/// whose projected vertices are `p`: the scale below which float decides a side by rounding.
double edge_scale(const Projection::P p[3]) {
  double S = 0.0, Z = 0.0;
  for (int i = 0; i < 3; ++i) {
    S = std::max(S, std::abs(p[i].x) + std::abs(p[i].y));
    Z = std::max(Z, p[i].z);
  }
  return kU * S * (14.0 * S + 32.0 * Z) + 0x1p-38 * Z * Z;
}

/// Whether the projected triangles around welded vertex `w` (projected position `at`) cover a
/// neighbourhood of it with a margin: their corner sectors at `at` cover every direction.
bool fan_covers(const Scene& scene, const MeshAdjacency& adj, const Projection& proj, std::uint32_t w) {
  struct Sector {
    double sx, sy, ex, ey;
  };
  std::vector<Sector> sectors;
  const auto& mesh = scene.mesh;
  for (const std::uint32_t tri : adj.around_vertex(w)) {
    int at = 0;
    while (at < 3 && adj.weld(mesh.triangles[tri][at]) != w) ++at;
    if (at == 3) continue;
    const Projection::P a = proj.map(mesh.vertex(tri, at)), b = proj.map(mesh.vertex(tri, (at + 1) % 3)),
                        c = proj.map(mesh.vertex(tri, (at + 2) % 3));
    const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
    const double area = cross2(bx, by, cx, cy), scale = (std::abs(bx) + std::abs(by)) * (std::abs(cx) + std::abs(cy));
    if (!(std::abs(area) > 1e-9 * scale)) return false;  // a face seen edge-on: the ray grazes it
    sectors.push_back(area > 0 ? Sector{bx, by, cx, cy} : Sector{cx, cy, bx, by});
  }
  if (sectors.empty()) return false;
  auto inside = [&](double vx, double vy) {
    for (const Sector& s : sectors)
      if (cross2(s.sx, s.sy, vx, vy) > 0.0 && cross2(vx, vy, s.ex, s.ey) > 0.0) return true;
    return false;
  };
  constexpr double kTurn = 1e-6;  // radians: just either side of each sector boundary
  const double c = std::cos(kTurn), s = std::sin(kTurn);
  for (const Sector& q : sectors)
    for (const auto& [vx, vy] : {std::pair{q.sx, q.sy}, std::pair{q.ex, q.ey}})
      if (!inside(vx * c - vy * s, vx * s + vy * c) || !inside(vx * c + vy * s, -vx * s + vy * c)) return false;
  return true;
}

/// Whether welded edge {a, b} is an edge through which the surface continues across the ray's
/// projection: exactly two triangles, whose third vertices project strictly to opposite sides.
bool edge_passes_through(const Scene& scene, const MeshAdjacency& adj, const Projection& proj, std::uint32_t wa,
                         std::uint32_t wb, const Projection::P& pa, const Projection::P& pb, double scale) {
  const auto& tris = adj.around_edge(wa, wb);
  if (tris.size() != 2) return false;
  int sides = 0;
  for (const std::uint32_t tri : tris) {
    int k = 0;
    while (k < 3 && (adj.weld(scene.mesh.triangles[tri][k]) == wa || adj.weld(scene.mesh.triangles[tri][k]) == wb)) ++k;
    if (k == 3) return false;
    const Projection::P c = proj.map(scene.mesh.vertex(tri, k));
    const double side = cross2(pb.x - pa.x, pb.y - pa.y, c.x - pa.x, c.y - pa.y);
    if (!(std::abs(side) > 4.0 * scale)) return false;  // edge-on
    sides += side > 0 ? 1 : -1;
  }
  return sides == 0;
}

/// Distance from point p to triangle (a, b, c), in double (Ericson, Real-Time Collision
/// Detection, 5.1.5).
double point_triangle_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return length(p - a);
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return length(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return length(p - (a + ab * (d1 / (d1 - d3))));
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return length(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return length(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const double denom = 1.0 / (va + vb + vc);
  return length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

}  // namespace

MeshAdjacency::MeshAdjacency(const TriangleMesh& mesh) : weld_(weld_vertices(mesh)) {
  for (std::uint32_t t = 0; t < mesh.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = weld_[mesh.triangles[t][c]], b = weld_[mesh.triangles[t][(c + 1) % 3]];
      auto& around = vertex_tris_[a];
      if (around.empty() || around.back() != t) around.push_back(t);
      if (a != b) edge_tris_[std::uint64_t(std::min(a, b)) << 32 | std::max(a, b)].push_back(t);
    }
}

const std::vector<std::uint32_t>& MeshAdjacency::around_vertex(std::uint32_t w) const {
  const auto it = vertex_tris_.find(w);
  return it == vertex_tris_.end() ? none_ : it->second;
}

const std::vector<std::uint32_t>& MeshAdjacency::around_edge(std::uint32_t a, std::uint32_t b) const {
  const auto it = edge_tris_.find(std::uint64_t(std::min(a, b)) << 32 | std::max(a, b));
  return it == edge_tris_.end() ? none_ : it->second;
}

double ulp_displacement(const Ray& ray, double t) {
  return 32.0 * kU * (max_component(abs(Vec3d(ray.org))) + std::abs(t) * max_component(abs(Vec3d(ray.dir))));
}

bool near_contour_or_surface(const Scene& scene, const MeshAdjacency& adj, const Ray& ray, double t_end,
                             const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& spheres) {
  const Projection proj(ray);
  const double tmin = ray.tmin;
  const Vec3d o(ray.org), d(ray.dir);
  const Vec3d start = o + d * tmin;
  const double dlen = length(d);
  // The 2D radius: Δ(t), doubled for the shear (|sx|, |sy| <= 1) and doubled as a margin.
  auto radius = [&](double t) { return 4.0 * ulp_displacement(ray, t); };
  const double t_slack = 1e-6 * (std::abs(t_end) + std::abs(tmin)) + radius(t_end) / dlen;
  const auto& mesh = scene.mesh;
  for (const std::uint32_t tri : triangles) {
    const Projection::P p[3] = {proj.map(mesh.vertex(tri, 0)), proj.map(mesh.vertex(tri, 1)), proj.map(mesh.vertex(tri, 2))};
    // (c) the start lies within Δ(tmin) (or the float scale of the triangle) of its surface.
    const Vec3d a(mesh.vertex(tri, 0)), b(mesh.vertex(tri, 1)), c(mesh.vertex(tri, 2));
    const double far = std::max({length(a - start), length(b - start), length(c - start)});
    if (point_triangle_distance(start, a, b, c) <= 2.0 * ulp_displacement(ray, tmin) + 64.0 * kU * far) return true;
    const double tlo = std::min({p[0].t, p[1].t, p[2].t}), thi = std::max({p[0].t, p[1].t, p[2].t});
    if (tlo > t_end + t_slack || thi < tmin - t_slack) continue;
    const double scale = edge_scale(p);
    const double area = cross2(p[1].x - p[0].x, p[1].y - p[0].y, p[2].x - p[0].x, p[2].y - p[0].y);
    // Where the line meets the triangle's plane (barycentrics of the ray's projection, the
    // origin): only a triangle met within [tmin, t_end] (up to the slack) can change the answer.
    const double w0 = cross2(p[1].x, p[1].y, p[2].x, p[2].y), w1 = cross2(p[2].x, p[2].y, p[0].x, p[0].y),
                 w2 = cross2(p[0].x, p[0].y, p[1].x, p[1].y);
    const bool edge_on = !(std::abs(area) > 4.0 * scale);
    if (!edge_on) {
      const double t_plane = (w0 * p[0].t + w1 * p[1].t + w2 * p[2].t) / area;
      if (t_plane > t_end + t_slack || t_plane < tmin - t_slack) continue;
    }
    for (int i = 0; i < 3; ++i) {
      const Projection::P& P = p[i];
      const Projection::P& Q = p[(i + 1) % 3];
      const double ex = Q.x - P.x, ey = Q.y - P.y, len2 = ex * ex + ey * ey;
      const double lambda = len2 > 0.0 ? std::clamp(-(P.x * ex + P.y * ey) / len2, 0.0, 1.0) : 0.0;
      const double cx = P.x + lambda * ex, cy = P.y + lambda * ey, t = P.t + lambda * (Q.t - P.t);
      const double dist = std::hypot(cx, cy), side = cross2(ex, ey, -P.x, -P.y);
      const bool near = dist <= radius(std::max(t, tmin)) || (std::abs(side) <= 4.0 * scale && lambda > 0.0 && lambda < 1.0);
      if (!near) continue;
      // (b) near an edge: a contour unless the surface continues across it ...
      const std::uint32_t wa = adj.weld(mesh.triangles[tri][i]), wb = adj.weld(mesh.triangles[tri][(i + 1) % 3]);
      if (edge_on || !edge_passes_through(scene, adj, proj, wa, wb, P, Q, scale)) return true;
      // ... and near a vertex: a contour unless its fan covers the neighbourhood.
      const double reach = 4.0 * scale / std::sqrt(std::max(len2, 1e-300));
      if (std::hypot(P.x, P.y) <= radius(P.t) + reach && !fan_covers(scene, adj, proj, wa)) return true;
      if (std::hypot(Q.x, Q.y) <= radius(Q.t) + reach && !fan_covers(scene, adj, proj, wb)) return true;
    }
  }
  for (const std::uint32_t prim : spheres) {
    const Sphere& s = scene.sphere(prim);
    const Vec3d c(s.center);
    const double r = s.radius;
    const double err = 64.0 * kU * (r + max_component(abs(c)));
    if (std::abs(length(start - c) - r) <= 2.0 * ulp_displacement(ray, tmin) + err) return true;  // (c)
    const double tc = dot(c - o, d) / (dlen * dlen);  // closest approach of the line
    const double h = length(o + d * tc - c);
    if (tc >= tmin - t_slack && tc <= t_end + t_slack && std::abs(h - r) <= radius(tc) + err) return true;  // grazing
  }
  return false;
}

}  // namespace raylab
