// The only translation unit of lib/geometry that includes CGAL: exact_predicates.h, exact_contact.h and
// exact_fallback.h.
#include "geometry/exact_predicates.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/CORE_Expr.h>
#include <CGAL/Mpzf.h>
#include <CGAL/intersections.h>

#include <array>
#include <cmath>
#include <optional>
#include <sstream>
#include <variant>
#include <vector>

#include "geometry/exact_contact.h"
#include "geometry/exact_fallback.h"
#include "geometry/float_mode.h"
#include "geometry/interval.h"
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

/// The exact parameter of the first point of the closed triangle on the ray segment [tmin,
/// tmax] (for a ray in the triangle's plane: the entry of the contact segment, or tmin when the
/// segment starts inside it), or nullopt. `epick_ray` is the ray through o and
/// exact_second_point, when there is one (a fast filtered rejection). Requires IEEE mode.
std::optional<ExactRational> triangle_contact(const Ray& r, const std::optional<Epick::Ray_3>& epick_ray,
                                              const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  // tmin = +inf (valid only with tmax = +inf) leaves no t to hit, and exact numbers cannot hold it.
  if (!is_valid(r) || std::isinf(r.tmin)) return std::nullopt;
  const Epick::Point_3 a = to_epick(p0), b = to_epick(p1), c = to_epick(p2);
  if (CGAL::collinear(a, b, c)) return std::nullopt;  // CGAL's triangle predicates require non-degenerate input
  if (epick_ray && !CGAL::do_intersect(*epick_ray, Epick::Triangle_3(a, b, c))) return std::nullopt;

  // Exact contact interval [t_enter, t_exit] along the ray (from t = 0).
  const Epeck::Point_3 o = to_epeck(r.org);
  const Epeck::Vector_3 d(r.dir.x, r.dir.y, r.dir.z);
  const Epeck::Ray_3 ray(o, d);
  const Epeck::Triangle_3 tri(to_epeck(p0), to_epeck(p1), to_epeck(p2));
  const auto contact = CGAL::intersection(ray, tri);
  if (!contact) return std::nullopt;
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
    return std::nullopt;
  }
  const ExactRational tmin(static_cast<double>(r.tmin));
  if (t_exit < tmin) return std::nullopt;
  ExactRational t = t_enter < tmin ? tmin : t_enter;
  if (std::isfinite(r.tmax) && t > ExactRational(static_cast<double>(r.tmax))) return std::nullopt;
  return t;
}

/// The exact parameter of the first point of the sphere's surface on the ray segment, or
/// nullopt; `disc` (when given) receives the sign of the discriminant (1: the line meets the
/// sphere twice, 0: tangent). Requires IEEE mode.
std::optional<ExactReal> sphere_contact(const Ray& r, const Sphere& sphere, int* disc_sign) {
  if (!is_valid(r) || std::isinf(r.tmin) || !(sphere.radius > 0.0f)) return std::nullopt;  // as above
  using R = ExactReal;
  const R ox = R(double(r.org.x)) - R(double(sphere.center.x));
  const R oy = R(double(r.org.y)) - R(double(sphere.center.y));
  const R oz = R(double(r.org.z)) - R(double(sphere.center.z));
  const R dx(double(r.dir.x)), dy(double(r.dir.y)), dz(double(r.dir.z));
  const R rad(double(sphere.radius));
  const R a = dx * dx + dy * dy + dz * dz;
  const R b = dx * ox + dy * oy + dz * oz;
  const R c = ox * ox + oy * oy + oz * oz - rad * rad;
  const R disc = b * b - a * c;
  const int sign = disc.sign();
  if (disc_sign) *disc_sign = sign;
  if (sign < 0) return std::nullopt;
  const R root = sqrt(disc);
  const R tmin(double(r.tmin));
  R t = (-b - root) / a;
  if (t < tmin) t = (-b + root) / a;
  if (t < tmin) return std::nullopt;
  if (std::isfinite(r.tmax) && t > R(double(r.tmax))) return std::nullopt;
  return t;
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

bool& exact_path_taken_on_this_thread() {
  thread_local bool taken = false;
  return taken;
}

ExactFirstHit::ExactFirstHit(const Ray& ray) : impl_(std::make_unique<Impl>(ray)) {
  exact_path_taken_on_this_thread() = true;
}
ExactFirstHit::~ExactFirstHit() = default;
ExactFirstHit::ExactFirstHit(ExactFirstHit&&) noexcept = default;
ExactFirstHit& ExactFirstHit::operator=(ExactFirstHit&&) noexcept = default;

bool ExactFirstHit::offer_triangle(unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const auto t = triangle_contact(s.ray, s.epick_ray, p0, p1, p2);
  if (!t || !s.accept(ExactTime(*t), prim)) return false;
  s.best_is_sphere = false;
  s.b0 = p0; s.b1 = p1; s.b2 = p2;
  return true;
}

bool ExactFirstHit::offer_sphere(unsigned prim, const Sphere& sphere) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const auto t = sphere_contact(s.ray, sphere, nullptr);
  if (!t || !s.accept(ExactTime(*t), prim)) return false;
  s.best_is_sphere = true;
  s.best_sphere = sphere;
  return true;
}

bool ExactFirstHit::has_hit() const { return impl_->has; }

namespace {

/// (u, v) of the first hit at parameter t (approximately) on a sphere or triangle (b0, b1, b2).
void set_hit_uv(Hit& h, const Ray& ray, double t, bool sphere, const Sphere& s, const Vec3f& b0, const Vec3f& b1,
                const Vec3f& b2) {
  const Vec3d p = Vec3d(ray.org) + Vec3d(ray.dir) * t;
  if (sphere) {
    float tt, u, v;
    Ray probe = ray;
    if (intersect_sphere(s, probe, ray.tmin, std::numeric_limits<float>::infinity(), tt, u, v)) {
      h.u = u;
      h.v = v;
    }
    return;
  }
  // Barycentrics of p by areas projected on the dominant plane of the normal.
  const Vec3d a(b0), b(b1), c(b2);
  const Vec3d n = cross(b - a, c - a);
  const int k = max_abs_axis(n), i = (k + 1) % 3, j = (k + 2) % 3;
  auto area2 = [&](const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    return (p1[i] - p0[i]) * (p2[j] - p0[j]) - (p1[j] - p0[j]) * (p2[i] - p0[i]);
  };
  const double total = area2(a, b, c);
  h.u = static_cast<float>(area2(a, p, c) / total);
  h.v = static_cast<float>(area2(a, b, p) / total);
}

/// Doubles around an exact time (IEEE mode).
std::pair<double, double> time_interval(const ExactTime& t) {
  return t.index() == 0 ? CGAL::to_interval(CGAL::exact(std::get<0>(t))) : CGAL::to_interval(std::get<1>(t));
}

}  // namespace

Hit ExactFirstHit::hit() const {
  const Impl& s = *impl_;
  if (!s.has) return {};
  Hit h = s.best;
  set_hit_uv(h, s.ray, s.best_t_approx, s.best_is_sphere, s.best_sphere, s.b0, s.b1, s.b2);
  return h;
}

float ExactFirstHit::closest_upper_bound() const {
  const Impl& s = *impl_;
  if (!s.has) return s.ray.tmax;
  // The double approximation is within a relative 2^-50 or so of the exact value; widen generously.
  const double up = s.best_t_approx + std::abs(s.best_t_approx) * 1e-6 + 1e-30;
  return std::nextafter(static_cast<float>(up), std::numeric_limits<float>::infinity());
}

void ExactFirstHit::best_time_bounds(float& lo, float& hi) const {
  const Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const std::pair<double, double> i = time_interval(s.best_t);
  lo = float_down(i.first);
  hi = float_up(i.second);
}

int ExactFirstHit::compare_time(const ExactFirstHit& other) const {
  const FloatModeScope ieee(false);
  return compare_times(impl_->best_t, other.impl_->best_t);
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


// ---- ExactFallback (exact_fallback.h) --------------------------------------------------------

namespace {

/// t = n / d exactly, d > 0 (CGAL::Mpzf: exact binary floats, +, -, × exact).
struct Fraction {
  CGAL::Mpzf n, d;
};
using FallbackTime = std::variant<Fraction, ExactTime>;

ExactRational to_rational(const CGAL::Mpzf& x) {
  mpq_t q;
  mpq_init(q);
  x.export_to_mpq_t(q);
  const ExactRational r{ExactRational::Exact_type(q)};
  mpq_clear(q);
  return r;
}

ExactTime as_exact_time(const FallbackTime& t) {
  if (t.index() == 1) return std::get<1>(t);
  const Fraction& f = std::get<0>(t);
  return ExactTime(to_rational(f.n) / to_rational(f.d));
}

int compare_fallback_times(const FallbackTime& a, const FallbackTime& b) {
  if (a.index() == 0 && b.index() == 0) {
    const Fraction &x = std::get<0>(a), &y = std::get<0>(b);
    const CGAL::Mpzf l = x.n * y.d, r = y.n * x.d;
    return l < r ? -1 : (r < l ? 1 : 0);
  }
  return compare_times(as_exact_time(a), as_exact_time(b));
}

/// The exact t of the first contact of the closed triangle with the ray segment, as
/// ExactFallback computes it: for a line crossing the triangle's plane, with the Plücker signs
/// and the fraction t = (a'·(b'×c')) / (d·n) in Mpzf (a' = p0 - o, ...; n = (p1-p0)×(p2-p0)); for
/// a line in (or parallel to) the plane, triangle_contact's constructions. Requires IEEE mode.
std::optional<FallbackTime> fallback_triangle_contact(const Ray& r, const std::optional<Epick::Ray_3>& epick_ray,
                                                      const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  if (!is_valid(r) || std::isinf(r.tmin)) return std::nullopt;
  if (CGAL::collinear(to_epick(p0), to_epick(p1), to_epick(p2))) return std::nullopt;
  // With a' = a - o etc.: the line meets the closed triangle iff the Plücker sides
  // d·(a'×b'), d·(b'×c'), d·(c'×a') do not have opposite signs; their sum is d·n,
  // n = (b-a)×(c-a), and the contact's t = (a'·(b'×c')) / (d·n). Exact in Mpzf.
  using F = CGAL::Mpzf;
  const F ox(double(r.org.x)), oy(double(r.org.y)), oz(double(r.org.z));
  const F dx(double(r.dir.x)), dy(double(r.dir.y)), dz(double(r.dir.z));
  const F ax = F(double(p0.x)) - ox, ay = F(double(p0.y)) - oy, az = F(double(p0.z)) - oz;
  const F bx = F(double(p1.x)) - ox, by = F(double(p1.y)) - oy, bz = F(double(p1.z)) - oz;
  const F cx = F(double(p2.x)) - ox, cy = F(double(p2.y)) - oy, cz = F(double(p2.z)) - oz;
  auto side = [&](const F& ux, const F& uy, const F& uz, const F& vx, const F& vy, const F& vz) {
    return dx * (uy * vz - uz * vy) + dy * (uz * vx - ux * vz) + dz * (ux * vy - uy * vx);
  };
  const F sab = side(ax, ay, az, bx, by, bz), sca = side(cx, cy, cz, ax, ay, az);
  const F bcx = by * cz - bz * cy, bcy = bz * cx - bx * cz, bcz = bx * cy - by * cx;
  const F sbc = dx * bcx + dy * bcy + dz * bcz;
  F d = sab + sbc + sca;
  if (CGAL::is_zero(d)) {  // the line in (or parallel to) the triangle's plane: the constructions
    const auto t = triangle_contact(r, epick_ray, p0, p1, p2);
    if (!t) return std::nullopt;
    return FallbackTime(ExactTime(*t));
  }
  const int sa = sab.sign(), sb = sbc.sign(), sc = sca.sign();
  if ((sa > 0 || sb > 0 || sc > 0) && (sa < 0 || sb < 0 || sc < 0)) return std::nullopt;
  F n = ax * bcx + ay * bcy + az * bcz;
  if (d.sign() < 0) n = -n, d = -d;
  if (n < F(double(r.tmin)) * d) return std::nullopt;
  if (std::isfinite(r.tmax) && n > F(double(r.tmax)) * d) return std::nullopt;
  return FallbackTime(Fraction{n, d});
}

}  // namespace

struct ExactFallback::Impl {
  Ray ray;
  std::optional<Epick::Ray_3> epick_ray;
  bool has = false;
  FallbackTime best_t;
  Hit best;
  bool best_is_sphere = false;
  Vec3f b0, b1, b2;
  Sphere best_sphere;

  explicit Impl(const Ray& r) : ray(r) {
    const FloatModeScope ieee(false);
    Vec3d second;
    if (exact_second_point(r, second)) epick_ray.emplace(to_epick(r.org), Epick::Point_3(second.x, second.y, second.z));
  }

  bool accept(const FallbackTime& t, unsigned prim) {
    if (has) {
      const int c = compare_fallback_times(t, best_t);
      if (c > 0 || (c == 0 && prim >= best.prim)) return false;
    }
    has = true;
    best_t = t;
    best.prim = prim;
    return true;
  }
};

ExactFallback::ExactFallback(const Ray& ray) : impl_(std::make_unique<Impl>(ray)) {
  exact_path_taken_on_this_thread() = true;
}
ExactFallback::~ExactFallback() = default;
ExactFallback::ExactFallback(ExactFallback&&) noexcept = default;
ExactFallback& ExactFallback::operator=(ExactFallback&&) noexcept = default;

bool ExactFallback::offer_triangle(unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const auto t = fallback_triangle_contact(s.ray, s.epick_ray, p0, p1, p2);
  if (!t || !s.accept(*t, prim)) return false;
  s.best_is_sphere = false;
  s.b0 = p0, s.b1 = p1, s.b2 = p2;
  return true;
}

bool ExactFallback::offer_sphere(unsigned prim, const Sphere& sphere) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const auto t = sphere_contact(s.ray, sphere, nullptr);
  if (!t || !s.accept(FallbackTime(ExactTime(*t)), prim)) return false;
  s.best_is_sphere = true;
  s.best_sphere = sphere;
  return true;
}

bool ExactFallback::has_hit() const { return impl_->has; }

void ExactFallback::best_time_bounds(double& lo, double& hi) const {
  const Impl& s = *impl_;
  const FloatModeScope ieee(false);
  if (s.best_t.index() == 0) {
    const Fraction& f = std::get<0>(s.best_t);
    const auto n = f.n.to_interval(), d = f.d.to_interval();
    const Interval q = Interval{n.first, n.second} / Interval{d.first, d.second};
    lo = q.lo, hi = q.hi;
    return;
  }
  const auto i = time_interval(std::get<1>(s.best_t));
  lo = i.first, hi = i.second;
}

Hit ExactFallback::hit() const {
  const Impl& s = *impl_;
  if (!s.has) return {};
  double lo, hi;
  best_time_bounds(lo, hi);
  Hit h = s.best;
  h.t = static_cast<float>(0.5 * (lo + hi));
  set_hit_uv(h, s.ray, 0.5 * (lo + hi), s.best_is_sphere, s.best_sphere, s.b0, s.b1, s.b2);
  return h;
}

// ---- ExactContactClassifier (exact_contact.h) ----------------------------------------------

const char* contact_name(Contact c) {
  switch (c) {
    case Contact::none: return "none";
    case Contact::crossing: return "crossing";
    case Contact::touching: return "touching";
    case Contact::on_surface: return "on_surface";
  }
  return "?";
}

struct ExactContactClassifier::Impl {
  Ray ray;
  std::optional<Epick::Ray_3> epick_ray;
  bool has = false;
  FallbackTime best_t;
  std::vector<std::array<Vec3f, 3>> tied_triangles;  ///< the triangles first met at best_t
  bool tied_transversal_sphere = false;              ///< a sphere met twice by the line, first at best_t

  explicit Impl(const Ray& r) : ray(r) {
    Vec3d second;
    if (exact_second_point(r, second)) epick_ray.emplace(to_epick(r.org), Epick::Point_3(second.x, second.y, second.z));
  }

  /// -1: t is before the current first contact (which it replaces), 0: a tie, 1: after.
  int offer(const FallbackTime& t) {
    const int c = has ? compare_fallback_times(t, best_t) : -1;
    if (c < 0) {
      has = true;
      best_t = t;
      tied_triangles.clear();
      tied_transversal_sphere = false;
    }
    return c;
  }
};

ExactContactClassifier::ExactContactClassifier(const Ray& ray) : impl_(std::make_unique<Impl>(ray)) {}
ExactContactClassifier::~ExactContactClassifier() = default;
ExactContactClassifier::ExactContactClassifier(ExactContactClassifier&&) noexcept = default;
ExactContactClassifier& ExactContactClassifier::operator=(ExactContactClassifier&&) noexcept = default;

void ExactContactClassifier::offer_triangle(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  const auto t = fallback_triangle_contact(s.ray, s.epick_ray, p0, p1, p2);
  if (t && s.offer(*t) <= 0) s.tied_triangles.push_back({p0, p1, p2});
}

void ExactContactClassifier::offer_sphere(const Sphere& sphere) {
  Impl& s = *impl_;
  const FloatModeScope ieee(false);
  int disc = 0;
  const auto t = sphere_contact(s.ray, sphere, &disc);
  if (t && s.offer(FallbackTime(ExactTime(*t))) <= 0) s.tied_transversal_sphere |= disc > 0;
}

double ExactContactClassifier::first_t() const {
  if (!impl_->has) return INFINITY;
  const FloatModeScope ieee(false);
  const auto& t = impl_->best_t;
  if (t.index() == 0) return CGAL::to_double(std::get<0>(t).n) / CGAL::to_double(std::get<0>(t).d);
  return approximate(std::get<1>(t));
}

namespace {

/// A direction in the projection plane, exact (CGAL::Mpzf: the projection below needs no division).
struct Dir2 {
  CGAL::Mpzf x, y;
};
CGAL::Mpzf cross2(const Dir2& a, const Dir2& b) { return a.x * b.y - a.y * b.x; }
bool same_direction(const Dir2& a, const Dir2& b) {
  return CGAL::is_zero(cross2(a, b)) && (a.x * b.x + a.y * b.y).sign() > 0;
}

/// Projection along a ray's direction d, scaled by d_kz (kz its largest axis): q -> (d_kz·(q_kx -
/// o_kx) - d_kx·(q_kz - o_kz), d_kz·(q_ky - o_ky) - d_ky·(q_kz - o_kz)), where every point of the ray
/// projects to 0. The scale multiplies every cross and dot product of projected directions by
/// d_kz² > 0, so their signs, all that is read, are those of the unscaled projection; without a
/// division the projection is exact in Mpzf.
class RayProjection {
 public:
  explicit RayProjection(const Ray& r)
      : kz_(max_abs_axis(r.dir)), kx_((kz_ + 1) % 3), ky_((kz_ + 2) % 3), dx_(double(r.dir[kx_])),
        dy_(double(r.dir[ky_])), dz_(double(r.dir[kz_])), ox_(double(r.org[kx_])), oy_(double(r.org[ky_])),
        oz_(double(r.org[kz_])) {}

  Dir2 operator()(const Vec3f& q) const {
    const CGAL::Mpzf z = CGAL::Mpzf(double(q[kz_])) - oz_;
    return Dir2{dz_ * (CGAL::Mpzf(double(q[kx_])) - ox_) - dx_ * z, dz_ * (CGAL::Mpzf(double(q[ky_])) - oy_) - dy_ * z};
  }

 private:
  int kz_, kx_, ky_;
  CGAL::Mpzf dx_, dy_, dz_, ox_, oy_, oz_;
};

/// A closed angular sector at the contact point, counter-clockwise from `s` to `e`; a
/// half-plane (angle π) when `half`.
struct Sector {
  Dir2 s, e;
  bool half;
  bool strictly_contains(const Dir2& v) const {
    if (cross2(s, v).sign() <= 0) return false;
    return half || cross2(v, e).sign() > 0;
  }
};

/// Whether the closed sectors cover every direction: each open arc left uncovered would begin
/// and end at a sector boundary, so it suffices that the directions just counter-clockwise and
/// just clockwise of every boundary direction are covered.
bool covers_circle(const std::vector<Sector>& sectors) {
  if (sectors.empty()) return false;
  auto covered = [&](const Dir2& v, bool ccw_side) {
    for (const Sector& q : sectors)
      if (q.strictly_contains(v) || same_direction(v, ccw_side ? q.s : q.e)) return true;
    return false;
  };
  for (const Sector& q : sectors)
    for (const Dir2* v : {&q.s, &q.e})
      if (!covered(*v, true) || !covered(*v, false)) return false;
  return true;
}

}  // namespace

Contact ExactContactClassifier::contact() const {
  const Impl& s = *impl_;
  if (!s.has) return Contact::none;
  const FloatModeScope ieee(false);
  if (compare_fallback_times(s.best_t, FallbackTime(Fraction{CGAL::Mpzf(double(s.ray.tmin)), CGAL::Mpzf(1.0)})) == 0)
    return Contact::on_surface;
  if (s.tied_transversal_sphere) return Contact::crossing;
  const RayProjection project(s.ray);
  auto minus = [](const Dir2& a, const Dir2& b) { return Dir2{a.x - b.x, a.y - b.y}; };
  std::vector<Sector> sectors;
  for (const auto& tri : s.tied_triangles) {
    const Dir2 a = project(tri[0]), b = project(tri[1]), c = project(tri[2]);
    const int sigma = cross2(minus(b, a), minus(c, a)).sign();
    if (sigma == 0) continue;  // the ray lies in the triangle's plane: it covers no neighbourhood
    // Sides of the ray's projection (the origin 0) relative to the edges, positive inside.
    const Dir2 zero{CGAL::Mpzf(0.0), CGAL::Mpzf(0.0)};
    const Dir2 v[3] = {a, b, c};
    int on_edge[3], zeros = 0;
    for (int i = 0; i < 3; ++i) {
      const Dir2& p = v[i];
      const Dir2& q = v[(i + 1) % 3];
      on_edge[i] = CGAL::is_zero(cross2(minus(q, p), minus(zero, p)));
      zeros += on_edge[i];
    }
    if (zeros == 0) return Contact::crossing;  // inside the projected triangle: a transversal hit
    if (zeros == 1) {                          // on edge i: the half-plane on the third vertex's side
      const int i = on_edge[0] ? 0 : (on_edge[1] ? 1 : 2);
      const Dir2 e = minus(v[(i + 1) % 3], v[i]);
      const Dir2 back{-e.x, -e.y};
      sectors.push_back(sigma > 0 ? Sector{e, back, true} : Sector{back, e, true});
    } else {  // at the vertex shared by the two edges through it
      const int k = !on_edge[0] ? 0 : (!on_edge[1] ? 1 : 2);  // the edge not through it: the vertex is k+2
      const int at = (k + 2) % 3;
      const Dir2 to_next = minus(v[(at + 1) % 3], v[at]), to_prev = minus(v[(at + 2) % 3], v[at]);
      sectors.push_back(sigma > 0 ? Sector{to_next, to_prev, false} : Sector{to_prev, to_next, false});
    }
  }
  return covers_circle(sectors) ? Contact::crossing : Contact::touching;
}

}  // namespace raylab
