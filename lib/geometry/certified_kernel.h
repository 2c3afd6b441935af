#pragma once
/// The certified kernel: exact first hits at (nearly) float speed. The float watertight test of
/// Woop, Benthin and Wald ("Watertight Ray/Triangle Intersection", JCGT 2(1) 2013) runs first,
/// with a rigorous forward error bound on its edge functions (after the static filters of
/// Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
/// Predicates", DCG 18 1997, and of CGAL's filtered kernels); where the bound cannot certify a
/// sign, whether a hit lies in [tmin, tmax], or which of two hits comes first, the decision is
/// made by the exact predicates (ExactFallback, exact_fallback.h: CGAL's filtered predicates and
/// exact arithmetic, coplanar rays included). The first hit it reports therefore has the exact first-hit parameter t* of the
/// primitives offered to it: the same primitive as the exact oracle, or another whose exact t
/// equals t*. Hits are accepted on the closed interval tmin <= t <= tmax (the oracle's rule;
/// `kClosedInterval` tells accelerators not to widen tmax for any-hit queries).
///
/// Error bound of the edge functions (the derivation the constants below come from). Notation:
/// u = 2^-24 (unit roundoff, round to nearest); μ = 2^-126 (flush to zero replaces a result
/// below 2^-126 by 0, and denormals-are-zero reads a subnormal input as 0: either is an absolute
/// error below μ). Every float operation satisfies fl(x∘y) = (x∘y)(1+δ) + η with |δ| <= u,
/// |η| <= μ; the build compiles with -ffp-contract=off, so each written operation is one rounding
/// (no FMA contraction) and the SIMD packet version (packed_triangles_simd.h) performs the same
/// operations. For a vertex q the kernel computes a_i = fl(q_i - o_i) and the sheared
///   Q̂x = fl(a_kx - fl(sx·a_kz)),  Q̂y = fl(a_ky - fl(sy·a_kz)),  sx = fl(d_kx/d_kz), |sx| <= 1,
/// of the exact Qx = (q_kx - o_kx) - (d_kx/d_kz)(q_kz - o_kz). Summing the four roundings (and
/// the perturbation of sx by a flushed d_kx, at most μ/|d_kz| <= 2^-66 because the filter
/// requires |d_kz| >= 2^-60) gives, with X, Y, Z the computed |a_kx|, |a_ky|, |a_kz|,
///   |Q̂x - Qx| <= (2uX + 4uZ)(1 + 4u) + 2^-66·Z + 9μ,
/// and since X <= |Q̂x| + Z(1+u) (likewise Y), both errors are below
///   E_q = 5u·(S_q + 3·Z_q) + 16μ,   S_q = |Q̂x| + |Q̂y|.
/// An edge function U = Cx·By - Cy·Bx, computed as Û = fl(fl(Ĉx·B̂y) - fl(Ĉy·B̂x)), then satisfies
///   |Û - U| <= E_b·S_c + E_c·S_b + 2·E_b·E_c + 2.1u·S_b·S_c + 4μ
/// (the first terms from the inputs' errors, the fourth from the three roundings of Û). With
/// S = max_q S_q and Z = max_q Z_q over the triangle's three vertices, one bound serves U, V, W:
///   |Û - U| <= 12.2u·S² + 30.1u·S·Z + 450u²·Z² + μ·(33·S + 5) + (smaller terms),
/// which edge_bound() rounds up to B = S·(14u·S + 32u·Z) + 2^-38·Z² + 2^-119·(1 + S + Z): the
/// larger constants absorb the rounding of B's own evaluation (six operations, a relative
/// 6u), and the μ term the flushing of B's own products. Overflow makes B infinite and every
/// comparison with it false, NaN likewise: such a triangle goes to the exact path.
///
/// Decisions, in three stages (the filters of CGAL's kernels: static, dynamic, exact):
///  1. float: a sign is certain when |Û| > B. Two certain opposite signs: the line misses the
///     closed triangle. Three certain equal signs: it crosses the triangle's interior, det =
///     U+V+W is certainly non-zero, and t = (U·az + V·bz + W·cz)/det with az = (q_kz - o_kz)/d_kz
///     is enclosed in double interval arithmetic (interval.h) from Û ± B; the hit is certain
///     when that interval lies in [tmin, tmax] and comes before the current first hit's. Where
///     it cannot be, for a triangle that reaches the origin's depth (the one a secondary ray
///     starts from, crossed just before or after the origin), t is enclosed from the plane's
///     determinants in double with a static bound (plane_crossing_t, Shewchuk's orient3d filter);
///     the same enclosure rejects a triangle of uncertain edge signs whose plane is met outside
///     [tmin, tmax] before the double stage does.
///  2. double: whatever stage 1 leaves open (a small edge function, a t near an interval end or
///     near the current first hit's) is recomputed in double interval arithmetic from the float
///     inputs, which encloses U, V, W and t about 2^29 times more tightly.
///  3. exact: what stage 2 leaves open (a line through an edge or a vertex, or in the triangle's
///     plane; two hits at the same or nearly the same t) goes to ExactFallback, an implementation
///     of ExactFirstHit's rule apart from the one the exact oracle uses.
///
/// Spheres: the discriminant and roots of |o + t·d - c|² = r² are enclosed in double interval
/// arithmetic from the float inputs (widened by μ for DAZ); uncertain signs or interval ends go
/// to the exact path (exact algebraic roots).
///
/// Invalid rays never reach a kernel (AggregateBase rejects them); degenerate triangles have
/// U = V = W = 0 exactly in every rounding (Û, V̂, Ŵ are then 0 up to μ-sized flushes), never
/// certify, and the exact path rejects them before any CGAL precondition.
#include <algorithm>
#include <cmath>
#include <memory>

#include "geometry/exact_fallback.h"
#include "geometry/exact_predicates.h"
#include "geometry/interval.h"
#include "geometry/triangle_kernels.h"

namespace raylab {

struct CertifiedKernel {
  /// Accepts t in the closed [tmin, tmax]: any-hit queries pass their ray unchanged.
  static constexpr bool kClosedInterval = true;

  /// A primitive's geometry, kept for the current first hit so that an exact comparison can
  /// be handed both contenders.
  struct Shape {
    bool sphere = false;
    Vec3f p0, p1, p2;
    Sphere s;
  };

  struct Context {
    Ray ray;
    int kx = 0, ky = 1, kz = 2;
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    /// The float filter's preconditions hold (|d_kz| >= 2^-60): otherwise the double stage decides.
    bool filter = false;
    /// The depth cull's preconditions hold as well (|d_kz| <= 2^100, so that sz = 1/d_kz is normal).
    bool cull = false;
    /// A float >= the exact t of the current first hit, or tmax while there is none (best_upper).
    float upper = 0.0f;
    // The current first hit: its exact t lies in [lo, hi]; reach is closest() for traversal.
    bool has = false;
    /// [lo, hi] comes from the double stage or the exact path (not from the float filter).
    bool tight = false;
    /// The exact path holds the current first hit (or another at the same exact t).
    bool best_in_exact = false;
    double lo = 0.0, hi = 0.0;
    float reach = 0.0f;
    unsigned prim = kInvalidId;
    TriangleHit best;
    Shape shape;
    std::unique_ptr<ExactFallback> exact;  ///< created on the first exact decision of the ray
  };

  /// An upper bound on t that traversal may prune against: `t` (the best hit's certified upper
  /// bound, or tmax) raised by a relative 2^-20. Box and plane entry distances are computed
  /// with at most three roundings (relative error γ3 < 2^-22, bounds.h), so an entry whose exact
  /// value is <= t is computed <= reach_of(t) and is not pruned.
  static float reach_of(float t) { return t * (1.0f + 0x1p-19f) + 0x1p-120f; }

  static Context prepare(const Ray& ray) {
    Context c;
    prepare(c, ray);
    return c;
  }
  /// prepare(ray) into an existing context (a previous ray's, or a new one), without moving a
  /// whole Context: prepare_context() picks this form.
  static void prepare(Context& c, const Ray& ray) {
    c.ray = ray;
    set_watertight_shear(c, ray.dir);
    c.filter = std::abs(ray.dir[c.kz]) >= 0x1p-60f && std::isfinite(c.sz);
    c.cull = c.filter && std::abs(ray.dir[c.kz]) <= 0x1p100f;
    c.upper = ray.tmax;
    c.reach = reach_of(ray.tmax);
    c.has = c.tight = c.best_in_exact = false;
    c.prim = kInvalidId;
    c.exact.reset();
  }
  static float closest(const Context& c) { return c.reach; }
  /// A float >= the exact t of the current first hit, or tmax while there is none.
  static float best_upper(const Context& c) { return c.upper; }

  /// The edge-function bound B of the derivation above, from S = max_q (|Q̂x| + |Q̂y|) and
  /// Z = max_q |a_kz| over the triangle's vertices.
  static float edge_bound(float S, float Z) {
    return S * (14.0f * 0x1p-24f * S + 32.0f * 0x1p-24f * Z) + 0x1p-38f * (Z * Z) + 0x1p-119f * (1.0f + S + Z);
  }

  /// The depth bounds: floats lo <= hi around the exact t of every point where the line meets the
  /// triangle (requires c.cull). A triangle with hi < tmin or lo > best_upper(c) cannot become
  /// the first hit: most candidates of a leaf (those behind the origin, beyond the current first
  /// hit or beyond tmax) are rejected in float, without the double stage; and where [lo, hi]
  /// encloses the plane crossing, it certifies most hits without it too (decide_crossing).
  /// Derivation, with
  /// ẑ_q = fl(a_kz·sz) the computed (q_kz - o_kz)/d_kz (three roundings: |ẑ_q - z_q| <= 3.1u·|z_q|
  /// + 2^-63, given 2^-60 <= |d_kz| <= 2^100):
  ///  - Any point of the closed triangle is a convex combination of its vertices, so a point of
  ///    the line on it has t = (p_kz - o_kz)/d_kz in [min_q z_q, max_q z_q]: the range test,
  ///    [ẑ_min - 2^-20·|ẑ_min| - 2^-60, ẑ_max + 2^-20·|ẑ_max| + 2^-60] (16u covers the 3.1u of ẑ
  ///    and the roundings of the bound itself).
  ///  - When the float filter certifies that U, V, W share a sign, t = Σ λ_q z_q with
  ///    λ_q = |U_q|/Σ|U| exact (U_q the exact edge function of vertex q). With D = Σ|Û| and every
  ///    |Û_q - U_q| <= B, Σ_q |λ_q - λ̂_q| <= 6B/(D - 3B) for λ̂_q = |Û_q|/D, and Σ(λ_q - λ̂_q) = 0,
  ///    so |Σ λ_q ẑ_q - Σ λ̂_q ẑ_q| <= 3B/(D - 3B)·(ẑ_max - ẑ_min) <= 3.8·(B/D)·(ẑ_max - ẑ_min)
  ///    once D >= 16B. The float evaluation t̂ = fl(fl(Σ fl(|Û_q|·ẑ_q))·fl(1/fl(D))) is within
  ///    7.3u·max|ẑ| + 5μ/D of Σ λ̂_q ẑ_q (|Σ λ̂_q ẑ_q| <= max|ẑ|; 5μ/D <= 2^-63 once D >= 2^-60;
  ///    D <= 2^120 keeps 1/D normal),
  ///    and Σ λ_q ẑ_q within 3.2u·max|ẑ| + 2^-63 of t. Hence
  ///      |t̂ - t| <= E = 7·(B/D)·(ẑ_max - ẑ_min) + 2^-19·max|ẑ| + 2^-60,
  ///    the larger constants covering the roundings of E, t̂ - E and t̂ + E. The interval is a few
  ///    float ulps of t wide for a triangle far from degenerate, where the range test is as wide
  ///    as the triangle's depth extent (the triangle under a diffuse or shadow ray's origin,
  ///    crossed just behind it, needs the interval).
  /// An overflow, an infinity or a NaN fails every comparison or is excluded: never culls.
  /// Returns true when [lo, hi] encloses the plane crossing's t (the second case), with `t` the
  /// float estimate t̂ inside it; false when it is the range test's [lo, hi].
  static bool depth_bounds(const Context& c, float U, float V, float W, float B, float az, float bz, float cz, float& lo,
                           float& hi, float& t) {
    const float za = az * c.sz, zb = bz * c.sz, zc = cz * c.sz;
    const float zmin = std::min(std::min(za, zb), zc), zmax = std::max(std::max(za, zb), zc);
    const float aU = std::abs(U), aV = std::abs(V), aW = std::abs(W), D = aU + aV + aW;
    const bool certain = (U > B && V > B && W > B) || (U < -B && V < -B && W < -B);
    if (certain && D >= 16.0f * B && D >= 0x1p-60f && D <= 0x1p120f) {
      const float inv_D = 1.0f / D;
      t = (aU * za + aV * zb + aW * zc) * inv_D;
      const float E = 7.0f * (B * inv_D) * (zmax - zmin) + 0x1p-19f * std::max(std::abs(zmin), std::abs(zmax)) + 0x1p-60f;
      if (std::abs(t) <= 0x1p127f && E <= 0x1p127f) {
        lo = t - E, hi = t + E;
        return true;
      }
    }
    lo = zmin - (0x1p-20f * std::abs(zmin) + 0x1p-60f);
    hi = zmax + (0x1p-20f * std::abs(zmax) + 0x1p-60f);
    return false;
  }

  static bool intersect(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit) {
    if (c.has && c.prim == prim) return false;  // offered again (no mailbox): nothing changes
    if (!c.filter) return refine_triangle(c, prim, triangle(p0, p1, p2), hit);
    const Vec3f a = p0 - c.ray.org, b = p1 - c.ray.org, d = p2 - c.ray.org;
    const float az = a[c.kz], bz = b[c.kz], cz = d[c.kz];
    const float ax = a[c.kx] - c.sx * az, ay = a[c.ky] - c.sy * az;
    const float bx = b[c.kx] - c.sx * bz, by = b[c.ky] - c.sy * bz;
    const float cx = d[c.kx] - c.sx * cz, cy = d[c.ky] - c.sy * cz;
    const float U = cx * by - cy * bx;
    const float V = ax * cy - ay * cx;
    const float W = bx * ay - by * ax;
    const float S = std::max(std::max(std::abs(ax) + std::abs(ay), std::abs(bx) + std::abs(by)),
                             std::abs(cx) + std::abs(cy));
    const float Z = std::max(std::max(std::abs(az), std::abs(bz)), std::abs(cz));
    const float B = edge_bound(S, Z);
    if (std::max(std::max(U, V), W) > B && std::min(std::min(U, V), W) < -B) return false;  // surely misses
    return decide_unrejected(c, prim, p0, p1, p2, U, V, W, B, az, bz, cz, hit);
  }

  /// The rest of intersect() for a triangle the float filter did not reject, out of line: most
  /// triangles a ray is offered are rejected, and intersect() stays small enough to inline.
  [[gnu::noinline]] static bool decide_unrejected(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1,
                                                  const Vec3f& p2, float U, float V, float W, float B, float az,
                                                  float bz, float cz, TriangleHit& hit) {
    if (c.cull) {
      float lo, hi, t = 0.0f;
      const bool crossing = depth_bounds(c, U, V, W, B, az, bz, cz, lo, hi, t);
      if (hi < c.ray.tmin || lo > c.upper) return false;
      if (crossing) return decide_crossing(c, prim, p0, p1, p2, U, V, W, B, az, bz, cz, lo, hi, t, hit);
    }
    return decide_triangle(c, prim, p0, p1, p2, U, V, W, B, az, bz, cz, hit);
  }

  /// decide_triangle for a triangle whose interior the line surely crosses at an exact t in
  /// [lo, hi] (depth_bounds, the crossing case), t̂ = `t`: installed from that enclosure without
  /// the double stage when it settles the interval ends and the order; else decide_triangle.
  static bool decide_crossing(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float U,
                              float V, float W, float B, float az, float bz, float cz, float lo, float hi, float t,
                              TriangleHit& hit) {
    if (hi < c.ray.tmin || lo > c.ray.tmax || (c.has && double(lo) > c.hi)) return false;
    if (!(lo >= c.ray.tmin && hi <= c.ray.tmax) || (c.has && !(double(hi) < c.lo)))
      return decide_triangle(c, prim, p0, p1, p2, U, V, W, B, az, bz, cz, hit);
    install_crossing(c, prim, p0, p1, p2, U, V, W, lo, hi, t, hit);
    return true;
  }

  /// Makes the triangle the first hit, at an exact t in [lo, hi] ⊂ [tmin, tmax] with hi before
  /// the current first hit's lower bound (decide_crossing's certified case), with the estimate
  /// `t` and the barycentrics of its edge functions U, V, W.
  static void install_crossing(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float U,
                               float V, float W, float lo, float hi, float t, TriangleHit& hit) {
    const float inv_det = 1.0f / (U + V + W);
    install(c, prim, Interval{lo, hi}, TriangleHit{t, V * inv_det, W * inv_det}, triangle(p0, p1, p2), false, false);
    hit = c.best;
  }

  /// The rest of intersect() for a triangle the float filter did not reject: U, V, W are the
  /// computed edge functions (each within B of the exact one) and az, bz, cz the computed
  /// q_kz - o_kz.
  static bool decide_triangle(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float U,
                              float V, float W, float B, float az, float bz, float cz, TriangleHit& hit) {
    if (!((U > B && V > B && W > B) || (U < -B && V < -B && W < -B)))
      return refine_triangle(c, prim, triangle(p0, p1, p2), hit);
    // The line surely crosses the triangle's interior. A triangle whose vertices reach the
    // origin's depth may be the one the ray starts from, crossed just before or just after the
    // origin, where plane_t's enclosure straddles 0; plane_crossing_t's does not.
    const bool reaches_origin_depth = c.ray.dir[c.kz] > 0.0f ? std::min(std::min(az, bz), cz) <= 0.0f
                                                             : std::max(std::max(az, bz), cz) >= 0.0f;
    Interval t;
    if (!(reaches_origin_depth && plane_crossing_t(c.ray, p0, p1, p2, t))) t = plane_t(c, U, V, W, B, az, bz, cz);
    if (t.hi < c.ray.tmin || t.lo > c.ray.tmax || (c.has && t.lo > c.hi)) return false;
    if (!(t.lo >= c.ray.tmin && t.hi <= c.ray.tmax) || (c.has && !(t.hi < c.lo)))
      return refine_triangle(c, prim, triangle(p0, p1, p2), hit);  // an interval end or the order: tighter
    const float inv_det = 1.0f / (U + V + W);
    install(c, prim, t, TriangleHit{static_cast<float>(0.5 * (t.lo + t.hi)), V * inv_det, W * inv_det},
            triangle(p0, p1, p2), false, false);
    hit = c.best;
    return true;
  }

  static bool intersect_sphere(Context& c, unsigned prim, const Sphere& s, TriangleHit& hit) {
    if (!(s.radius > 0.0f)) return false;  // as ExactFirstHit: never hit
    if (c.has && c.prim == prim) return false;
    Shape shape;
    shape.sphere = true;
    shape.s = s;
    Interval t;
    const int verdict = sphere_t(c, s, t);
    if (verdict < 0) return false;
    if (verdict == 0) return offer_exact(c, prim, shape, hit);
    const double tm = 0.5 * (t.lo + t.hi);
    const Vec3d p = Vec3d(c.ray.org) + Vec3d(c.ray.dir) * tm - Vec3d(s.center);
    const double phi = std::atan2(p.y, p.x), theta = std::acos(std::clamp(p.z / double(s.radius), -1.0, 1.0));
    const TriangleHit th{static_cast<float>(tm), static_cast<float>((phi + M_PI) / (2 * M_PI)),
                         static_cast<float>(theta / M_PI)};
    return offer_tight(c, prim, t, th, shape, hit);
  }

 private:
  static Shape triangle(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
    Shape s;
    s.p0 = p0, s.p1 = p1, s.p2 = p2;
    return s;
  }

  /// The plane-crossing t of a triangle from the float filter's edge functions (each within B
  /// of the exact one) and its computed a_kz, enclosed in double. (Only called when U, V, W
  /// surely share a sign, so det = U + V + W does not vanish.) It is evaluated as
  ///   t = z_a + (V·(z_b - z_a) + W·(z_c - z_a)) / det,   z_q = (q_kz - o_kz) / d_kz,
  /// where the edge functions' error B multiplies only the triangle's own depth extent, not the
  /// distance to it: the enclosure is a few float ulps of t wide, as tight as the float t itself.
  static Interval plane_t(const Context& c, float U, float V, float W, float B, float az, float bz, float cz) {
    interval_stage_taken_on_this_thread() = true;
    const Interval u = Interval::rounded(double(U) - B, double(U) + B);
    const Interval v = Interval::rounded(double(V) - B, double(V) + B);
    const Interval w = Interval::rounded(double(W) - B, double(W) + B);
    const Interval det = u + v + w;
    // The exact q_kz - o_kz is within u(1 + 2u)·|a_kz| + 3.1μ of the computed a_kz (one
    // rounding, two inputs read under DAZ), hence in a_kz·(1 ± 2^-23) ± 2^-124.
    const Interval dz = Interval::of_float(c.ray.dir[c.kz]);
    auto z = [&](float q) {
      const double lo = q >= 0.0f ? double(q) * (1.0 - 0x1p-23) : double(q) * (1.0 + 0x1p-23);
      const double hi = q >= 0.0f ? double(q) * (1.0 + 0x1p-23) : double(q) * (1.0 - 0x1p-23);
      return Interval::rounded(lo - 0x1p-124, hi + 0x1p-124);
    };
    const Interval za = z(az);
    return (za + (v * (z(bz) - za) + w * (z(cz) - za)) / det) / dz;
  }

  /// The exact t at which the line meets the triangle's plane, t = (p0 - o)·n / (d·n) with
  /// n = (p1 - p0) × (p2 - p0), enclosed in `t` from the two determinants evaluated in double
  /// with a static error bound (Shewchuk 1997's orient3d filter); false, with `t` unset, when
  /// d·n is not surely non-zero or a bound overflows. Its width is relative to the determinants'
  /// permanents (2^-49 of them), not to the triangle's depth extent as plane_t's: a ray that starts
  /// on a triangle, offset a few hundred ulps off it (Wächter and Binder, Ray Tracing Gems 2019,
  /// ch. 6), meets that triangle's plane just before its origin (or just after it, a shadow ray
  /// toward a light behind the surface), and this enclosure says on which side where plane_t's
  /// straddles 0. A static filter: not counted as the double stage.
  /// Error bound, with ε = 2^-53: the differences r = p0 - o, e1, e2 are double subtractions of
  /// float inputs (relative error ε, and 2^-125 when an input is a subnormal read as 0 under
  /// DAZ); from differences within ε, the computed r·(e1 × e2) is within (7ε + 56ε²)·P of the
  /// exact value of those differences (Shewchuk's o3derrboundA, P = Σ|r_i|·(|e1_j·e2_k| +
  /// |e1_k·e2_j|)), and their relative errors add 3ε·P more: below 2^-49·P for P computed in
  /// double. The absolute errors add at most 18·2^-125·L² + O(2^-250·L), L the largest |r_i|,
  /// |e1_i|, |e2_i|, |d_i|, and flushed double results 2^-1022 each: below 2^-120·(L² + 1).
  /// The same holds for d·n with d's components in place of r's.
  static bool plane_crossing_t(const Ray& ray, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, Interval& t) {
    const Vec3d a(p0), e1 = Vec3d(p1) - a, e2 = Vec3d(p2) - a, r = a - Vec3d(ray.org), d(ray.dir);
    const double nx = e1.y * e2.z - e1.z * e2.y, ny = e1.z * e2.x - e1.x * e2.z, nz = e1.x * e2.y - e1.y * e2.x;
    const double mx = std::abs(e1.y * e2.z) + std::abs(e1.z * e2.y), my = std::abs(e1.z * e2.x) + std::abs(e1.x * e2.z),
                 mz = std::abs(e1.x * e2.y) + std::abs(e1.y * e2.x);
    const double num = r.x * nx + r.y * ny + r.z * nz, den = d.x * nx + d.y * ny + d.z * nz;
    const double L = std::max(std::max(std::max(max_abs(e1), max_abs(e2)), max_abs(r)), max_abs(d));
    const double absolute = 0x1p-120 * (L * L + 1.0);
    const double num_bound = 0x1p-49 * (std::abs(r.x) * mx + std::abs(r.y) * my + std::abs(r.z) * mz) + absolute;
    const double den_bound = 0x1p-49 * (std::abs(d.x) * mx + std::abs(d.y) * my + std::abs(d.z) * mz) + absolute;
    if (!(std::abs(den) > den_bound) || !(num_bound < INFINITY)) return false;
    t = Interval::rounded(num - num_bound, num + num_bound) / Interval::rounded(den - den_bound, den + den_bound);
    return std::isfinite(t.lo) && std::isfinite(t.hi);
  }
  static double max_abs(const Vec3d& v) { return std::max(std::max(std::abs(v.x), std::abs(v.y)), std::abs(v.z)); }

  /// The double stage: the exact edge functions, det and t enclosed in double interval
  /// arithmetic from the float inputs (a relative width near 2^-50 instead of the float
  /// filter's 2^-20 or so). -1: the line surely misses the closed triangle; 1: it surely
  /// crosses its interior, at a t in `t`; 0: undecided (the line meets an edge or a vertex,
  /// lies in the plane, or passes within ~2^-50 of one).
  static int triangle_t(const Context& c, const Shape& tri, Interval& t) {
    interval_stage_taken_on_this_thread() = true;
    const Interval dz = Interval::of_float(c.ray.dir[c.kz]);
    const Interval sx = Interval::of_float(c.ray.dir[c.kx]) / dz, sy = Interval::of_float(c.ray.dir[c.ky]) / dz;
    const Interval ox = Interval::of_float(c.ray.org[c.kx]), oy = Interval::of_float(c.ray.org[c.ky]),
                   oz = Interval::of_float(c.ray.org[c.kz]);
    Interval X[3], Y[3], Z[3];
    const Vec3f* q[3] = {&tri.p0, &tri.p1, &tri.p2};
    for (int i = 0; i < 3; ++i) {
      const Interval a = Interval::of_float((*q[i])[c.kz]) - oz;
      X[i] = (Interval::of_float((*q[i])[c.kx]) - ox) - sx * a;
      Y[i] = (Interval::of_float((*q[i])[c.ky]) - oy) - sy * a;
      Z[i] = a / dz;
    }
    const Interval U = X[2] * Y[1] - Y[2] * X[1], V = X[0] * Y[2] - Y[0] * X[2], W = X[1] * Y[0] - Y[1] * X[0];
    const bool pos = U.lo > 0.0 || V.lo > 0.0 || W.lo > 0.0, neg = U.hi < 0.0 || V.hi < 0.0 || W.hi < 0.0;
    if (pos && neg) return -1;
    if (!((U.lo > 0.0 && V.lo > 0.0 && W.lo > 0.0) || (U.hi < 0.0 && V.hi < 0.0 && W.hi < 0.0))) return 0;
    t = Z[0] + (V * (Z[1] - Z[0]) + W * (Z[2] - Z[0])) / (U + V + W);  // as plane_t: tight
    return 1;
  }

  /// The sphere's first root not before tmin, enclosed in double interval arithmetic: -1 no
  /// hit in [tmin, tmax] surely; 1 the root is in `t`, surely in [tmin, tmax]; 0 undecided.
  static int sphere_t(const Context& c, const Sphere& s, Interval& t) {
    interval_stage_taken_on_this_thread() = true;
    Interval oc[3], d[3];
    for (int k = 0; k < 3; ++k) {
      oc[k] = Interval::of_float(c.ray.org[k]) - Interval::of_float(s.center[k]);
      d[k] = Interval::of_float(c.ray.dir[k]);
    }
    const Interval A = square(d[0]) + square(d[1]) + square(d[2]);
    const Interval Bh = d[0] * oc[0] + d[1] * oc[1] + d[2] * oc[2];
    const Interval C = (square(oc[0]) + square(oc[1]) + square(oc[2])) - square(Interval::of_float(s.radius));
    const Interval disc = square(Bh) - A * C;
    if (disc.certainly_negative()) return -1;
    if (!disc.certainly_positive() || !A.certainly_positive()) return 0;
    const Interval root = sqrt(disc);
    const Interval t0 = (-Bh - root) / A, t1 = (-Bh + root) / A;
    // The exact rule: the smaller root if it is >= tmin, else the larger one.
    if (t0.lo >= c.ray.tmin) t = t0;
    else if (t0.hi < c.ray.tmin) t = t1;
    else return 0;
    if (t.hi < c.ray.tmin || t.lo > c.ray.tmax) return -1;
    return t.lo >= c.ray.tmin && t.hi <= c.ray.tmax ? 1 : 0;
  }

  /// A triangle the float filter could not settle: the double stage, then the exact path.
  static bool refine_triangle(Context& c, unsigned prim, const Shape& tri, TriangleHit& hit) {
    Interval plane;
    if (plane_crossing_t(c.ray, tri.p0, tri.p1, tri.p2, plane) &&
        (plane.hi < c.ray.tmin || plane.lo > c.ray.tmax || (c.has && plane.lo > c.hi)))
      return false;  // whatever the edges decide, the plane is met outside [tmin, tmax] or after the first hit
    Interval t;
    const int verdict = triangle_t(c, tri, t);
    if (verdict < 0) return false;
    if (verdict > 0) {
      if (t.hi < c.ray.tmin || t.lo > c.ray.tmax || (c.has && t.lo > c.hi)) return false;
      if (t.lo >= c.ray.tmin && t.hi <= c.ray.tmax) {
        // Barycentrics for the report, in double from the enclosures' midpoints.
        TriangleHit th{static_cast<float>(0.5 * (t.lo + t.hi)), 0.0f, 0.0f};
        barycentrics(c, tri, th);
        return offer_tight(c, prim, t, th, tri, hit);
      }
    }
    return offer_exact(c, prim, tri, hit);
  }

  /// Installs a candidate whose exact t surely lies in `t` ⊂ [tmin, tmax] (a double-stage
  /// enclosure) if it comes first; the exact path decides an order the enclosures cannot.
  static bool offer_tight(Context& c, unsigned prim, const Interval& t, const TriangleHit& th, const Shape& shape,
                          TriangleHit& hit) {
    if (c.has) {
      if (t.lo > c.hi) return false;
      if (!(t.hi < c.lo) && !c.tight) {  // tighten the current first hit's enclosure first
        Interval bt;
        if ((c.shape.sphere ? sphere_t(c, c.shape.s, bt) : triangle_t(c, c.shape, bt)) > 0) {
          c.lo = std::max(c.lo, bt.lo), c.hi = std::min(c.hi, bt.hi), c.tight = true;
          if (t.lo > c.hi) return false;
        }
      }
      if (!(t.hi < c.lo)) return offer_exact(c, prim, shape, hit);
    }
    install(c, prim, t, th, shape, true, false);
    hit = c.best;
    return true;
  }

  /// The exact path decides whether the candidate is hit and whether it comes first.
  static bool offer_exact(Context& c, unsigned prim, const Shape& shape, TriangleHit& hit) {
    ensure_exact(c);
    const bool won = shape.sphere ? c.exact->offer_sphere(prim, shape.s)
                                  : c.exact->offer_triangle(prim, shape.p0, shape.p1, shape.p2);
    if (!won) return false;
    double lo, hi;
    c.exact->best_time_bounds(lo, hi);
    const Hit h = c.exact->hit();
    install(c, prim, Interval{lo, hi}, TriangleHit{h.t, h.u, h.v}, shape, true, true);
    hit = c.best;
    return true;
  }

  /// Creates the exact path of this ray and hands it the current first hit.
  static void ensure_exact(Context& c) {
    if (!c.exact) c.exact = std::make_unique<ExactFallback>(c.ray);
    if (c.has && !c.best_in_exact) {
      // It surely comes first among what the exact path holds; at a tie of exact t the exact
      // path may keep the other primitive, which is as good.
      if (c.shape.sphere) c.exact->offer_sphere(c.prim, c.shape.s);
      else c.exact->offer_triangle(c.prim, c.shape.p0, c.shape.p1, c.shape.p2);
      c.best_in_exact = true;
    }
  }

  static void barycentrics(const Context& c, const Shape& tri, TriangleHit& th) {
    const Vec3d p = Vec3d(c.ray.org) + Vec3d(c.ray.dir) * double(th.t);
    const Vec3d a(tri.p0), e1 = Vec3d(tri.p1) - a, e2 = Vec3d(tri.p2) - a, n = cross(e1, e2);
    const double nn = dot(n, n);
    if (!(nn > 0.0)) return;
    th.u = static_cast<float>(dot(cross(p - a, e2), n) / nn);
    th.v = static_cast<float>(dot(cross(e1, p - a), n) / nn);
  }

  static void install(Context& c, unsigned prim, const Interval& t, const TriangleHit& th, const Shape& shape,
                      bool tight, bool in_exact) {
    c.has = true;
    c.tight = tight;
    c.prim = prim;
    c.lo = t.lo;
    c.hi = t.hi;
    c.upper = float_up(t.hi);
    c.reach = reach_of(c.upper);
    c.best = th;
    c.shape = shape;
    c.best_in_exact = in_exact;
  }
};

}  // namespace raylab
