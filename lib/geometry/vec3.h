#pragma once
/// 3-vectors. `Vec3f` is the storage and traversal type (32-bit floats, as meshes are stored);
/// `Vec3d` is used where a kernel needs extra precision (the watertight fallback, samplers).
#include <algorithm>
#include <cmath>
#include <cstddef>

namespace raylab {

template <class T>
struct Vec3 {
  T x{}, y{}, z{};

  constexpr Vec3() = default;
  constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3(T s) : x(s), y(s), z(s) {}
  template <class U>
  constexpr explicit Vec3(const Vec3<U>& o) : x(static_cast<T>(o.x)), y(static_cast<T>(o.y)), z(static_cast<T>(o.z)) {}

  constexpr T operator[](std::size_t i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr T& operator[](std::size_t i) { return i == 0 ? x : (i == 1 ? y : z); }

  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator*(const Vec3& o) const { return {x * o.x, y * o.y, z * o.z}; }
  constexpr Vec3 operator/(const Vec3& o) const { return {x / o.x, y / o.y, z / o.z}; }
  constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vec3& o) const = default;
};

template <class T> constexpr Vec3<T> operator*(T s, const Vec3<T>& v) { return v * s; }
template <class T> constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> inline T length(const Vec3<T>& v) { return std::sqrt(dot(v, v)); }
template <class T> inline Vec3<T> normalize(const Vec3<T>& v) { return v / length(v); }
template <class T> constexpr Vec3<T> min(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <class T> constexpr Vec3<T> max(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
template <class T> inline Vec3<T> abs(const Vec3<T>& v) { return {std::abs(v.x), std::abs(v.y), std::abs(v.z)}; }
template <class T> constexpr T max_component(const Vec3<T>& v) { return std::max(v.x, std::max(v.y, v.z)); }
template <class T> constexpr T min_component(const Vec3<T>& v) { return std::min(v.x, std::min(v.y, v.z)); }
/// Index of the component of largest magnitude.
template <class T> inline int max_abs_axis(const Vec3<T>& v) {
  const Vec3<T> a = abs(v);
  return a.x >= a.y ? (a.x >= a.z ? 0 : 2) : (a.y >= a.z ? 1 : 2);
}
template <class T> inline bool is_finite(const Vec3<T>& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

}  // namespace raylab
