#include "accel/bvh/compressed_wide_bvh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "accel/common/huge_pages.h"

namespace raylab {

float decode_compressed_plane(float origin, float cell, std::uint8_t q) {
  const float x = std::fma(static_cast<float>(q), cell, origin);
  return std::abs(x) < std::numeric_limits<float>::min() ? std::copysign(0.0f, x) : x;
}

namespace {

constexpr int kMinExponent = -126;  // 2^e stays a normal float, so q·2^e is exact
constexpr int kMaxExponent = 127;

/// A grid origin at or below `lo` that is zero or normal (DAZ would read a denormal as zero).
float grid_origin(float lo) {
  if (std::abs(lo) >= std::numeric_limits<float>::min() || lo == 0.0f) return lo;
  return lo > 0.0f ? 0.0f : -std::numeric_limits<float>::min();
}

/// Cells of lo (rounded down) and hi (rounded up) for each of `n` children on one axis, for the
/// smallest exponent whose grid of 255 cells holds them all after the decoding's rounding.
void quantise_axis(const float* lo, const float* hi, int n, float& origin, float& cell_out,
                   std::uint8_t* q_lo, std::uint8_t* q_hi) {
  float node_lo = std::numeric_limits<float>::infinity(), node_hi = -std::numeric_limits<float>::infinity();
  for (int i = 0; i < n; ++i) {
    node_lo = std::min(node_lo, lo[i]);
    node_hi = std::max(node_hi, hi[i]);
  }
  origin = grid_origin(node_lo);
  const double extent = static_cast<double>(node_hi) - static_cast<double>(origin);
  int e = extent > 0.0 ? std::max(kMinExponent, static_cast<int>(std::ceil(std::log2(extent / 255.0)))) : kMinExponent;
  for (; e <= kMaxExponent; ++e) {
    const float cell = std::ldexp(1.0f, e);
    const double cell_d = std::ldexp(1.0, e);
    bool fits = true;
    for (int i = 0; i < n && fits; ++i) {
      double a = std::floor((static_cast<double>(lo[i]) - origin) / cell_d);
      int ql = static_cast<int>(std::clamp(a, 0.0, 255.0));
      while (ql > 0 && decode_compressed_plane(origin, cell, static_cast<std::uint8_t>(ql)) > lo[i]) --ql;
      double b = std::ceil((static_cast<double>(hi[i]) - origin) / cell_d);
      int qh = static_cast<int>(std::clamp(b, 0.0, 255.0));
      while (qh < 255 && decode_compressed_plane(origin, cell, static_cast<std::uint8_t>(qh)) < hi[i]) ++qh;
      fits = decode_compressed_plane(origin, cell, static_cast<std::uint8_t>(ql)) <= lo[i] &&
             decode_compressed_plane(origin, cell, static_cast<std::uint8_t>(qh)) >= hi[i];
      q_lo[i] = static_cast<std::uint8_t>(ql);
      q_hi[i] = static_cast<std::uint8_t>(qh);
    }
    if (fits) {
      cell_out = cell;
      return;
    }
  }
  throw std::length_error("compressed wide BVH: a node's boxes do not fit an 8-bit grid of normal float cells");
}

}  // namespace

template <int N>
CompressedWideBvh<N> compress_wide_bvh(WideBvh<N>&& wide) {
  CompressedWideBvh<N> out;
  out.root_box = wide.root_box;
  out.packets = std::move(wide.packets);
  out.nodes.reserve(wide.nodes.size());
  advise_huge_pages(out.nodes.data(), out.nodes.capacity() * sizeof(CompressedWideBvhNode<N>));
  out.nodes.resize(wide.nodes.size());
  for (std::size_t k = 0; k < wide.nodes.size(); ++k) {
    const WideBvhNode<N>& w = wide.nodes[k];
    CompressedWideBvhNode<N>& c = out.nodes[k];
    const int n = static_cast<int>(w.used);
    for (int a = 0; a < 3; ++a) {
      std::fill_n(c.planes[a], N, std::uint8_t{255});
      std::fill_n(c.planes[3 + a], N, std::uint8_t{0});
      if (n > 0) quantise_axis(w.bounds[a], w.bounds[3 + a], n, c.origin[a], c.cell[a], c.planes[a], c.planes[3 + a]);
      else c.origin[a] = 0.0f, c.cell[a] = 1.0f;
    }
    for (int i = 0; i < N; ++i) c.child[i] = w.child[i];
    c.used = w.used;
  }
  wide.nodes = {};
  return out;
}

template CompressedWideBvh<8> compress_wide_bvh<8>(WideBvh<8>&&);

}  // namespace raylab
