#include "accel/bvh/quantized_wide_node.h"

#include "accel/common/huge_pages.h"
#include "geometry/float_mode.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace raylab {

namespace {

constexpr int kMinStepExponent = -120;  // q·step stays normal for q >= 1 (FTZ/DAZ leave it alone)
constexpr int kMaxStepExponent = 127;

/// A plane the traversal reads the same with and without flush-to-zero: 0 or a normal float.
bool normal_or_zero(float x) { return x == 0.0f || std::abs(x) >= std::numeric_limits<float>::min(); }

/// The largest byte whose plane lies at or below `lo` (0's plane, the origin, always does).
std::uint8_t quantize_down(float lo, float step, float origin) {
  const double guess = std::floor((static_cast<double>(lo) - origin) / step);
  int q = static_cast<int>(std::clamp(guess, 0.0, 255.0));
  while (q > 0 && !(dequantize(static_cast<std::uint8_t>(q), step, origin) <= lo &&
                    normal_or_zero(dequantize(static_cast<std::uint8_t>(q), step, origin))))
    --q;
  return static_cast<std::uint8_t>(q);
}

/// The least byte whose plane lies at or above `hi`, or -1 when none does.
int quantize_up(float hi, float step, float origin) {
  const double guess = std::ceil((static_cast<double>(hi) - origin) / step);
  if (guess > 255.0) return -1;
  for (int q = static_cast<int>(std::max(guess, 0.0)); q <= 255; ++q) {
    const float plane = dequantize(static_cast<std::uint8_t>(q), step, origin);
    if (plane >= hi && normal_or_zero(plane)) return q;
  }
  return -1;
}

}  // namespace

template <int N>
QuantizedWideBvhNode<N> quantize_wide_node(const WideBvhNode<N>& node) {
  // Under DAZ a subnormal bound would compare as 0: the planes are chosen against the real bounds.
  const FloatModeScope ieee(false);
  QuantizedWideBvhNode<N> out{};
  out.used = node.used;
  for (int i = 0; i < N; ++i) out.child[i] = node.child[i];
  const int used = static_cast<int>(node.used);
  for (int a = 0; a < 3; ++a) {
    float lo = std::numeric_limits<float>::infinity(), hi = -std::numeric_limits<float>::infinity();
    for (int i = 0; i < used; ++i) {
      lo = std::min(lo, node.bounds[a][i]);
      hi = std::max(hi, node.bounds[3 + a][i]);
    }
    if (used == 0) lo = hi = 0.0f;
    if (!std::isfinite(lo) || !std::isfinite(hi))
      throw std::invalid_argument("quantize_wide_node: a child box is empty or not finite");
    // A subnormal origin would read as 0 under DAZ: round it outward to 0 or -FLT_MIN.
    if (!normal_or_zero(lo)) lo = lo > 0.0f ? 0.0f : -std::numeric_limits<float>::min();
    // The least power of two whose 255 steps span the extent (computed in double: hi - lo may
    // overflow in float); larger ones where rounding at the origin's magnitude leaves the top
    // plane short of some child's upper bound.
    const double extent = static_cast<double>(hi) - lo;
    int e = kMinStepExponent;
    if (extent > 0.0) e = std::max(e, static_cast<int>(std::ceil(std::log2(extent / 255.0))));
    for (;; ++e) {
      if (e > kMaxStepExponent) throw std::logic_error("quantize_wide_node: no step spans the node");
      const float step = std::ldexp(1.0f, e);
      std::uint8_t q[6][N] = {};
      bool fits = true;
      for (int i = 0; i < used && fits; ++i) {
        q[a][i] = quantize_down(node.bounds[a][i], step, lo);
        const int up = quantize_up(node.bounds[3 + a][i], step, lo);
        fits = up >= 0;
        if (fits) q[3 + a][i] = static_cast<std::uint8_t>(up);
      }
      if (!fits) continue;
      out.origin[a] = lo;
      out.step[a] = step;
      for (int i = 0; i < N; ++i) {
        out.q[a][i] = q[a][i];
        out.q[3 + a][i] = q[3 + a][i];
      }
      break;
    }
  }
  return out;
}

template <int N>
QuantizedWideBvh<N> quantize_wide_bvh(WideBvh<N>&& wide) {
  QuantizedWideBvh<N> out;
  out.nodes.reserve(wide.nodes.size());
  advise_huge_pages(out.nodes.data(), out.nodes.capacity() * sizeof(QuantizedWideBvhNode<N>));
  for (const WideBvhNode<N>& n : wide.nodes) out.nodes.push_back(quantize_wide_node(n));
  out.packets = std::move(wide.packets);
  out.root_box = wide.root_box;
  wide = WideBvh<N>{};
  return out;
}

template QuantizedWideBvhNode<4> quantize_wide_node<4>(const WideBvhNode<4>&);
template QuantizedWideBvhNode<8> quantize_wide_node<8>(const WideBvhNode<8>&);
template QuantizedWideBvh<4> quantize_wide_bvh<4>(WideBvh<4>&&);
template QuantizedWideBvh<8> quantize_wide_bvh<8>(WideBvh<8>&&);

}  // namespace raylab
