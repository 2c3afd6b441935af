#pragma once
/// The adversarial cases of issue 6 ("where methods fail"), shared by the adversarial test suite
/// (tests/test_adversarial.cpp) and the robustness experiment (experiments/exp_robustness.cpp),
/// so the report's failure table counts exactly the rays the tests hold each method to.
///
/// Each case is a small scene plus rays built by hand to land on the places where float
/// methods and spatial subdivisions fail: shared edges and vertices, split planes and cell
/// faces, coplanar and duplicated triangles, degenerate triangles, extreme coordinates, rays on
/// surfaces and grazing rays, and piles of identical triangles (deep or degenerate trees).
///
/// Which AccuracyBound applies (accel_factory.h): the exact oracle classifies every ray
/// (crossing, touching, on-surface, ill-conditioned; contact_classes.h) and each class has its
/// own bound. Cases whose rays are aimed at edges, vertices or planes count as feature-aimed
/// (the bound for crossings of edge/vertex-aimed rays, which methods that are not watertight
/// need); rays in general position get the bound for other rays.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "geometry/input_error.h"
#include "scene/cgal_meshes.h"
#include "scene/scene.h"
#include "scene/scene_spec.h"

namespace raylab::adversarial {

enum class RayClass {
  closed_features,  ///< feature_rays on a closed mesh: transversal crossings at edges/vertices
  open_features,    ///< exact contact with edges, vertices or planes that need not be a crossing
  general,          ///< rays in general position
};

inline const char* ray_class_name(RayClass c) {
  return c == RayClass::closed_features ? "closed_features" : c == RayClass::open_features ? "open_features" : "general";
}

struct Case {
  std::string name;    ///< e.g. "split_planes"
  std::string detail;  ///< one line for the report
  std::shared_ptr<const Scene> scene;
  std::vector<Ray> rays;
  RayClass ray_class = RayClass::general;

  /// Whether AccuracyBound's bound for feature-aimed crossings applies.
  bool feature_rays() const { return ray_class != RayClass::general; }
};

/// Every accelerator spec the factory knows, with its listed variants (as the oracle suite runs
/// them). The environment variable RAYLAB_TEST_ACCELS (comma-separated accelerator names, e.g.
/// `brute,exact,embree`) restricts the list, for diagnosing one accelerator; unset, all run.
inline std::vector<std::string> accel_specs_under_test() {
  std::vector<std::string> only;
  if (const char* env = std::getenv("RAYLAB_TEST_ACCELS")) {
    std::string cur;
    for (const char* p = env;; ++p) {
      if (*p == ',' || *p == '\0') {
        if (!cur.empty()) only.push_back(cur);
        cur.clear();
        if (!*p) break;
      } else {
        cur += *p;
      }
    }
  }
  std::vector<std::string> specs;
  for (const auto& kind : accelerator_kinds()) {
    if (!only.empty() && std::find(only.begin(), only.end(), kind.name) == only.end()) continue;
    specs.push_back(kind.name);
    for (const auto& v : kind.oracle_variants) specs.push_back(kind.name + ":" + v);
  }
  return specs;
}

namespace detail {

inline std::shared_ptr<Scene> mesh_scene(const std::string& spec, TriangleMesh mesh) {
  auto s = std::make_shared<Scene>();
  s->spec = spec;
  s->mesh = std::move(mesh);
  return s;
}

inline void add_triangle(TriangleMesh& m, Vec3f a, Vec3f b, Vec3f c) {
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c});
  m.triangles.push_back({base, base + 1, base + 2});
}

inline void append_rays(std::vector<Ray>& to, const std::vector<Ray>& from) { to.insert(to.end(), from.begin(), from.end()); }

/// Deterministic uniform floats in [0, 1) (splitmix64), independent of the library's generators.
struct Rng {
  std::uint64_t s;
  explicit Rng(std::uint64_t seed) : s(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  Vec3d direction() {
    const double z = 2 * uniform() - 1, phi = 2 * M_PI * uniform(), r = std::sqrt(std::max(0.0, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
};

/// A closed bipyramid of `sides` triangles around each of its two apexes (valence `sides`).
inline TriangleMesh bipyramid(int sides) {
  TriangleMesh m;
  m.vertices.push_back({0, 0, 1});
  m.vertices.push_back({0, 0, -1});
  for (int i = 0; i < sides; ++i) {
    const double a = 2 * M_PI * i / sides;
    m.vertices.push_back({static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0.0f});
  }
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(sides); ++i) {
    const std::uint32_t a = 2 + i, b = 2 + (i + 1) % sides;
    m.triangles.push_back({0, a, b});  // outward: counter-clockwise seen from +z
    m.triangles.push_back({1, b, a});
  }
  return m;
}

/// Axis-parallel rays (direction ±e_axis with ±0 in the other components) whose origins lie
/// outside the bounds, with the two other coordinates taken from `coords`.
inline void axis_rays(std::vector<Ray>& rays, const Bounds3f& b, const std::vector<std::pair<float, float>>& coords) {
  const float pad = 0.5f * std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z}) + 1.0f;
  int k = 0;
  for (const auto& [p, q] : coords)
    for (int axis = 0; axis < 3; ++axis) {
      const bool negative = (k++ % 2) == 1;
      const float zero = (k % 4) < 2 ? 0.0f : -0.0f;  // both signs of zero
      Vec3f o, d(zero);
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      o[a1] = p;
      o[a2] = q;
      o[axis] = negative ? b.hi[axis] + pad : b.lo[axis] - pad;
      d[axis] = negative ? -1.0f : 1.0f;
      rays.push_back(Ray{o, d, 0.0f, std::numeric_limits<float>::infinity()});
    }
}

/// Power-of-two fractions lo + k/2^j·(hi - lo), j <= levels: the split planes of midpoint
/// kd-trees, octrees and grids of power-of-two resolution.
inline std::vector<float> dyadic(float lo, float hi, int levels) {
  std::vector<float> v;
  const int n = 1 << levels;
  for (int k = 0; k <= n; ++k) v.push_back(lo + (hi - lo) * static_cast<float>(k) / static_cast<float>(n));
  return v;
}

/// Random lines through the scene's bounds (general position).
inline std::vector<Ray> random_lines(const Bounds3f& b, std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<Ray> rays;
  const Vec3d lo(b.lo), hi(b.hi), c = (lo + hi) * 0.5;
  const double r = 0.5 * length(hi - lo) + 1e-6 * (1 + length(c));
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d target = lo + Vec3d(rng.uniform() * (hi.x - lo.x), rng.uniform() * (hi.y - lo.y), rng.uniform() * (hi.z - lo.z));
    const Vec3d w = rng.direction();
    const Vec3d o = target - w * (2 * r);
    rays.push_back(Ray{Vec3f(o), Vec3f(w * (2 * r)), 0.0f, std::numeric_limits<float>::infinity()});
  }
  return rays;
}

inline TriangleMesh transformed(TriangleMesh m, double scale, Vec3d offset) {
  for (auto& v : m.vertices) v = Vec3f(Vec3d(v) * scale + offset);
  return m;
}

}  // namespace detail

/// Closed CGAL demo meshes with at most `max_triangles` triangles (all when 0), in name order.
inline std::vector<std::string> closed_cgal_meshes(std::size_t max_triangles) {
  std::vector<std::string> names;
  for (const auto& name : cgal_mesh_names()) {
    try {
      const auto s = make_scene("cgal:" + name);
      if (max_triangles && s->mesh.size() > max_triangles) continue;
      if (describe(*s).closed) names.push_back(name);
    } catch (const InputError&) {
    }
  }
  return names;
}

/// Shared edges and vertices of a closed mesh: rays aimed exactly at them (feature_rays), and,
/// with `touching` (on closed meshes), n/2 rays touching it at vertices and n/2 grazing its
/// silhouette edges.
inline Case shared_edges_case(const std::string& name, std::shared_ptr<const Scene> scene, std::size_t n,
                              bool touching = false) {
  Case c{"shared_edges/" + name,
         touching ? "rays aimed exactly at shared edges and vertices; rays touching vertices, grazing silhouette edges"
                  : "rays aimed exactly at shared edges and vertices",
         scene, {}, RayClass::closed_features};
  if (!describe(*scene).closed) c.ray_class = RayClass::open_features;
  detail::append_rays(c.rays, make_ray_set("edges:" + std::to_string(n), scene));
  detail::append_rays(c.rays, make_ray_set("vertices:" + std::to_string(n), scene));
  if (touching && c.ray_class == RayClass::closed_features) {
    const std::string half = std::to_string(std::max<std::size_t>(1, n / 2));
    try {
      detail::append_rays(c.rays, make_ray_set("touching:" + half, scene));
    } catch (const InputError&) {  // a mesh without a vertex the generator can touch
    }
    detail::append_rays(c.rays, make_ray_set("grazing:" + half, scene));
  }
  return c;
}

/// A closed mesh far from the origin (offsets 1e3, and 1e6 with the mesh scaled by 100: at its
/// own size a mesh of unit extent at 1e6 collapses to a few float positions and grid cells turn a
/// few ulps wide), tiny (scale 1e-6) and huge (1e6), rotated, through the `transformed` scene kind: edge-, vertex-aimed, touching and grazing rays
/// and random lines.
inline std::vector<Case> transformed_cases(const std::string& mesh_spec, std::size_t n) {
  std::vector<Case> cases;
  for (const auto& [label, transform] : std::vector<std::pair<std::string, std::string>>{
           {"offset1e3", "rotate=1;2;3:40,translate=1e3:-2e3:5e2"},
           {"offset1e6", "rotate=x:30,scale=100,translate=1e6:3e5:-2e5"},
           {"scale1e-6", "rotate=y:70,scale=1e-6"},
           {"scale1e6", "rotate=z:10,scale=1e6,translate=2e6:0:0"}}) {
    const std::string spec = "transformed:of=(" + mesh_spec + ")," + transform;
    Case c = shared_edges_case(label, make_scene(spec), n, true);
    c.name = "transformed/" + label;
    c.detail = "`" + spec + "`: edge-, vertex-aimed, touching and grazing rays, random lines";
    detail::append_rays(c.rays, detail::random_lines(c.scene->bounds(), n, 61));
    cases.push_back(std::move(c));
  }
  return cases;
}

/// All cases except the CGAL meshes; `n` scales the ray counts (a few hundred rays each at n=1).
inline std::vector<Case> synthetic_cases(std::size_t n = 1) {
  using namespace detail;
  std::vector<Case> cases;
  const float inf = std::numeric_limits<float>::infinity();

  // High-valence fans: a closed bipyramid with two apexes of valence 256.
  cases.push_back(shared_edges_case("fan256", mesh_scene("fan256", bipyramid(256)), 256 * n));

  // Split planes: a closed sphere spanning [-1,1]^3, whose equator and meridian vertices lie on
  // the planes x=0, y=0, z=0 (the first split of any midpoint subdivision). Axis-parallel rays
  // with ±0 direction components start on dyadic fractions of the bounds and on vertex
  // coordinates, so they run inside split planes and cell faces and through vertices.
  {
    auto scene = make_scene("sphere:n=512");
    Case c{"split_planes", "axis-parallel rays (±0 components) on dyadic split planes and vertex coordinates", scene, {},
           RayClass::open_features};
    const Bounds3f b = scene->bounds();
    std::vector<std::pair<float, float>> coords;
    const auto xs = dyadic(b.lo.x, b.hi.x, 3);
    for (float p : xs)
      for (float q : xs) coords.emplace_back(p, q);
    for (std::size_t i = 0; i < scene->mesh.vertices.size(); i += 7) {
      const Vec3f v = scene->mesh.vertices[i];
      coords.emplace_back(v.x, v.y);
      coords.emplace_back(v.y, v.z);
      coords.emplace_back(v.z, v.x);
    }
    for (std::size_t k = 0; k < n; ++k) axis_rays(c.rays, b, coords);
    cases.push_back(std::move(c));
  }

  // Coplanar triangles: a sheet of triangles exactly in the plane z = 0.5 (a dyadic split plane
  // of the unit cube), duplicated triangles, and coplanar overlapping triangles; rays into the
  // sheet through its shared edges and vertices and rays lying in the plane.
  {
    TriangleMesh m;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const float x0 = i * 0.25f, y0 = j * 0.25f, x1 = x0 + 0.25f, y1 = y0 + 0.25f;
        add_triangle(m, {x0, y0, 0.5f}, {x1, y0, 0.5f}, {x1, y1, 0.5f});
        add_triangle(m, {x0, y0, 0.5f}, {x1, y1, 0.5f}, {x0, y1, 0.5f});
      }
    add_triangle(m, {0, 0, 0.5f}, {0.25f, 0, 0.5f}, {0.25f, 0.25f, 0.5f});     // duplicate
    add_triangle(m, {0.1f, 0.1f, 0.5f}, {0.9f, 0.2f, 0.5f}, {0.3f, 0.8f, 0.5f});  // coplanar overlap
    add_triangle(m, {0, 0, 0}, {1, 0, 0}, {0, 0, 1});                           // in the plane y = 0
    add_triangle(m, {0, 0, 0}, {1, 0, 0}, {0, 0, 1});                           // ... duplicated
    add_triangle(m, {0, 0, 1}, {1, 1, 1}, {1, 0, 1});                           // top face of the box
    auto scene = mesh_scene("coplanar", std::move(m));
    Case c{"coplanar", "triangles in a split plane, duplicated and coplanar overlapping triangles", scene, {},
           RayClass::open_features};
    Rng rng(11);
    for (std::size_t k = 0; k < 64 * n; ++k) {
      // Through grid points and edge points of the sheet, from above and below.
      const float x = static_cast<float>(rng.next() % 9) * 0.125f, y = static_cast<float>(rng.next() % 9) * 0.125f;
      const Vec3d w = rng.direction();
      const Vec3d o = Vec3d(x, y, 0.5) - w * 2.0;
      c.rays.push_back(Ray{Vec3f(o), Vec3f(w * 2.0), 0.0f, inf});
      // In the plane z = 0.5, and in the plane y = 0.
      c.rays.push_back(Ray{{-1.0f, y, 0.5f}, {1.0f, x - y, 0.0f}, 0.0f, inf});
      c.rays.push_back(Ray{{x, 0.0f, -1.0f}, {0.0f, 0.0f, 1.0f}, 0.0f, inf});
    }
    axis_rays(c.rays, scene->bounds(), {{0.25f, 0.25f}, {0.5f, 0.5f}, {0.125f, 0.5f}, {0.5f, 0.0f}});
    append_rays(c.rays, random_lines(scene->bounds(), 128 * n, 12));
    cases.push_back(std::move(c));
  }

  // Degenerate triangles: zero area (collinear), repeated vertices, a point triangle, triangles
  // with identical centroids and with identical bounds; rays aimed at them and random lines.
  {
    TriangleMesh m;
    add_triangle(m, {0, 0, 0}, {1, 1, 1}, {2, 2, 2});              // collinear
    add_triangle(m, {0, 1, 0}, {0, 1, 0}, {1, 1, 0});              // repeated vertex
    add_triangle(m, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f});  // a point
    for (int i = 1; i <= 16; ++i) {  // identical centroids (1, 1, 1), growing and turning
      const float s = 0.05f * i;
      const float a = 0.3f * i;
      const Vec3f c(1, 1, 1);
      const Vec3f u(s * std::cos(a), s * std::sin(a), 0.2f * s), v(-s * std::sin(a), s * std::cos(a), -0.1f * s);
      add_triangle(m, c + u, c + v, c - u - v);
    }
    for (int i = 0; i < 8; ++i) {  // identical bounds [0,1]x[0,1]x[1.5,2]: the box's diagonals
      add_triangle(m, {0, 0, 1.5f}, {1, 1, 2}, i % 2 ? Vec3f(1, 0, 1.5f) : Vec3f(0, 1, 2));
      add_triangle(m, {1, 0, 1.5f}, {0, 1, 2}, i % 2 ? Vec3f(0, 0, 2) : Vec3f(1, 1, 1.5f));
    }
    auto scene = mesh_scene("degenerate", std::move(m));
    Case c{"degenerate", "zero-area, collinear and repeated-vertex triangles; identical centroids and bounds", scene, {},
           RayClass::open_features};
    Rng rng(21);
    for (std::size_t k = 0; k < 128 * n; ++k) {
      const double s = rng.uniform();
      const Vec3d target = k % 4 == 0   ? Vec3d(2 * s, 2 * s, 2 * s)                     // on the collinear triangle
                           : k % 4 == 1 ? Vec3d(s, 1, 0)                                  // on the repeated-vertex one
                           : k % 4 == 2 ? Vec3d(1, 1, 1)                                  // the common centroid
                                        : Vec3d(s, s, 1.5 + 0.5 * s);                     // the shared diagonal
      const Vec3d w = rng.direction();
      c.rays.push_back(Ray{Vec3f(target - w * 3.0), Vec3f(w * 3.0), 0.0f, inf});
    }
    append_rays(c.rays, random_lines(scene->bounds(), 256 * n, 22));
    cases.push_back(std::move(c));
  }

  // Extreme coordinates: a closed sphere moved by 1e5, 1e6 and 1e7 (radius 1e-3 of the offset,
  // about a thousand float ulps) and shrunk to radius 1e-6; rays at its edges and vertices.
  for (const auto& [label, scale, offset] : std::vector<std::tuple<std::string, double, double>>{
           {"offset1e5", 1e2, 1e5}, {"offset1e6", 1e3, 1e6}, {"offset1e7", 1e4, 1e7}, {"scale1e-6", 1e-6, 0.0}}) {
    auto scene = mesh_scene("extreme_" + label,
                            transformed(make_scene("sphere:n=512")->mesh, scale, Vec3d(offset, -0.5 * offset, 0.25 * offset)));
    Case c = shared_edges_case("x", scene, 128 * n);
    c.name = "extreme/" + label;
    c.detail = "a sphere at offset " + std::to_string(offset) + ", radius " + std::to_string(scale);
    append_rays(c.rays, random_lines(scene->bounds(), 128 * n, 31));
    cases.push_back(std::move(c));
  }

  // Rays on surfaces: origins on triangles of a closed sphere (rounded to float), leaving in
  // random directions; and grazing rays, lying in a triangle's plane along its edges.
  {
    auto scene = make_scene("sphere:n=256");
    Case c{"on_surface", "rays starting on a surface, and grazing rays along triangle edges and planes", scene, {},
           RayClass::open_features};
    Rng rng(41);
    const auto& mesh = scene->mesh;
    for (std::size_t k = 0; k < 256 * n; ++k) {
      const std::size_t t = rng.next() % mesh.size();
      const Vec3d p0(mesh.vertex(t, 0)), p1(mesh.vertex(t, 1)), p2(mesh.vertex(t, 2));
      double u = rng.uniform(), v = rng.uniform();
      if (u + v > 1) u = 1 - u, v = 1 - v;
      const Vec3d p = p0 + (p1 - p0) * u + (p2 - p0) * v;
      if (k % 2 == 0) {
        c.rays.push_back(Ray{Vec3f(p), Vec3f(rng.direction()), 0.0f, inf});
      } else {  // grazing: in the plane of triangle t, along an edge or across it
        const Vec3d dir = k % 4 == 1 ? p1 - p0 : (p2 - p1) * u + (p0 - p1) * v;
        c.rays.push_back(Ray{Vec3f(p - dir * 2.0), Vec3f(dir), 0.0f, inf});
      }
    }
    cases.push_back(std::move(c));
  }

  // Deep or degenerate trees: 512 identical triangles, 512 triangles sharing one edge, and a
  // column of 512 tiny triangles with identical x/y bounds; no subdivision can separate them.
  {
    TriangleMesh m;
    for (int i = 0; i < 512; ++i) add_triangle(m, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    for (int i = 0; i < 512; ++i) {
      const double a = M_PI * (i + 0.5) / 512;
      add_triangle(m, {2, 0, 0}, {3, 0, 0}, {2.5f, float(std::cos(a)), float(std::sin(a))});
    }
    for (int i = 0; i < 512; ++i) {
      const float z = 4e-4f * static_cast<float>(i);
      add_triangle(m, {4, 0, z}, {4.001f, 0, z}, {4, 0.001f, z});
    }
    auto scene = mesh_scene("deep", std::move(m));
    Case c{"deep_trees", "thousands of identical, edge-sharing and stacked triangles", scene, {}, RayClass::general};
    append_rays(c.rays, random_lines(scene->bounds(), 128 * n, 51));
    Rng rng(52);
    for (std::size_t k = 0; k < 32 * n; ++k) {  // down the stacks, in general position
      const float s = static_cast<float>(0.05 + 0.4 * rng.uniform());
      c.rays.push_back(Ray{{s, 0.3f * s + 0.01f, 5}, {0.01f, 0.02f, -1}, 0.0f, inf});
      c.rays.push_back(Ray{{4.0002f + 0.0001f * s, 0.0002f + 0.0001f * s, 5}, {0.0f, 0.0f, -1}, 0.0f, inf});
    }
    cases.push_back(std::move(c));
  }
  return cases;
}

/// Rays that are not valid (geometry/ray.h: is_valid): NaN or infinite components, a zero
/// direction, tmin < 0, tmin > tmax, NaN bounds. Every accelerator must report no hit.
inline std::vector<Ray> non_finite_rays() {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<Ray> rays;
  const Ray good{{0.25f, 0.25f, 5.0f}, {0.0f, 0.0f, -1.0f}, 0.0f, inf};
  for (int comp = 0; comp < 6; ++comp)
    for (float bad : {nan, inf, -inf}) {
      Ray r = good;
      (comp < 3 ? r.org : r.dir)[comp % 3] = bad;
      rays.push_back(r);
    }
  Ray r = good;
  r.dir = Vec3f(0.0f);
  rays.push_back(r);
  r = good;
  r.dir = Vec3f(-0.0f);
  rays.push_back(r);
  r = good;
  r.tmin = -1.0f;
  rays.push_back(r);
  r = good;
  r.tmin = 2.0f, r.tmax = 1.0f;
  rays.push_back(r);
  r = good;
  r.tmin = nan;
  rays.push_back(r);
  r = good;
  r.tmax = nan;
  rays.push_back(r);
  r = good;
  r.tmin = inf;
  r.tmax = inf;
  rays.push_back(r);
  r = good;
  r.org = Vec3f(nan);
  r.dir = Vec3f(nan);
  rays.push_back(r);
  r = good;
  r.org = Vec3f(3e38f, 3e38f, 3e38f);  // finite but huge: valid, must not hang
  rays.push_back(r);
  return rays;
}

}  // namespace raylab::adversarial
