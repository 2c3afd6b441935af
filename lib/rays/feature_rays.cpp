#include "rays/feature_rays.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

#include "geometry/exact_contact.h"
#include "geometry/input_error.h"
#include "geometry/triangle_mesh.h"
#include "rays/random.h"
#include "rays/sampling.h"

namespace raylab {
namespace {

Vec3d face_cross(const TriangleMesh& mesh, std::uint32_t tri) {
  const Vec3d p0(mesh.vertex(tri, 0)), p1(mesh.vertex(tri, 1)), p2(mesh.vertex(tri, 2));
  return cross(p1 - p0, p2 - p0);
}

struct Incidence {
  std::uint64_t feature;  ///< welded vertex, or (lo << 32 | hi) of an edge's welded vertices
  std::uint32_t tri;
  bool operator<(const Incidence& o) const { return feature != o.feature ? feature < o.feature : tri < o.tri; }
};

}  // namespace

std::vector<std::uint32_t> weld_vertices(const TriangleMesh& mesh) {
  std::vector<std::uint32_t> order(mesh.vertices.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto key = [&](std::uint32_t i) {
    const Vec3f& v = mesh.vertices[i];
    return std::make_tuple(v.x, v.y, v.z, i);
  };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  std::vector<std::uint32_t> weld(mesh.vertices.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool same = k > 0 && mesh.vertices[order[k]] == mesh.vertices[order[k - 1]];
    weld[order[k]] = same ? weld[order[k - 1]] : order[k];
  }
  return weld;
}

std::vector<Ray> feature_rays(const TriangleMesh& mesh, MeshFeature feature, std::size_t n, double distance,
                              std::uint64_t seed) {
  const std::vector<std::uint32_t> weld = weld_vertices(mesh);
  std::vector<Incidence> inc;
  inc.reserve(3 * mesh.size());
  // Welded vertices of zero-area triangles (decided exactly). No kernel hits such a triangle, so
  // the surface has a crack along it: features touching one are not sampled (see below).
  std::vector<bool> touches_degenerate(mesh.vertices.size(), false);
  for (std::uint32_t t = 0; t < mesh.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (is_degenerate_exact(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]))
      for (int c = 0; c < 3; ++c) touches_degenerate[weld[tri[c]]] = true;
  }
  for (std::uint32_t t = 0; t < mesh.size(); ++t) {
    if (face_cross(mesh, t) == Vec3d(0.0)) continue;
    const auto& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) {
      const std::uint64_t a = weld[tri[c]], b = weld[tri[(c + 1) % 3]];
      inc.push_back({feature == MeshFeature::vertex ? a : (std::min(a, b) << 32 | std::max(a, b)), t});
    }
  }
  if (inc.empty()) throw InputError("feature rays: the mesh has no non-degenerate triangle");
  std::sort(inc.begin(), inc.end());
  // Group starts: features are inc[starts[f] .. starts[f+1]).
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < inc.size(); ++i)
    if (i == 0 || inc[i].feature != inc[i - 1].feature) starts.push_back(i);
  starts.push_back(inc.size());
  const std::size_t features = starts.size() - 1;

  // Per feature: the mean normal and the cone half-angle. A feature where some adjacent face
  // is 80° or more from the mean normal (a fold, or a fin whose faces point apart) has no
  // direction that crosses every adjacent face from the front with a margin: it is seen in
  // silhouette from every side, so it is not sampled while any other feature is eligible.
  const double max_cone = 30.0 * std::numbers::pi / 180.0;
  const double max_theta = 80.0 * std::numbers::pi / 180.0;
  std::vector<Vec3d> normals(features);
  std::vector<double> cones(features);
  std::vector<std::size_t> eligible;
  for (std::size_t f = 0; f < features; ++f) {
    Vec3d normal(0.0);
    for (std::size_t i = starts[f]; i < starts[f + 1]; ++i) normal += face_cross(mesh, inc[i].tri);
    if (!(length(normal) > 0.0)) normal = face_cross(mesh, inc[starts[f]].tri);
    normal = normalize(normal);
    double min_cos = 1.0;
    for (std::size_t i = starts[f]; i < starts[f + 1]; ++i)
      min_cos = std::min(min_cos, dot(normal, normalize(face_cross(mesh, inc[i].tri))));
    const double theta = std::acos(std::clamp(min_cos, -1.0, 1.0));
    normals[f] = normal;
    cones[f] = std::clamp(0.5 * (0.5 * std::numbers::pi - theta), 0.0, max_cone);
    const std::uint64_t key = inc[starts[f]].feature;
    const bool cracked = feature == MeshFeature::vertex
                             ? touches_degenerate[key]
                             : (touches_degenerate[key >> 32] || touches_degenerate[key & 0xffffffffu]);
    if (theta <= max_theta && !cracked) eligible.push_back(f);
  }
  if (eligible.empty())
    for (std::size_t f = 0; f < features; ++f) eligible.push_back(f);

  Rng rng(seed);
  std::vector<Ray> rays;
  rays.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t f = eligible[rng.below(eligible.size())];
    const std::uint64_t key = inc[starts[f]].feature;
    Vec3d p;
    if (feature == MeshFeature::vertex) {
      p = Vec3d(mesh.vertices[key]);
    } else {
      const Vec3d a(mesh.vertices[key >> 32]), b(mesh.vertices[key & 0xffffffffu]);
      p = Vec3d(Vec3f(a + (b - a) * rng.uniform_open()));
    }
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const Vec3d w = Frame(-normals[f]).to_world(sample_uniform_cone(u1, u2, std::cos(cones[f])));
    const Vec3f org(p - w * distance);
    Vec3f dir(p - Vec3d(org));
    if (dir == Vec3f(0.0f)) dir = Vec3f(w);
    rays.push_back(Ray{org, dir, 0.0f, std::numeric_limits<float>::infinity()});
  }
  return rays;
}

}  // namespace raylab

namespace raylab {
namespace {

/// x rounded to `bits` significant bits (round to nearest).
double round_to_bits(double x, int bits) {
  if (x == 0.0 || !std::isfinite(x)) return x;
  const int e = std::ilogb(x);
  return std::ldexp(std::nearbyint(std::ldexp(x, bits - 1 - e)), e - (bits - 1));
}

/// The non-degenerate triangles around each welded vertex and each welded edge.
struct Adjacency {
  std::vector<std::uint32_t> weld;
  std::vector<std::vector<std::uint32_t>> fan;  ///< by welded vertex id
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;  ///< (edge key, triangle), sorted
  explicit Adjacency(const TriangleMesh& mesh) : weld(weld_vertices(mesh)), fan(mesh.vertices.size()) {
    for (std::uint32_t t = 0; t < mesh.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      if (is_degenerate_exact(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]])) continue;
      for (int c = 0; c < 3; ++c) {
        const std::uint64_t a = weld[tri[c]], b = weld[tri[(c + 1) % 3]];
        fan[a].push_back(t);
        edges.emplace_back(std::min(a, b) << 32 | std::max(a, b), t);
      }
    }
    std::sort(edges.begin(), edges.end());
  }
};

Vec3d unit_normal(const TriangleMesh& mesh, std::uint32_t tri) { return normalize(face_cross(mesh, tri)); }

}  // namespace

bool ray_exactly_through(const Vec3f& p, const Vec3d& w, double distance, Ray& out) {
  const double wmax = max_component(abs(w));
  if (!(wmax > 0.0) || !std::isfinite(wmax)) return false;
  Vec3f d;
  for (int a = 0; a < 3; ++a) d[a] = std::abs(w[a]) < 0x1p-8 * wmax ? 0.0f : static_cast<float>(round_to_bits(w[a], 8));
  const double dmax = max_component(abs(Vec3d(d)));
  const int k0 = static_cast<int>(std::ceil(std::log2(std::max(distance, 1e-30) / dmax)));
  for (int k = k0; k <= k0 + 40; ++k) {
    Vec3f o;
    bool exact = true;
    for (int a = 0; a < 3 && exact; ++a) {
      const double od = double(p[a]) - std::ldexp(double(d[a]), k);  // exact in double: 24- and 8-bit operands
      o[a] = static_cast<float>(od);
      exact = std::isfinite(o[a]) && double(o[a]) == od;
    }
    if (!exact) continue;
    out = Ray{o, d, 0.0f, std::numeric_limits<float>::infinity()};
    return true;
  }
  return false;
}

std::vector<Ray> touching_vertex_rays(const TriangleMesh& mesh, std::size_t n, double distance, std::uint64_t seed) {
  const Adjacency adj(mesh);
  // Vertices with a fan of three or more triangles that is not flat, with the fan's mean normal
  // and spread (the largest angle between the mean normal and a face normal).
  std::vector<std::uint32_t> vertices;
  std::vector<Vec3d> normals;
  std::vector<double> spreads;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (adj.weld[v] != v || adj.fan[v].size() < 3) continue;
    Vec3d normal(0.0);
    for (const std::uint32_t t : adj.fan[v]) normal += face_cross(mesh, t);
    if (!(length(normal) > 0.0)) continue;
    normal = normalize(normal);
    double spread = 0.0;
    for (const std::uint32_t t : adj.fan[v])
      spread = std::max(spread, std::acos(std::clamp(dot(normal, unit_normal(mesh, t)), -1.0, 1.0)));
    if (spread < 1e-3) continue;  // a flat fan has no touching direction off its plane
    vertices.push_back(v);
    normals.push_back(normal);
    spreads.push_back(spread);
  }
  if (vertices.empty()) throw InputError("touching rays: the mesh has no vertex with a fan that is not flat");
  Rng rng(seed);
  std::vector<Ray> rays;
  rays.reserve(n);
  for (std::size_t picks = 0; rays.size() < n && picks < 4 * n + 64; ++picks) {
    const std::size_t pick = rng.below(vertices.size());
    const std::uint32_t v = vertices[pick];
    const double spread = spreads[pick];
    // The tilt out of the tangent plane is drawn within the fan's spread: directions there see
    // some faces from the front and some from behind, which a touching line must.
    const Frame frame(normals[pick]);
    for (int tries = 0; tries < 64; ++tries) {
      const double phi = 2.0 * std::numbers::pi * rng.uniform(), alpha = std::tan(spread * (2.0 * rng.uniform() - 1.0));
      const Vec3d w = frame.to_world({std::cos(phi), std::sin(phi), alpha});
      int front = 0, back = 0;
      for (const std::uint32_t t : adj.fan[v]) (dot(w, face_cross(mesh, t)) > 0.0 ? front : back)++;
      if (front == 0 || back == 0) continue;  // every face on one side: the line crosses the fan
      Ray ray;
      if (!ray_exactly_through(mesh.vertices[v], w, distance, ray)) continue;
      ExactContactClassifier fan(ray);
      for (const std::uint32_t t : adj.fan[v]) fan.offer_triangle(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2));
      // First met at v (t = |p - o| / |d| exactly reached at the vertex), and touching there.
      const double t_v = length(Vec3d(mesh.vertices[v]) - Vec3d(ray.org)) / length(Vec3d(ray.dir));
      if (fan.contact() != Contact::touching || std::abs(fan.first_t() - t_v) > 1e-9 * t_v) continue;
      rays.push_back(ray);
      break;
    }
  }
  if (rays.size() < n)
    throw InputError("touching rays: found " + std::to_string(rays.size()) + " of " + std::to_string(n) +
                     " rays touching the mesh at a vertex");
  return rays;
}

std::vector<Ray> grazing_edge_rays(const TriangleMesh& mesh, std::size_t n, double distance, std::uint64_t seed) {
  const Adjacency adj(mesh);
  struct Crease {
    std::uint32_t a, b, t1, t2;
  };
  std::vector<Crease> creases;
  for (std::size_t i = 0; i + 1 < adj.edges.size(); ++i) {
    const auto key = adj.edges[i].first;
    if (adj.edges[i + 1].first != key || (i + 2 < adj.edges.size() && adj.edges[i + 2].first == key) ||
        (i > 0 && adj.edges[i - 1].first == key))
      continue;  // manifold edges only: exactly two triangles
    const std::uint32_t t1 = adj.edges[i].second, t2 = adj.edges[i + 1].second;
    if (dot(unit_normal(mesh, t1), unit_normal(mesh, t2)) > 1.0 - 1e-9) continue;  // coplanar: no silhouette
    creases.push_back({static_cast<std::uint32_t>(key >> 32), static_cast<std::uint32_t>(key & 0xffffffffu), t1, t2});
  }
  if (creases.empty()) throw InputError("grazing rays: the mesh has no edge shared by two non-coplanar triangles");
  Rng rng(seed);
  std::vector<Ray> rays;
  rays.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Crease& e = creases[rng.below(creases.size())];
    const Vec3d a(mesh.vertices[e.a]), b(mesh.vertices[e.b]);
    const Vec3d n1 = unit_normal(mesh, e.t1), n2 = unit_normal(mesh, e.t2), along = normalize(b - a);
    const double c = dot(n1, n2), limit = (1.0 - c) / (1.0 + c);
    const double g = k % 2 == 0 ? 2.0 * rng.uniform_open() - 1.0
                                : (rng.uniform() < 0.5 ? -1.0 : 1.0) * (1.0 - std::pow(10.0, -6.0 * rng.uniform()));
    const Vec3d across = normalize((n1 - n2) + (n1 + n2) * (g * limit));
    const double beta = (std::numbers::pi / 3.0) * (2.0 * rng.uniform() - 1.0);
    const Vec3d w = across * std::cos(beta) + along * std::sin(beta);
    const Vec3d p = Vec3d(Vec3f(a + (b - a) * rng.uniform_open()));
    const Vec3f org(p - w * distance);
    Vec3f dir(p - Vec3d(org));
    if (dir == Vec3f(0.0f)) dir = Vec3f(w);
    rays.push_back(Ray{org, dir, 0.0f, std::numeric_limits<float>::infinity()});
  }
  return rays;
}

}  // namespace raylab
