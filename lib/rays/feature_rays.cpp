#include "rays/feature_rays.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

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

/// weld[i] = the smallest vertex index with the same position as vertex i.
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

struct Incidence {
  std::uint64_t feature;  ///< welded vertex, or (lo << 32 | hi) of an edge's welded vertices
  std::uint32_t tri;
  bool operator<(const Incidence& o) const { return feature != o.feature ? feature < o.feature : tri < o.tri; }
};

}  // namespace

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
