#pragma once
/// The reference record the SAH builders sort and partition (internal to the builders).
///
/// 32 bytes, 16-byte aligned, so that one reference is two SSE loads: lo with the primitive id in
/// the fourth lane, hi with padding. Partitions move these records, not indices into a box
/// array, so that binning reads memory in order (Wald 2007 §3; Embree's PrimRef).
#include <immintrin.h>

#include <cstdint>

#include "geometry/bounds.h"

namespace raylab {

struct alignas(16) BvhBuildRef {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::uint32_t pad;

  Bounds3f box() const { return {Vec3f(lo[0], lo[1], lo[2]), Vec3f(hi[0], hi[1], hi[2])}; }
  /// Twice the box centre along `axis` (builders bin and sort by lo + hi).
  float centroid2(int axis) const { return lo[axis] + hi[axis]; }

  /// `box` must not be empty.
  static BvhBuildRef make(const Bounds3f& box, std::uint32_t id) {
    return {{box.lo.x, box.lo.y, box.lo.z}, id, {box.hi.x, box.hi.y, box.hi.z}, 0u};
  }
};
static_assert(sizeof(BvhBuildRef) == 32);

/// The lower corner of the reference at `lo` (BvhBuildRef::lo) in an SSE register, with lane 3
/// (the id's bits) zeroed. Read as a float, an id below 2^23 is a denormal; builds run without
/// FTZ/DAZ, where SSE arithmetic on denormals takes a microcode assist (profiled: ~1/3 of the
/// binning loop, the centroid's multiply with a denormal lane).
inline __m128 bvh_ref_lo(const float* lo) {
  return _mm_and_ps(_mm_load_ps(lo), _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)));
}

/// An empty box is replaced by the point at the origin (its centroid in the original midpoint
/// builder), so that every reference has a finite centroid; node boxes may then include the
/// origin, which is conservative.
inline Bounds3f bvh_build_box(const Bounds3f& box) { return box.empty() ? Bounds3f(Vec3f(0.0f)) : box; }

}  // namespace raylab
