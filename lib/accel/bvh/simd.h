#pragma once
/// The few SIMD float operations the wide BVH needs, N = 4 (SSE) or 8 (AVX; two SSE halves
/// where the target has no AVX). Every operation is the IEEE operation of its scalar
/// counterpart, lane by lane, so code written with them rounds exactly as scalar code does,
/// with two exceptions: `fmadd` and `fmsub` fuse, and min/max keep the
/// operand order of SSE (`min(a, b) = a < b ? a : b`, `max(a, b) = a > b ? a : b`, so a NaN in
/// either yields b), which the robust box test relies on to mirror intersect_box's branches.
#include <immintrin.h>

#include <cstdint>

namespace raylab::simd {

template <int N>
struct Float;

template <>
struct Float<4> {
  __m128 v;
  static Float load(const float* p) { return {_mm_load_ps(p)}; }
  static Float broadcast(float x) { return {_mm_set1_ps(x)}; }
  /// Four unsigned bytes from `p` (any alignment), converted exactly to float.
  static Float from_bytes(const std::uint8_t* p) {
    std::int32_t bits;
    __builtin_memcpy(&bits, p, sizeof bits);
    const __m128i bytes = _mm_cvtsi32_si128(bits);
#if defined(__SSE4_1__)
    return {_mm_cvtepi32_ps(_mm_cvtepu8_epi32(bytes))};
#else
    const __m128i zero = _mm_setzero_si128();
    return {_mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero))};
#endif
  }
  void store(float* p) const { _mm_store_ps(p, v); }
  friend Float operator+(Float a, Float b) { return {_mm_add_ps(a.v, b.v)}; }
  friend Float operator-(Float a, Float b) { return {_mm_sub_ps(a.v, b.v)}; }
  friend Float operator*(Float a, Float b) { return {_mm_mul_ps(a.v, b.v)}; }
  friend Float operator/(Float a, Float b) { return {_mm_div_ps(a.v, b.v)}; }
  friend Float min(Float a, Float b) { return {_mm_min_ps(a.v, b.v)}; }
  friend Float max(Float a, Float b) { return {_mm_max_ps(a.v, b.v)}; }
  /// a·b + c, fused where the target has FMA (callers whose a·b is exact get the same result either way).
  friend Float fmadd(Float a, Float b, Float c) {
#if defined(__FMA__)
    return {_mm_fmadd_ps(a.v, b.v, c.v)};
#else
    return {_mm_add_ps(_mm_mul_ps(a.v, b.v), c.v)};
#endif
  }
  /// a·b - c, fused where the target has FMA.
  friend Float fmsub(Float a, Float b, Float c) {
#if defined(__FMA__)
    return {_mm_fmsub_ps(a.v, b.v, c.v)};
#else
    return {_mm_sub_ps(_mm_mul_ps(a.v, b.v), c.v)};
#endif
  }
  friend Float abs(Float a) { return {_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)}; }
  /// max(|a|, |b|), one instruction where the target has AVX-512DQ (VRANGEPS); a lane with a NaN
  /// input may give NaN or the other input's magnitude.
  friend Float max_abs(Float a, Float b) {
#if defined(__AVX512DQ__) && defined(__AVX512VL__)
    return {_mm_range_ps(a.v, b.v, 0b1011)};  // imm[1:0] = 11: larger magnitude; imm[3:2] = 10: sign cleared
#else
    return max(abs(a), abs(b));
#endif
  }
  /// The sign bits of a (every other bit 0); x ^ sign_bits(a) is x with its sign flipped where a's is set.
  friend Float sign_bits(Float a) { return {_mm_and_ps(a.v, _mm_set1_ps(-0.0f))}; }
  friend Float operator^(Float a, Float b) { return {_mm_xor_ps(a.v, b.v)}; }
  /// Lane masks as bits (bit i = lane i).
  friend unsigned operator<=(Float a, Float b) { return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(a.v, b.v))); }
  friend unsigned operator<(Float a, Float b) { return static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(a.v, b.v))); }
  friend unsigned operator>(Float a, Float b) { return static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(a.v, b.v))); }
  friend unsigned operator>=(Float a, Float b) { return static_cast<unsigned>(_mm_movemask_ps(_mm_cmpge_ps(a.v, b.v))); }
  friend unsigned operator==(Float a, Float b) { return static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(a.v, b.v))); }
  /// Lanes whose value is finite (NaN and ±inf are not).
  friend unsigned finite(Float a) {
    const __m128 abs = _mm_andnot_ps(_mm_set1_ps(-0.0f), a.v);
    return static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(abs, _mm_set1_ps(__builtin_huge_valf()))));
  }
};

#if defined(__AVX__)
template <>
struct Float<8> {
  __m256 v;
  static Float load(const float* p) { return {_mm256_load_ps(p)}; }
  /// Lanes 0-3 from `lo`, 4-7 from `hi` (each 16-byte aligned).
  static Float load_halves(const float* lo, const float* hi) {
    return {_mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(lo)), _mm_load_ps(hi), 1)};
  }
  static Float broadcast(float x) { return {_mm256_set1_ps(x)}; }
  static Float from_bytes(const std::uint8_t* p) {
#if defined(__AVX2__)
    return {_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))))};
#else
    const __m128 lo = Float<4>::from_bytes(p).v, hi = Float<4>::from_bytes(p + 4).v;
    return {_mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1)};
#endif
  }
  void store(float* p) const { _mm256_store_ps(p, v); }
  friend Float operator+(Float a, Float b) { return {_mm256_add_ps(a.v, b.v)}; }
  friend Float operator-(Float a, Float b) { return {_mm256_sub_ps(a.v, b.v)}; }
  friend Float operator*(Float a, Float b) { return {_mm256_mul_ps(a.v, b.v)}; }
  friend Float operator/(Float a, Float b) { return {_mm256_div_ps(a.v, b.v)}; }
  friend Float min(Float a, Float b) { return {_mm256_min_ps(a.v, b.v)}; }
  friend Float max(Float a, Float b) { return {_mm256_max_ps(a.v, b.v)}; }
  friend Float fmadd(Float a, Float b, Float c) {
#if defined(__FMA__)
    return {_mm256_fmadd_ps(a.v, b.v, c.v)};
#else
    return {_mm256_add_ps(_mm256_mul_ps(a.v, b.v), c.v)};
#endif
  }
  friend Float fmsub(Float a, Float b, Float c) {
#if defined(__FMA__)
    return {_mm256_fmsub_ps(a.v, b.v, c.v)};
#else
    return {_mm256_sub_ps(_mm256_mul_ps(a.v, b.v), c.v)};
#endif
  }
  friend Float abs(Float a) { return {_mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v)}; }
  friend Float max_abs(Float a, Float b) {
#if defined(__AVX512DQ__) && defined(__AVX512VL__)
    return {_mm256_range_ps(a.v, b.v, 0b1011)};
#else
    return max(abs(a), abs(b));
#endif
  }
  friend Float sign_bits(Float a) { return {_mm256_and_ps(a.v, _mm256_set1_ps(-0.0f))}; }
  friend Float operator^(Float a, Float b) { return {_mm256_xor_ps(a.v, b.v)}; }
#if defined(__AVX512F__) && defined(__AVX512VL__)
  friend unsigned operator<=(Float a, Float b) { return _mm256_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ); }
  friend unsigned operator<(Float a, Float b) { return _mm256_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ); }
  friend unsigned operator>(Float a, Float b) { return _mm256_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ); }
  friend unsigned operator>=(Float a, Float b) { return _mm256_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ); }
  friend unsigned operator==(Float a, Float b) { return _mm256_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ); }
#else
  friend unsigned operator<=(Float a, Float b) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)));
  }
  friend unsigned operator<(Float a, Float b) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)));
  }
  friend unsigned operator>(Float a, Float b) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ)));
  }
  friend unsigned operator>=(Float a, Float b) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ)));
  }
  friend unsigned operator==(Float a, Float b) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, _CMP_EQ_OQ)));
  }
#endif
  friend unsigned finite(Float a) {
    const __m256 abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v);
    return static_cast<unsigned>(
        _mm256_movemask_ps(_mm256_cmp_ps(abs, _mm256_set1_ps(__builtin_huge_valf()), _CMP_LT_OQ)));
  }
};
#else
/// Without AVX: two SSE halves.
template <>
struct Float<8> {
  Float<4> lo, hi;
  static Float load(const float* p) { return {Float<4>::load(p), Float<4>::load(p + 4)}; }
  static Float load_halves(const float* lo, const float* hi) { return {Float<4>::load(lo), Float<4>::load(hi)}; }
  static Float broadcast(float x) { return {Float<4>::broadcast(x), Float<4>::broadcast(x)}; }
  static Float from_bytes(const std::uint8_t* p) { return {Float<4>::from_bytes(p), Float<4>::from_bytes(p + 4)}; }
  void store(float* p) const { lo.store(p); hi.store(p + 4); }
  friend Float operator+(Float a, Float b) { return {a.lo + b.lo, a.hi + b.hi}; }
  friend Float operator-(Float a, Float b) { return {a.lo - b.lo, a.hi - b.hi}; }
  friend Float operator*(Float a, Float b) { return {a.lo * b.lo, a.hi * b.hi}; }
  friend Float operator/(Float a, Float b) { return {a.lo / b.lo, a.hi / b.hi}; }
  friend Float min(Float a, Float b) { return {min(a.lo, b.lo), min(a.hi, b.hi)}; }
  friend Float max(Float a, Float b) { return {max(a.lo, b.lo), max(a.hi, b.hi)}; }
  friend Float fmadd(Float a, Float b, Float c) { return {fmadd(a.lo, b.lo, c.lo), fmadd(a.hi, b.hi, c.hi)}; }
  friend Float fmsub(Float a, Float b, Float c) { return {fmsub(a.lo, b.lo, c.lo), fmsub(a.hi, b.hi, c.hi)}; }
  friend Float abs(Float a) { return {abs(a.lo), abs(a.hi)}; }
  friend Float max_abs(Float a, Float b) { return {max_abs(a.lo, b.lo), max_abs(a.hi, b.hi)}; }
  friend Float sign_bits(Float a) { return {sign_bits(a.lo), sign_bits(a.hi)}; }
  friend Float operator^(Float a, Float b) { return {a.lo ^ b.lo, a.hi ^ b.hi}; }
  friend unsigned operator<=(Float a, Float b) { return (a.lo <= b.lo) | ((a.hi <= b.hi) << 4); }
  friend unsigned operator<(Float a, Float b) { return (a.lo < b.lo) | ((a.hi < b.hi) << 4); }
  friend unsigned operator>(Float a, Float b) { return (a.lo > b.lo) | ((a.hi > b.hi) << 4); }
  friend unsigned operator>=(Float a, Float b) { return (a.lo >= b.lo) | ((a.hi >= b.hi) << 4); }
  friend unsigned operator==(Float a, Float b) { return (a.lo == b.lo) | ((a.hi == b.hi) << 4); }
  friend unsigned finite(Float a) { return finite(a.lo) | (finite(a.hi) << 4); }
};
#endif

}  // namespace raylab::simd
