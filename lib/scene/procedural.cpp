#include "scene/procedural.h"

#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>

#include "geometry/input_error.h"
#include "scene/openmesh_conversion.h"

namespace raylab {
namespace {

using TriMesh = OpenMeshTriMesh;

constexpr std::int64_t kMaxTriangles = std::int64_t{1} << 27;

void require(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

std::uint32_t u32(std::size_t i) { return static_cast<std::uint32_t>(i); }

void check_triangle_budget(const std::string& kind, double triangles) {
  require(triangles <= static_cast<double>(kMaxTriangles),
          kind + ": the scene would have " + std::to_string(static_cast<std::int64_t>(triangles)) + " triangles, more than 2^27");
}

/// Appends an axis-aligned box [lo, hi] (12 outward-facing triangles) transformed by `xf`.
void append_box(TriangleMesh& mesh, const Vec3d& lo, const Vec3d& hi, const AffineTransform& xf) {
  const auto base = u32(mesh.vertices.size());
  for (int c = 0; c < 8; ++c)
    mesh.vertices.push_back(Vec3f(xf.apply_point(Vec3d((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z))));
  static const std::uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    mesh.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    mesh.triangles.push_back({base + q[0], base + q[2], base + q[3]});
  }
}

TriangleMesh from_openmesh(const TriMesh& m) {
  TriangleMesh out;
  out.vertices.reserve(m.n_vertices());
  std::vector<std::uint32_t> remap(m.n_vertices(), 0);
  for (const auto v : m.vertices()) {
    if (m.has_vertex_status() && m.status(v).deleted()) continue;
    remap[static_cast<std::size_t>(v.idx())] = u32(out.vertices.size());
    const auto& p = m.point(v);
    out.vertices.emplace_back(p[0], p[1], p[2]);
  }
  out.triangles.reserve(m.n_faces());
  for (const auto f : m.faces()) {
    if (m.has_face_status() && m.status(f).deleted()) continue;
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (const auto v : m.fv_range(f))
      if (k < 3) t[static_cast<std::size_t>(k++)] = remap[static_cast<std::size_t>(v.idx())];
    if (k == 3) out.triangles.push_back(t);
  }
  return out;
}

void require_plain_triangles(const Scene& s, const std::string& kind) {
  require(!s.instanced(), kind + ": the scene " + s.spec + " is instanced (a triangle mesh is needed)");
  require(s.spheres.empty(), kind + ": the scene " + s.spec + " has spheres (a triangle mesh is needed)");
  require(s.mesh.size() > 0, kind + ": the scene " + s.spec + " has no triangles");
}

}  // namespace

TriangleMesh uv_sphere(const Vec3f& center, float radius, int stacks, int slices) {
  require(stacks >= 2 && slices >= 3, "uv_sphere: needs stacks >= 2 and slices >= 3");
  TriangleMesh m;
  const Vec3d c(center);
  const double r = radius;
  m.vertices.reserve(static_cast<std::size_t>(2 + (stacks - 1) * slices));
  m.vertices.push_back(Vec3f(c + Vec3d(0, r, 0)));
  for (int i = 1; i < stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    const double y = r * std::cos(theta), rho = r * std::sin(theta);
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * std::numbers::pi * j / slices;
      m.vertices.push_back(Vec3f(c + Vec3d(rho * std::cos(phi), y, rho * std::sin(phi))));
    }
  }
  const auto south = u32(m.vertices.size());
  m.vertices.push_back(Vec3f(c - Vec3d(0, r, 0)));
  auto ring = [&](int i, int j) { return u32(1 + static_cast<std::size_t>(i - 1) * slices + static_cast<std::size_t>(j % slices)); };
  m.triangles.reserve(static_cast<std::size_t>(2 * slices * (stacks - 1)));
  for (int j = 0; j < slices; ++j) m.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const std::uint32_t a = ring(i, j), b = ring(i, j + 1), lo_a = ring(i + 1, j), lo_b = ring(i + 1, j + 1);
      m.triangles.push_back({a, b, lo_b});
      m.triangles.push_back({a, lo_b, lo_a});
    }
  for (int j = 0; j < slices; ++j) m.triangles.push_back({south, ring(stacks - 1, j), ring(stacks - 1, j + 1)});
  return m;
}

Scene make_sphere(const SphereConfig& c) {
  require(c.triangles >= 8 && c.triangles <= kMaxTriangles, "sphere: n must be in [8, 2^27]");
  require(std::isfinite(c.radius) && c.radius > 0, "sphere: radius must be positive");
  const int stacks = std::max(2, static_cast<int>(std::lround((1.0 + std::sqrt(1.0 + static_cast<double>(c.triangles))) / 2.0)));
  Scene s;
  s.mesh = uv_sphere(Vec3f(0.0f), static_cast<float>(c.radius), stacks, 2 * stacks);
  return s;
}

Scene make_sphereflake(const SphereflakeConfig& c) {
  require(c.depth >= 0 && c.depth <= 7, "sphereflake: depth must be in [0, 7]");
  require(c.tess >= 2 && c.tess <= 64, "sphereflake: tess must be in [2, 64]");
  double count = 0;
  for (int d = 0, p = 1; d <= c.depth; ++d, p *= 9) count += p;
  const double per_sphere = 2.0 * (2 * c.tess) * (c.tess - 1);
  if (c.as_triangles) check_triangle_budget("sphereflake", count * per_sphere);

  // Child directions in the frame of the growth direction w: six around the equator, three at
  // 60 degrees elevation between them (Haines' SPD `balls`, up to the exact angles).
  struct Dir { double equator, elevation; };
  std::vector<Dir> dirs;
  for (int k = 0; k < 6; ++k) dirs.push_back({k * std::numbers::pi / 3, 0.0});
  for (int k = 0; k < 3; ++k) dirs.push_back({std::numbers::pi / 6 + k * 2 * std::numbers::pi / 3, std::numbers::pi / 3});

  Scene s;
  s.spheres.reserve(static_cast<std::size_t>(count));
  auto grow = [&](auto&& self, const Vec3d& center, double radius, const Vec3d& w, int depth) -> void {
    s.spheres.push_back({Vec3f(center), static_cast<float>(radius)});
    if (depth == 0) return;
    const Vec3d helper = std::abs(w.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d u = normalize(cross(helper, w)), v = cross(w, u);
    for (const auto& d : dirs) {
      const Vec3d dir = (u * std::cos(d.equator) + v * std::sin(d.equator)) * std::cos(d.elevation) + w * std::sin(d.elevation);
      const double child = radius / 3.0;
      self(self, center + dir * (radius + child), child, dir, depth - 1);
    }
  };
  grow(grow, Vec3d(0.0), 1.0, Vec3d(0, 1, 0), c.depth);
  if (!c.as_triangles) return s;
  Scene t;
  const TriangleMesh unit = uv_sphere(Vec3f(0.0f), 1.0f, c.tess, 2 * c.tess);
  t.mesh.vertices.reserve(unit.vertices.size() * s.spheres.size());
  t.mesh.triangles.reserve(unit.size() * s.spheres.size());
  for (const auto& sp : s.spheres) {
    const auto base = u32(t.mesh.vertices.size());
    for (const auto& p : unit.vertices) t.mesh.vertices.push_back(sp.center + p * sp.radius);
    for (const auto& tri : unit.triangles) t.mesh.triangles.push_back({tri[0] + base, tri[1] + base, tri[2] + base});
  }
  return t;
}

Scene make_stadium(const Scene& object, const StadiumConfig& c) {
  require(!object.instanced(), "stadium: the object " + object.spec + " must not be instanced");
  require(c.ratio >= 1 && c.ratio <= 1e6, "stadium: ratio must be in [1, 1e6]");
  require(c.segments >= 8 && c.segments <= 4096, "stadium: segments must be in [8, 4096]");
  require(c.tiers >= 1 && c.tiers <= 256, "stadium: tiers must be in [1, 256]");
  const Bounds3f ob = object.bounds();
  require(!ob.empty(), "stadium: the object " + object.spec + " is empty");
  const double diag = length(Vec3d(ob.diagonal()));
  require(diag > 0, "stadium: the object " + object.spec + " has a zero-size bounding box");
  check_triangle_budget("stadium", static_cast<double>(object.mesh.size()) + c.segments * (1.0 + 4.0 * c.tiers));

  // The object keeps its own coordinates (and precision); the stadium is placed around it so
  // that its goal line, 0.9 of the half-length from the centre, runs under the object.
  const double a = c.ratio * diag / 2, b = 0.65 * a;
  const Vec3d goal(0.5 * (double(ob.lo.x) + ob.hi.x), ob.lo.y, 0.5 * (double(ob.lo.z) + ob.hi.z));
  const Vec3d centre = goal - Vec3d(0.9 * a, 0, 0);
  Scene s;
  s.mesh = object.mesh;
  s.spheres = object.spheres;
  TriangleMesh& m = s.mesh;
  auto ellipse = [&](double scale, double height, int j) {
    const double phi = 2 * std::numbers::pi * j / c.segments;
    return Vec3f(centre + Vec3d(scale * a * std::cos(phi), height, scale * b * std::sin(phi)));
  };
  // Ground: a fan facing up.
  const auto hub = u32(m.vertices.size());
  m.vertices.push_back(Vec3f(centre));
  for (int j = 0; j < c.segments; ++j) m.vertices.push_back(ellipse(1.0, 0.0, j));
  for (int j = 0; j < c.segments; ++j)
    m.triangles.push_back({hub, hub + 1 + u32(static_cast<std::size_t>((j + 1) % c.segments)), hub + 1 + u32(static_cast<std::size_t>(j))});
  // Stands: the stepped profile (riser, tread, riser, ...) swept around the ellipse.
  const double rise = 0.03 * a, step = 0.04;
  const auto first = u32(m.vertices.size());
  const int profile = 2 * c.tiers + 1;
  for (int p = 0; p < profile; ++p) {
    const double scale = 1.0 + step * (p / 2), height = rise * ((p + 1) / 2);
    for (int j = 0; j < c.segments; ++j) m.vertices.push_back(ellipse(scale, height, j));
  }
  auto at = [&](int p, int j) { return first + u32(static_cast<std::size_t>(p) * c.segments + static_cast<std::size_t>(j % c.segments)); };
  for (int p = 0; p + 1 < profile; ++p)
    for (int j = 0; j < c.segments; ++j) {
      m.triangles.push_back({at(p, j), at(p + 1, j), at(p + 1, j + 1)});
      m.triangles.push_back({at(p, j), at(p + 1, j + 1), at(p, j + 1)});
    }
  const Bounds3f sb = s.bounds();
  require(is_finite(sb.lo) && is_finite(sb.hi), "stadium: the stadium's coordinates overflow float");
  return s;
}

Scene make_grass(const GrassConfig& c) {
  require(c.blades >= 1 && c.blades <= (std::int64_t{1} << 26), "grass: blades must be in [1, 2^26]");
  require(c.height > 0 && c.width > 0 && std::isfinite(c.height) && std::isfinite(c.width), "grass: height and width must be positive");
  std::mt19937_64 rng(c.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Scene s;
  auto& m = s.mesh;
  const auto n = static_cast<std::size_t>(c.blades);
  m.vertices.reserve(5 * n);
  m.triangles.reserve(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d p(unit(rng), 0.0, unit(rng));
    const double heading = 2 * std::numbers::pi * unit(rng), lean = 0.3 * c.height * unit(rng);
    const Vec3d t(std::cos(heading), 0, std::sin(heading)), side(-std::sin(heading), 0, std::cos(heading));
    const double w = c.width / 2;
    const auto base = u32(m.vertices.size());
    m.vertices.push_back(Vec3f(p - t * w));
    m.vertices.push_back(Vec3f(p + t * w));
    m.vertices.push_back(Vec3f(p - t * (0.6 * w) + side * (0.25 * lean) + Vec3d(0, c.height / 2, 0)));
    m.vertices.push_back(Vec3f(p + t * (0.6 * w) + side * (0.25 * lean) + Vec3d(0, c.height / 2, 0)));
    m.vertices.push_back(Vec3f(p + side * lean + Vec3d(0, c.height, 0)));
    m.triangles.push_back({base, base + 1, base + 3});
    m.triangles.push_back({base, base + 3, base + 2});
    m.triangles.push_back({base + 2, base + 3, base + 4});
  }
  return s;
}

Scene make_walls(const WallsConfig& c) {
  require(c.walls >= 1 && c.walls <= (std::int64_t{1} << 24), "walls: n must be in [1, 2^24]");
  require(std::isfinite(c.angle_degrees) && std::abs(c.angle_degrees) <= 360, "walls: angle must be in [-360, 360]");
  require(c.length > 0 && c.thickness > 0 && c.spacing > 0 && std::isfinite(c.length + c.thickness + c.spacing),
          "walls: length, thickness and spacing must be positive");
  const double gap = 0.1 * c.length;
  const auto per_row = std::max<std::int64_t>(
      1, std::llround(std::sqrt(static_cast<double>(c.walls) * c.spacing / (c.length + gap))));
  const std::int64_t rows = (c.walls + per_row - 1) / per_row;
  const Vec3d middle(0.5 * (per_row * (c.length + gap) - gap), 0.0, 0.5 * (rows - 1) * c.spacing);
  const AffineTransform xf = AffineTransform::rotation(Vec3d(0, 1, 0), c.angle_degrees * std::numbers::pi / 180.0) *
                             AffineTransform::translation(-middle);
  Scene s;
  s.mesh.vertices.reserve(8 * static_cast<std::size_t>(c.walls));
  s.mesh.triangles.reserve(12 * static_cast<std::size_t>(c.walls));
  for (std::int64_t i = 0; i < c.walls; ++i) {
    const double x = static_cast<double>(i % per_row) * (c.length + gap), z = static_cast<double>(i / per_row) * c.spacing;
    append_box(s.mesh, Vec3d(x, 0, z - c.thickness / 2), Vec3d(x + c.length, 1, z + c.thickness / 2), xf);
  }
  return s;
}

Scene make_room(const Scene& object, const RoomConfig& c) {
  require(!object.instanced(), "room: the object " + object.spec + " must not be instanced");
  require(std::isfinite(c.margin) && c.margin >= 0.01 && c.margin <= 100, "room: margin must be in [0.01, 100]");
  require(std::isfinite(c.window) && (c.window == 0 || (c.window >= 0.05 && c.window <= 0.95)),
          "room: window must be 0 (a closed room) or in [0.05, 0.95]");
  const Bounds3f ob = object.bounds();
  require(!ob.empty(), "room: the object " + object.spec + " is empty");
  const Vec3d extent(ob.diagonal());
  const double grow = c.margin * std::max({extent.x, extent.y, extent.z});
  require(grow > 0, "room: the object " + object.spec + " has a zero-size bounding box");
  check_triangle_budget("room", static_cast<double>(object.mesh.size()) + 36.0);
  const Vec3d lo = Vec3d(ob.lo) - Vec3d(grow), hi = Vec3d(ob.hi) + Vec3d(grow);
  Scene s;
  s.mesh = object.mesh;
  s.spheres = object.spheres;
  TriangleMesh& m = s.mesh;
  // Face `axis` at `side` (0: lo, 1: hi), spanned by the other two axes u, v; a windowed face is
  // the frame around the central square of half its side (4 quads), a solid face one quad.
  auto point = [&](int axis, int side, double fu, double fv) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Vec3d p;
    p[axis] = side ? hi[axis] : lo[axis];
    p[u] = lo[u] + fu * (hi[u] - lo[u]);
    p[v] = lo[v] + fv * (hi[v] - lo[v]);
    return Vec3f(p);
  };
  auto quad = [&](int axis, int side, double u0, double v0, double u1, double v1) {
    const auto base = u32(m.vertices.size());
    m.vertices.push_back(point(axis, side, u0, v0));
    m.vertices.push_back(point(axis, side, u1, v0));
    m.vertices.push_back(point(axis, side, u1, v1));
    m.vertices.push_back(point(axis, side, u0, v1));
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  };
  const double a = 0.5 * (1.0 - c.window), b = 1.0 - a;
  if (c.window == 0) {  // a closed room: one box, its 8 corners shared by its 12 triangles
    append_box(m, lo, hi, AffineTransform::identity());
    return s;
  }
  for (int axis = 0; axis < 3; ++axis) {
    quad(axis, 0, 0, 0, 1, 1);
    quad(axis, 1, 0, 0, a, 1);  // the window frame: left and right columns,
    quad(axis, 1, b, 0, 1, 1);
    quad(axis, 1, a, 0, b, a);  // bottom and top between them
    quad(axis, 1, a, b, b, 1);
  }
  return s;
}

Scene make_soup(const SoupConfig& c) {
  require(c.triangles >= 1 && c.triangles <= kMaxTriangles, "soup: n must be in [1, 2^27]");
  require(std::isfinite(c.size) && c.size >= 0 && c.size <= 1, "soup: size must be in [0, 1]");
  const double size = c.size > 0 ? c.size : std::cbrt(1.0 / static_cast<double>(c.triangles));
  std::mt19937_64 rng(c.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Scene s;
  const auto n = static_cast<std::size_t>(c.triangles);
  s.mesh.vertices.reserve(3 * n);
  s.mesh.triangles.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d centre(unit(rng), unit(rng), unit(rng));
    const auto base = u32(s.mesh.vertices.size());
    for (int k = 0; k < 3; ++k) {
      Vec3d p = centre + Vec3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * size;
      p = min(max(p, Vec3d(0.0)), Vec3d(1.0));
      s.mesh.vertices.push_back(Vec3f(p));
    }
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

Scene make_dust(const DustConfig& c) {
  require(c.triangles >= 1 && c.triangles <= kMaxTriangles, "dust: n must be in [1, 2^27]");
  require(std::isfinite(c.size) && c.size >= 0 && c.size <= 1, "dust: size must be in [0, 1]");
  SoupConfig soup;
  soup.triangles = c.triangles;
  soup.size = c.size > 0 ? c.size : 0.1 / std::sqrt(static_cast<double>(c.triangles));
  soup.seed = c.seed;
  return make_soup(soup);
}

Scene make_needles(const NeedlesConfig& c) {
  require(c.needles >= 1 && c.needles <= kMaxTriangles, "needles: n must be in [1, 2^27]");
  require(std::isfinite(c.length) && c.length > 0 && c.length <= 1e6, "needles: length must be in (0, 1e6]");
  require(std::isfinite(c.width) && c.width >= 0 && c.width <= 1e6, "needles: width must be in [0, 1e6]");
  const auto side = static_cast<std::int64_t>(std::ceil(std::sqrt(static_cast<double>(c.needles))));
  const double extent = 0.2, spacing = extent / static_cast<double>(side);
  const double width = c.width > 0 ? c.width : 0.25 * spacing;
  const Vec3d u = normalize(Vec3d(1, 1, 1)), e1 = normalize(Vec3d(1, -1, 0)), e2 = cross(u, e1);
  const Vec3d centre(0.5, 0.5, 0.5);
  Scene s;
  s.mesh.vertices.reserve(3 * static_cast<std::size_t>(c.needles));
  s.mesh.triangles.reserve(static_cast<std::size_t>(c.needles));
  for (std::int64_t k = 0; k < c.needles; ++k) {
    const double a = (static_cast<double>(k % side) + 0.5) * spacing - extent / 2;
    const double b = (static_cast<double>(k / side) + 0.5) * spacing - extent / 2;
    const Vec3d p = centre + e1 * a + e2 * b;
    const auto base = u32(s.mesh.vertices.size());
    s.mesh.vertices.push_back(Vec3f(p - u * (c.length / 2)));
    s.mesh.vertices.push_back(Vec3f(p + u * (c.length / 2)));
    s.mesh.vertices.push_back(Vec3f(p + e1 * width));
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

Scene make_fan(const FanConfig& c) {
  require(c.triangles >= 3 && c.triangles <= kMaxTriangles, "fan: n must be in [3, 2^27]");
  require(std::isfinite(c.radius) && c.radius > 0 && c.radius <= 1e6, "fan: radius must be in (0, 1e6]");
  require(std::isfinite(c.height) && c.height > 0 && c.height <= 1e6, "fan: height must be in (0, 1e6]");
  const auto n = static_cast<std::size_t>(c.triangles);
  Scene s;
  s.mesh.vertices.reserve(n + 1);
  s.mesh.triangles.reserve(n);
  s.mesh.vertices.push_back(Vec3f(Vec3d(0, c.height, 0)));
  for (std::size_t i = 0; i < n; ++i) {
    const double phi = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
    s.mesh.vertices.push_back(Vec3f(Vec3d(c.radius * std::cos(phi), 0, c.radius * std::sin(phi))));
  }
  for (std::size_t i = 0; i < n; ++i) s.mesh.triangles.push_back({0, u32(1 + (i + 1) % n), u32(1 + i)});
  return s;
}

namespace {

void check_near_miss_row(const NearMissRowConfig& c) {
  require(c.triangles >= 1 && c.triangles <= kMaxTriangles, "row: n must be in [1, 2^27]");
  require(std::isfinite(c.radius) && c.radius > 0 && c.radius <= 1e6, "row: radius must be in (0, 1e6]");
  require(std::isfinite(c.gap) && c.gap > 0 && c.gap <= c.radius / 4, "row: gap must be in (0, radius/4]");
}

}  // namespace

Scene make_near_miss_row(const NearMissRowConfig& c) {
  check_near_miss_row(c);
  // Successive triangles turn by the golden angle, so that the row surrounds the axis evenly and
  // no plane parallel to it separates the axis from more than about half of the triangles.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  const auto n = static_cast<std::size_t>(c.triangles);
  Scene s;
  s.mesh.vertices.reserve(3 * n);
  s.mesh.triangles.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = (static_cast<double>(i) + 0.5) / static_cast<double>(n), theta = golden * static_cast<double>(i);
    const Vec3d radial(0, std::cos(theta), std::sin(theta)), tangent(0, -std::sin(theta), std::cos(theta));
    const Vec3d foot = Vec3d(x, 0, 0) + radial * c.gap;
    const auto base = u32(s.mesh.vertices.size());
    s.mesh.vertices.push_back(Vec3f(foot - tangent * c.radius));
    s.mesh.vertices.push_back(Vec3f(foot + tangent * c.radius));
    s.mesh.vertices.push_back(Vec3f(Vec3d(x, 0, 0) + radial * c.radius));
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

std::vector<Ray> near_miss_row_rays(const NearMissRowConfig& c, std::size_t n, std::uint64_t seed) {
  check_near_miss_row(c);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Ray> rays;
  rays.reserve(n);
  const double offset = c.gap / 4, slope = c.gap / (8 * 1.1);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d org(-0.05, offset * unit(rng) / std::sqrt(2.0), offset * unit(rng) / std::sqrt(2.0));
    const Vec3d dir = normalize(Vec3d(1, slope * unit(rng) / std::sqrt(2.0), slope * unit(rng) / std::sqrt(2.0)));
    rays.push_back(Ray{Vec3f(org), Vec3f(dir)});
  }
  return rays;
}

std::uint64_t subdivision_triangle_limit() {
  const long pages = sysconf(_SC_PHYS_PAGES), page_bytes = sysconf(_SC_PAGE_SIZE);
  const std::uint64_t cap = static_cast<std::uint64_t>(kMaxTriangles);
  if (pages <= 0 || page_bytes <= 0) return cap;
  const double held = static_cast<double>(pages) * static_cast<double>(page_bytes) / kSubdivisionBytesPerTriangle;
  return held < static_cast<double>(cap) ? static_cast<std::uint64_t>(held) : cap;
}

Scene make_subdivided(const Scene& of, int levels) {
  require_plain_triangles(of, "subdivided");
  require(levels >= 0 && levels <= kMaxSubdivisionLevels,
          "subdivided: levels must be in [0, " + std::to_string(kMaxSubdivisionLevels) + "]");
  const double triangles = static_cast<double>(of.mesh.size()) * std::pow(4.0, levels);
  const std::uint64_t limit = subdivision_triangle_limit();
  if (triangles > static_cast<double>(limit)) {
    const long pages = sysconf(_SC_PHYS_PAGES), page_bytes = sysconf(_SC_PAGE_SIZE);
    char memory[160] = "";
    if (pages > 0 && page_bytes > 0)
      std::snprintf(memory, sizeof memory, ", and what %.1f GiB of physical memory holds at about %.0f bytes per triangle",
                    static_cast<double>(pages) * static_cast<double>(page_bytes) / (1u << 30), kSubdivisionBytesPerTriangle);
    throw InputError("subdivided: " + std::to_string(levels) + " levels of " + std::to_string(of.mesh.size()) + " triangles would make " +
                     std::to_string(static_cast<std::uint64_t>(triangles)) + " (x4 per level), more than the limit of " +
                     std::to_string(limit) + " triangles (the least of 2^27" + memory + ")");
  }
  Scene s;
  if (levels == 0) {
    s.mesh = of.mesh;
    return s;
  }
  TriMesh m = to_openmesh(of.mesh);
  // Room for the final mesh up front: LoopT holds references to points across add_vertex, which
  // dangle when the vertex array reallocates (seen as garbage coordinates on large meshes).
  std::size_t nv = m.n_vertices(), ne = m.n_edges(), nf = m.n_faces();
  for (int l = 0; l < levels; ++l) {
    nv += ne;
    ne = 2 * ne + 3 * nf;
    nf *= 4;
  }
  m.reserve(nv, ne, nf);
  // LoopT indexes its weight table by vertex valence without a bounds check and sizes it for
  // valence < 50 by default; pole fans exceed that. Subdivision keeps old valences and gives new
  // vertices valence <= 6, so the input's largest valence bounds every level's.
  std::size_t max_valence = 0;
  for (const auto vh : m.vertices()) max_valence = std::max<std::size_t>(max_valence, m.valence(vh));
  OpenMesh::Subdivider::Uniform::LoopT<TriMesh> loop;
  loop.init_weights(std::max<std::size_t>(50, max_valence + 1));
  loop.attach(m);
  loop(static_cast<std::size_t>(levels));
  loop.detach();
  s.mesh = from_openmesh(m);
  for (const auto& v : s.mesh.vertices) require(is_finite(v), "subdivided: the subdivision produced a non-finite coordinate");
  return s;
}

Scene make_decimated(const Scene& of, std::int64_t faces) {
  require_plain_triangles(of, "decimated");
  require(faces >= 1 && faces <= kMaxTriangles, "decimated: faces must be in [1, 2^27]");
  Scene s;
  if (static_cast<std::size_t>(faces) >= of.mesh.size()) {
    s.mesh = of.mesh;
    return s;
  }
  TriMesh m = to_openmesh(of.mesh);
  m.request_vertex_status();
  m.request_edge_status();
  m.request_face_status();
  m.request_face_normals();
  m.update_face_normals();
  {
    OpenMesh::Decimater::DecimaterT<TriMesh> decimater(m);
    OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle quadric;
    decimater.add(quadric);
    decimater.module(quadric).unset_max_err();
    require(decimater.initialize(), "decimated: OpenMesh's decimater could not be initialised");
    decimater.decimate_to_faces(0, static_cast<std::size_t>(faces));
  }
  m.garbage_collection();
  s.mesh = from_openmesh(m);
  return s;
}

Scene make_instances(std::shared_ptr<const Scene> base, const InstancesConfig& c) {
  require(base != nullptr, "instances: no base scene");
  require(!base->instanced(), "instances: the base " + base->spec + " is itself instanced (one instance level)");
  require(base->primitive_count() > 0, "instances: the base " + base->spec + " is empty");
  require(c.count >= 1 && c.count <= (1 << 24), "instances: count must be in [1, 2^24] (104 bytes of instance each)");
  const Bounds3f b = base->bounds();
  const Vec3d centre(b.center());
  const double diag = length(Vec3d(b.diagonal()));
  const double spacing = 1.5 * (diag > 0 ? diag : 1.0);
  auto g = static_cast<std::int64_t>(std::ceil(std::cbrt(static_cast<double>(c.count))));
  while (g * g * g < c.count) ++g;
  std::mt19937_64 rng(c.seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> angle(0.0, 15.0 * std::numbers::pi / 180.0);
  Scene s;
  s.bases.push_back(std::move(base));
  s.instances.reserve(static_cast<std::size_t>(c.count));
  for (std::int64_t i = 0; i < c.count; ++i) {
    const Vec3d cell(static_cast<double>(i % g), static_cast<double>((i / g) % g), static_cast<double>(i / (g * g)));
    Vec3d axis(normal(rng), normal(rng), normal(rng));
    if (dot(axis, axis) < 1e-12) axis = Vec3d(0, 1, 0);
    const double a = angle(rng);
    s.instances.push_back({AffineTransform::translation(centre + cell * spacing) * AffineTransform::rotation(axis, a) *
                               AffineTransform::translation(-centre),
                           0});
  }
  return s;
}

Scene make_transformed(const Scene& of, const TransformedConfig& c) {
  require(c.scale >= 1e-30 && c.scale <= 1e30, "transformed: scale must be in [1e-30, 1e30]");
  require(length(c.axis) > 0.0 && is_finite(c.axis), "transformed: the rotation axis must be a non-zero vector");
  require(std::isfinite(c.degrees) && is_finite(c.translate), "transformed: rotate and translate must be finite");
  const AffineTransform xf = AffineTransform::translation(c.translate) *
                             AffineTransform::rotation(c.axis, c.degrees * std::numbers::pi / 180.0) *
                             AffineTransform::scaling(Vec3d(c.scale));
  Scene s;
  s.bases = of.bases;
  s.instances.reserve(of.instances.size());
  for (const auto& inst : of.instances) s.instances.push_back({xf * inst.transform, inst.base});
  s.mesh = of.mesh;
  for (auto& v : s.mesh.vertices) v = xf.apply_point(v);
  s.spheres.reserve(of.spheres.size());
  for (const auto& sp : of.spheres)
    s.spheres.push_back({xf.apply_point(sp.center), static_cast<float>(double(sp.radius) * c.scale)});
  return s;
}

}  // namespace raylab
