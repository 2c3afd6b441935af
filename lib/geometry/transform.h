#pragma once
/// Affine transforms p' = L·p + t, stored as a row-major 3x4 matrix in double so that composing
/// and inverting loses as little as possible; applied to rays in float.
#include <array>
#include <cmath>

#include "geometry/bounds.h"
#include "geometry/ray.h"

namespace raylab {

struct AffineTransform {
  std::array<std::array<double, 4>, 3> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};

  static AffineTransform identity() { return {}; }
  static AffineTransform translation(const Vec3d& t) {
    AffineTransform a; a.m[0][3] = t.x; a.m[1][3] = t.y; a.m[2][3] = t.z; return a;
  }
  static AffineTransform scaling(const Vec3d& s) {
    AffineTransform a; a.m[0][0] = s.x; a.m[1][1] = s.y; a.m[2][2] = s.z; return a;
  }
  /// Rotation by `radians` about a unit axis (Rodrigues).
  static AffineTransform rotation(const Vec3d& axis, double radians) {
    const Vec3d k = normalize(axis);
    const double c = std::cos(radians), s = std::sin(radians), C = 1 - c;
    AffineTransform a;
    a.m[0] = {c + k.x * k.x * C, k.x * k.y * C - k.z * s, k.x * k.z * C + k.y * s, 0};
    a.m[1] = {k.y * k.x * C + k.z * s, c + k.y * k.y * C, k.y * k.z * C - k.x * s, 0};
    a.m[2] = {k.z * k.x * C - k.y * s, k.z * k.y * C + k.x * s, c + k.z * k.z * C, 0};
    return a;
  }

  /// this ∘ o: applies o first.
  AffineTransform operator*(const AffineTransform& o) const {
    AffineTransform r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = (j == 3) ? m[i][3] : 0.0;
        for (int k = 0; k < 3; ++k) s += m[i][k] * o.m[k][j];
        r.m[i][j] = s;
      }
    return r;
  }

  double determinant() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }

  /// Inverse of an invertible transform (the caller checks determinant() != 0).
  AffineTransform inverse() const {
    const double det = determinant();
    AffineTransform r;
    r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
    r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
    r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
    r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
    r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
    r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
    r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
    r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
    r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
    for (int i = 0; i < 3; ++i) r.m[i][3] = -(r.m[i][0] * m[0][3] + r.m[i][1] * m[1][3] + r.m[i][2] * m[2][3]);
    return r;
  }

  Vec3d apply_point(const Vec3d& p) const {
    return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
            m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
            m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
  }
  Vec3d apply_vector(const Vec3d& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  Vec3f apply_point(const Vec3f& p) const { return Vec3f(apply_point(Vec3d(p))); }
  Vec3f apply_vector(const Vec3f& v) const { return Vec3f(apply_vector(Vec3d(v))); }
  /// The direction is transformed but not renormalised, so t is the same in both spaces.
  Ray apply(const Ray& r) const { return {apply_point(r.org), apply_vector(r.dir), r.tmin, r.tmax}; }
  /// Bounds of the transformed box (all eight corners), rounded outward by a relative ulp.
  Bounds3f apply(const Bounds3f& b) const {
    Bounds3d out;
    for (int c = 0; c < 8; ++c)
      out.extend(apply_point(Vec3d((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z)));
    Bounds3f f;
    for (int a = 0; a < 3; ++a) {
      f.lo[a] = std::nextafter(static_cast<float>(out.lo[a]), -std::numeric_limits<float>::infinity());
      f.hi[a] = std::nextafter(static_cast<float>(out.hi[a]), std::numeric_limits<float>::infinity());
    }
    return f;
  }
};

/// All twelve entries finite.
inline bool is_finite(const AffineTransform& a) {
  for (const auto& row : a.m)
    for (const double x : row)
      if (!std::isfinite(x)) return false;
  return true;
}

/// Finite, with a non-zero determinant and a finite inverse: what placing geometry by `a` (and
/// taking rays back by its inverse) needs.
inline bool is_invertible(const AffineTransform& a) { return is_finite(a) && a.determinant() != 0.0 && is_finite(a.inverse()); }

}  // namespace raylab
