#pragma once
/// Closed intervals of doubles that contain an exact real value, for the certified kernel's
/// double-precision steps (certified_kernel.h): every operation rounds its result outward, so
/// the exact result of the operation on any members of the operands lies in the result.
///
/// Outward rounding without changing the rounding mode: a double operation rounded to nearest is
/// within 2^-53·|r| of the exact result r (plus 2^-1022 when flush-to-zero drops a subnormal
/// result), and widen_down/widen_up move the computed value by 2^-50·|r| + 2^-1000, which exceeds
/// that error even after the widening step's own rounding (it is itself a double operation
/// within 2^-53 of exact). Overflow gives an infinite bound, NaN an empty interval (lo > hi is
/// false for NaN, so `certain_*` tests below are false): a caller never certifies from either.
#include <algorithm>
#include <cmath>

namespace raylab {

struct Interval {
  double lo = 0.0, hi = 0.0;

  static double widen_down(double x) { return x - (std::abs(x) * 0x1p-50 + 0x1p-1000); }
  static double widen_up(double x) { return x + (std::abs(x) * 0x1p-50 + 0x1p-1000); }
  static Interval rounded(double lo, double hi) { return {widen_down(lo), widen_up(hi)}; }

  /// A float input read under DAZ may be a subnormal flushed to zero: [x - 2^-126, x + 2^-126].
  static Interval of_float(float x) {
    const double d = x;
    return {widen_down(d - 0x1p-126), widen_up(d + 0x1p-126)};
  }
  static Interval point(double x) { return {x, x}; }

  bool certainly_positive() const { return lo > 0.0; }
  bool certainly_negative() const { return hi < 0.0; }
};

inline Interval operator+(const Interval& a, const Interval& b) { return Interval::rounded(a.lo + b.lo, a.hi + b.hi); }
inline Interval operator-(const Interval& a, const Interval& b) { return Interval::rounded(a.lo - b.hi, a.hi - b.lo); }
inline Interval operator-(const Interval& a) { return {-a.hi, -a.lo}; }
inline Interval operator*(const Interval& a, const Interval& b) {
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  return Interval::rounded(std::min(std::min(p[0], p[1]), std::min(p[2], p[3])),
                           std::max(std::max(p[0], p[1]), std::max(p[2], p[3])));
}
/// The square of a member: non-negative, tighter than a * a when the interval spans 0.
inline Interval square(const Interval& a) {
  const double l = std::abs(a.lo), h = std::abs(a.hi);
  const double m = std::max(l, h);
  const double n = (a.lo <= 0.0 && a.hi >= 0.0) ? 0.0 : std::min(l, h);
  return {std::max(0.0, Interval::widen_down(n * n)), Interval::widen_up(m * m)};
}
/// a / b for an interval b that does not contain 0 (the caller checks); otherwise (-inf, inf).
inline Interval operator/(const Interval& a, const Interval& b) {
  if (!(b.lo > 0.0 || b.hi < 0.0)) return {-INFINITY, INFINITY};
  const double q[4] = {a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi};
  return Interval::rounded(std::min(std::min(q[0], q[1]), std::min(q[2], q[3])),
                           std::max(std::max(q[0], q[1]), std::max(q[2], q[3])));
}
/// The square root of the non-negative members of `a` (an interval reaching below 0 is cut at 0).
inline Interval sqrt(const Interval& a) {
  return {std::max(0.0, Interval::widen_down(std::sqrt(std::max(0.0, a.lo)))),
          Interval::widen_up(std::sqrt(std::max(0.0, a.hi)))};
}

/// Set to true on the calling thread whenever the certified kernel runs its double stage
/// (certified_kernel.h: plane_t, triangle_t, sphere_t); AggregateBase reads and clears it to count
/// RayCounters::interval_stage, as exact_path_taken_on_this_thread() for the exact path.
inline bool& interval_stage_taken_on_this_thread() {
  thread_local bool taken = false;
  return taken;
}

/// The largest float <= x and the smallest float >= x (x a double; ±inf and NaN pass).
inline float float_down(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -INFINITY) : f;
}
inline float float_up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, INFINITY) : f;
}

}  // namespace raylab
