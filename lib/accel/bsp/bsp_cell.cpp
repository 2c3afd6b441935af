#include "accel/bsp/bsp_cell.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace raylab {

ConvexCell::ConvexCell(const Bounds3f& box) {
  const Vec3d lo(box.lo), hi(box.hi);
  auto corner = [&](int i) { return Vec3d(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z); };
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& q : quads) faces_.push_back({corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])});
}

namespace {

double polygon_area(const std::vector<Vec3d>& poly) {
  Vec3d sum(0.0);
  for (std::size_t i = 1; i + 1 < poly.size(); ++i) sum += cross(poly[i] - poly[0], poly[i + 1] - poly[0]);
  return 0.5 * length(sum);
}

/// The part of `poly` with sign·distance >= 0; crossing points are appended to `cap`.
std::vector<Vec3d> clip_polygon(const std::vector<Vec3d>& poly, const BspPlane& plane, double sign,
                                std::vector<Vec3d>* cap) {
  std::vector<Vec3d> out;
  auto emit = [&](const Vec3d& p) {
    if (out.empty() || !(out.back() == p)) out.push_back(p);
  };
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec3d& a = poly[i];
    const Vec3d& b = poly[(i + 1) % poly.size()];
    const double da = sign * plane.signed_distance(a), db = sign * plane.signed_distance(b);
    if (da >= 0.0) emit(a);
    if (da == 0.0 && cap) cap->push_back(a);
    if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      // The same expression from both ends of a shared edge, so neighbouring faces agree.
      const bool forward = std::make_pair(a.x, std::make_pair(a.y, a.z)) < std::make_pair(b.x, std::make_pair(b.y, b.z));
      const Vec3d& u = forward ? a : b;
      const Vec3d& w = forward ? b : a;
      const double du = plane.signed_distance(u), dw = plane.signed_distance(w);
      const Vec3d p = u + (w - u) * (du / (du - dw));
      emit(p);
      if (cap) cap->push_back(p);
    }
  }
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out.size() >= 3 ? out : std::vector<Vec3d>{};
}

/// The convex polygon through `points` (all on `plane`), ordered by angle about their centroid.
std::vector<Vec3d> order_cap(std::vector<Vec3d> points, const Vec3d& normal) {
  auto key = [](const Vec3d& p) { return std::make_tuple(p.x, p.y, p.z); };
  std::sort(points.begin(), points.end(), [&](const Vec3d& a, const Vec3d& b) { return key(a) < key(b); });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return {};
  Vec3d c(0.0);
  for (const auto& p : points) c += p;
  c = c / static_cast<double>(points.size());
  const Vec3d n = normalize(normal);
  const Vec3d u = normalize(std::abs(n.x) > 0.5 ? cross(n, Vec3d(0, 1, 0)) : cross(n, Vec3d(1, 0, 0)));
  const Vec3d v = cross(n, u);
  std::sort(points.begin(), points.end(), [&](const Vec3d& a, const Vec3d& b) {
    return std::atan2(dot(a - c, v), dot(a - c, u)) < std::atan2(dot(b - c, v), dot(b - c, u));
  });
  return points;
}

}  // namespace

double ConvexCell::surface_area() const {
  double a = 0.0;
  for (const auto& f : faces_) a += polygon_area(f);
  return a;
}

Bounds3f ConvexCell::bounds() const {
  Vec3d lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const auto& f : faces_)
    for (const Vec3d& p : f) {
      lo = min(lo, p);
      hi = max(hi, p);
    }
  Bounds3f b;
  if (faces_.empty()) return b;
  for (int k = 0; k < 3; ++k) {
    // The vertices carry the rounding of the clipping; widen by a relative 1e-9 before
    // rounding outward to float.
    const double l = lo[k] - 1e-9 * (std::abs(lo[k]) + 1e-30), h = hi[k] + 1e-9 * (std::abs(hi[k]) + 1e-30);
    b.lo[k] = static_cast<float>(l);
    b.hi[k] = static_cast<float>(h);
    if (double(b.lo[k]) > l) b.lo[k] = std::nextafter(b.lo[k], -std::numeric_limits<float>::infinity());
    if (double(b.hi[k]) < h) b.hi[k] = std::nextafter(b.hi[k], std::numeric_limits<float>::infinity());
  }
  return b;
}

void ConvexCell::split(const BspPlane& plane, ConvexCell& negative, ConvexCell& positive) const {
  negative.faces_.clear();
  positive.faces_.clear();
  std::vector<Vec3d> cap;
  for (const auto& f : faces_) {
    auto n = clip_polygon(f, plane, -1.0, nullptr);
    if (!n.empty()) negative.faces_.push_back(std::move(n));
    auto p = clip_polygon(f, plane, 1.0, &cap);
    if (!p.empty()) positive.faces_.push_back(std::move(p));
  }
  auto poly = order_cap(std::move(cap), plane.normal);
  if (poly.size() >= 3 && !negative.faces_.empty() && !positive.faces_.empty()) {
    negative.faces_.push_back(poly);
    positive.faces_.push_back(std::move(poly));
  }
}

}  // namespace raylab
