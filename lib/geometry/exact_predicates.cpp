// The only translation unit of lib/geometry that includes CGAL (see exact_predicates.h).
#include "geometry/exact_predicates.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/CORE_Expr.h>
#include <CGAL/intersections.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <variant>

#include "geometry/float_mode.h"
#include "geometry/triangle_mesh.h"

namespace raylab {
namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;
using ExactRational = Epeck::FT;
using ExactReal = CORE::Expr;

Epick::Point_3 to_epick(const Vec3f& p) { return {p.x, p.y, p.z}; }
Epeck::Point_3 to_epeck(const Vec3f& p) { return {p.x, p.y, p.z}; }

ExactReal to_real(const ExactRational& q) {
  std::ostringstream s;
  s << CGAL::exact(q);  // "num/den" or "num"
  return ExactReal(CORE::BigRat(s.str().c_str()));
}

using ExactTime = std::variant<ExactRational, ExactReal>;

int compare_times(const ExactTime& a, const ExactTime& b) {
  if (a.index() == 0 && b.index() == 0) {
    const auto r = CGAL::compare(std::get<0>(a), std::get<0>(b));
    return r == CGAL::SMALLER ? -1 : (r == CGAL::LARGER ? 1 : 0);
  }
  const ExactReal x = a.index() == 0 ? to_real(std::get<0>(a)) : std::get<1>(a);
  const ExactReal y = b.index() == 0 ? to_real(std::get<0>(b)) : std::get<1>(b);
  return x.cmp(y);
}

double approximate(const ExactTime& t) {
  return t.index() == 0 ? CGAL::to_double(std::get<0>(t)) : std::get<1>(t).doubleValue();
}

}  // namespace

bool exact_second_point(const Ray& ray, Vec3d& second) {
  if (!is_valid(ray)) return false;
  const FloatModeScope ieee(false);
  const double dmax = max_component(abs(Vec3d(ray.dir))), omax = max_component(abs(Vec3d(ray.org)));
  int k0 = 0;
  if (omax > 0.0) k0 = std::ilogb(omax) - std::ilogb(dmax);
  for (int step = 0; step <= 128; ++step) {
    const int k = k0 + (step % 2 == 0 ? step / 2 : -(step + 1) / 2);
    bool exact = true;
    for (int a = 0; a < 3 && exact; ++a) {
      const double o = ray.org[a], e = std::ldexp(double(ray.dir[a]), k);
      const double s = o + e;
      // Knuth's TwoSum: the rounding error of o + e, exactly.
      const double bv = s - o, av = s - bv;
      exact = std::isfinite(s) && (o - av) + (e - bv) == 0.0;
      second[a] = s;
    }
    if (exact) return true;
  }
  return false;
}

struct ExactFirstHit::Impl {
  Ray ray;
  /// The ray through o and exact_second_point, when there is one.
  std::optional<Epick::Ray_3> epick_ray;
  bool has = false;
  ExactTime best_t;
  double best_t_approx = 0.0;
  Hit best;
  // Geometry of the best primitive, to compute (u, v) once at the end.
  bool best_is_sphere = false;
  Vec3f b0, b1, b2;
  Sphere best_sphere;

  explicit Impl(const Ray& r)
      : ray(r) {
    Vec3d second;
    if (exact_second_point(r, second)) epick_ray.emplace(to_epick(r.org), Epick::Point_3(second.x, second.y, second.z));
  }

  bool accept(const ExactTime& t, unsigned prim) {
    if (has) {
      const int c = compare_times(t, best_t);
      if (c > 0 || (c == 0 && prim >= best.prim)) return false;
    }
    has = true;
    best_t = t;
    best_t_approx = approximate(t);
    best.prim = prim;
    best.t = static_cast<float>(best_t_approx);
    return true;
  }
};

ExactFirstHit::ExactFirstHit(const Ray& ray) : impl_(std::make_unique<Impl>(ray)) {}
ExactFirstHit::~ExactFirstHit() = default;
ExactFirstHit::ExactFirstHit(ExactFirstHit&&) noexcept = default;
ExactFirstHit& ExactFirstHit::operator=(ExactFirstHit&&) noexcept = default;

bool ExactFirstHit::offer_triangle(unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  Impl& s = *impl_;
  // tmin = +inf (valid only with tmax = +inf) leaves no t to hit, and exact numbers cannot hold it.
  if (!is_valid(s.ray) || std::isinf(s.ray.tmin)) return false;
  const FloatModeScope ieee(false);
  const Epick::Point_3 a = to_epick(p0), b = to_epick(p1), c = to_epick(p2);
  if (CGAL::collinear(a, b, c)) return false;  // CGAL's triangle predicates require non-degenerate input
  if (s.epick_ray && !CGAL::do_intersect(*s.epick_ray, Epick::Triangle_3(a, b, c))) return false;

  // Exact contact interval [t_enter, t_exit] along the ray (from t = 0).
  const Epeck::Point_3 o = to_epeck(s.ray.org);
  const Epeck::Vector_3 d(s.ray.dir.x, s.ray.dir.y, s.ray.dir.z);
  const Epeck::Ray_3 ray(o, d);
  const Epeck::Triangle_3 tri(to_epeck(p0), to_epeck(p1), to_epeck(p2));
  const auto contact = CGAL::intersection(ray, tri);
  if (!contact) return false;
  const ExactRational dd = d * d;
  auto param = [&](const Epeck::Point_3& p) { return ((p - o) * d) / dd; };
  ExactRational t_enter, t_exit;
  if (const auto* p = boost::get<Epeck::Point_3>(&*contact)) {
    t_enter = t_exit = param(*p);
  } else if (const auto* seg = boost::get<Epeck::Segment_3>(&*contact)) {
    t_enter = param(seg->source());
    t_exit = param(seg->target());
    if (t_exit < t_enter) std::swap(t_enter, t_exit);
  } else {
    return false;
  }
  const ExactRational tmin(static_cast<double>(s.ray.tmin));
  if (t_exit < tmin) return false;
  ExactRational t = t_enter < tmin ? tmin : t_enter;
  if (std::isfinite(s.ray.tmax) && t > ExactRational(static_cast<double>(s.ray.tmax))) return false;
  if (!s.accept(ExactTime(t), prim)) return false;
  s.best_is_sphere = false;
  s.b0 = p0; s.b1 = p1; s.b2 = p2;
  return true;
}

bool ExactFirstHit::offer_sphere(unsigned prim, const Sphere& sphere) {
  Impl& s = *impl_;
  if (!is_valid(s.ray) || std::isinf(s.ray.tmin) || !(sphere.radius > 0.0f)) return false;  // as above
  const FloatModeScope ieee(false);
  using R = ExactReal;
  const R ox = R(double(s.ray.org.x)) - R(double(sphere.center.x));
  const R oy = R(double(s.ray.org.y)) - R(double(sphere.center.y));
  const R oz = R(double(s.ray.org.z)) - R(double(sphere.center.z));
  const R dx(double(s.ray.dir.x)), dy(double(s.ray.dir.y)), dz(double(s.ray.dir.z));
  const R r(double(sphere.radius));
  const R a = dx * dx + dy * dy + dz * dz;
  const R b = dx * ox + dy * oy + dz * oz;
  const R c = ox * ox + oy * oy + oz * oz - r * r;
  const R disc = b * b - a * c;
  if (disc.sign() < 0) return false;
  const R root = sqrt(disc);
  const R tmin(double(s.ray.tmin));
  R t = (-b - root) / a;
  if (t < tmin) t = (-b + root) / a;
  if (t < tmin) return false;
  if (std::isfinite(s.ray.tmax) && t > R(double(s.ray.tmax))) return false;
  if (!s.accept(ExactTime(t), prim)) return false;
  s.best_is_sphere = true;
  s.best_sphere = sphere;
  return true;
}

bool ExactFirstHit::has_hit() const { return impl_->has; }

Hit ExactFirstHit::hit() const {
  const Impl& s = *impl_;
  if (!s.has) return {};
  Hit h = s.best;
  const Vec3d p = Vec3d(s.ray.org) + Vec3d(s.ray.dir) * s.best_t_approx;
  if (s.best_is_sphere) {
    float t, u, v;
    Ray probe = s.ray;
    if (intersect_sphere(s.best_sphere, probe, s.ray.tmin, std::numeric_limits<float>::infinity(), t, u, v)) {
      h.u = u;
      h.v = v;
    }
  } else {
    // Barycentrics of p by areas projected on the dominant plane of the normal.
    const Vec3d a(s.b0), b(s.b1), c(s.b2);
    const Vec3d n = cross(b - a, c - a);
    const int k = max_abs_axis(n), i = (k + 1) % 3, j = (k + 2) % 3;
    auto area2 = [&](const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
      return (p1[i] - p0[i]) * (p2[j] - p0[j]) - (p1[j] - p0[j]) * (p2[i] - p0[i]);
    };
    const double total = area2(a, b, c);
    h.u = static_cast<float>(area2(a, p, c) / total);
    h.v = static_cast<float>(area2(a, b, p) / total);
  }
  return h;
}

float ExactFirstHit::closest_upper_bound() const {
  const Impl& s = *impl_;
  if (!s.has) return s.ray.tmax;
  // The double approximation is within a relative 2^-50 or so of the exact value; widen generously.
  const double up = s.best_t_approx + std::abs(s.best_t_approx) * 1e-6 + 1e-30;
  return std::nextafter(static_cast<float>(up), std::numeric_limits<float>::infinity());
}

int exact_orientation(const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d) {
  const FloatModeScope ieee(false);
  const auto o = CGAL::orientation(to_epick(a), to_epick(b), to_epick(c), to_epick(d));
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

bool exact_triangle_intersects_box(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
  const FloatModeScope ieee(false);
  const CGAL::Bbox_3 bb(box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z);
  const Epick::Point_3 a = to_epick(p0), b = to_epick(p1), c = to_epick(p2);
  if (!CGAL::collinear(a, b, c)) return CGAL::do_intersect(Epick::Triangle_3(a, b, c), bb);
  // Degenerate: the triangle is the segment between its two farthest vertices (or a point).
  if (a == b && b == c) return CGAL::do_intersect(a, Epick::Iso_cuboid_3(bb));
  const Epick::Point_3* ends[3][2] = {{&a, &b}, {&b, &c}, {&a, &c}};
  bool hit = false;
  for (auto& e : ends)
    if (*e[0] != *e[1]) hit = hit || CGAL::do_intersect(Epick::Segment_3(*e[0], *e[1]), bb);
  return hit;
}

bool is_degenerate_exact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  const FloatModeScope ieee(false);
  return CGAL::collinear(to_epick(p0), to_epick(p1), to_epick(p2));
}

}  // namespace raylab
