#pragma once
/// Flush-to-zero / denormals-are-zero control of the SSE unit (MXCSR). Embree asks for FTZ and
/// DAZ on every tracing thread (Embree 3 manual, "Performance Recommendations"); raylab traces
/// every accelerator under the same mode so timings compare like with like. The exact oracle
/// turns the mode off around its CGAL calls, whose interval filters assume IEEE arithmetic.
#include <xmmintrin.h>

namespace raylab {

/// Sets FTZ and DAZ (`enable` = true) or clears them for the lifetime of the scope, on this thread.
class FloatModeScope {
 public:
  explicit FloatModeScope(bool flush_denormals) : saved_(_mm_getcsr()) {
    constexpr unsigned kFtzDaz = 0x8040u;  // bit 15 FTZ, bit 6 DAZ
    _mm_setcsr(flush_denormals ? (saved_ | kFtzDaz) : (saved_ & ~kFtzDaz));
  }
  ~FloatModeScope() { _mm_setcsr(saved_); }
  FloatModeScope(const FloatModeScope&) = delete;
  FloatModeScope& operator=(const FloatModeScope&) = delete;

 private:
  unsigned saved_;
};

}  // namespace raylab
