#include "accel/bsp/bsp_cell.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace raylab {

ConvexCell::ConvexCell(const Bounds3f& box) {
  const Vec3d lo(box.lo), hi(box.hi);
  magnitude_ = std::max(max_component(max(abs(lo), abs(hi))), 0.0);
  box_ = Bounds3d(lo, hi);
  auto corner = [&](int i) { return Vec3d(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z); };
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& q : quads) faces_.push_back({corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])});
  orient_faces();
}

void ConvexCell::orient_faces() {
  Vec3d centre(0.0);
  std::size_t vertices = 0;
  for (const auto& f : faces_)
    for (const Vec3d& v : f) centre += v, ++vertices;
  if (vertices > 0) centre = centre / static_cast<double>(vertices);
  outward_.clear();
  for (const auto& f : faces_) {
    Vec3d area(0.0);
    for (std::size_t i = 0; i < f.size(); ++i) area += cross(f[i] - f[0], f[(i + 1) % f.size()] - f[0]);
    outward_.push_back(dot(area, f[0] - centre) >= 0.0 ? 1.0 : -1.0);
  }
}

namespace {

/// Bound on the rounding of one clipping step's arithmetic on a vertex coordinate (a handful of
/// double ulps), relative to the root box's magnitude, with a wide margin.
constexpr double kClipRounding = 1e-14;

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

bool ConvexCell::meets_line(const Vec3d& origin, const Vec3d& direction) const {
  // The line passes through a convex polygon exactly when it turns the same way around every
  // edge: the signs of dot(d, (a - o) x (b - o)) over the edges (a, b) do not differ.
  for (const auto& face : faces_) {
    bool positive = false, negative = false;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const double s = dot(direction, cross(face[i] - origin, face[(i + 1) % face.size()] - origin));
      positive = positive || s > 0.0;
      negative = negative || s < 0.0;
    }
    if (!(positive && negative)) return true;
  }
  return false;
}

double ConvexCell::surface_area() const {
  double a = 0.0;
  for (const auto& f : faces_) a += polygon_area(f);
  return a;
}

Bounds3f ConvexCell::bounds() const {
  Bounds3f b;
  if (faces_.empty()) return b;
  for (int k = 0; k < 3; ++k) {
    const double l = box_.lo[k], h = box_.hi[k];
    b.lo[k] = static_cast<float>(l);
    b.hi[k] = static_cast<float>(h);
    if (double(b.lo[k]) > l) b.lo[k] = std::nextafter(b.lo[k], -std::numeric_limits<float>::infinity());
    if (double(b.hi[k]) < h) b.hi[k] = std::nextafter(b.hi[k], std::numeric_limits<float>::infinity());
  }
  return b;
}

bool ConvexCell::estimate_split(const BspPlane& plane, SplitEstimate& e) const {
  // Each part's faces are the parts of this cell's faces on its side (their area vectors summed
  // as they are walked: Newell's formula, relative to the face's first vertex) and the cap, the
  // cell's section by the plane. The part is closed, so its outward face area vectors sum to
  // zero: the cap's area is the length of the sum of its other faces' outward area vectors.
  if (faces_.empty()) return false;
  Bounds3d neg_box, pos_box;
  bool any_neg = false, any_pos = false;
  Vec3d pos_outward(0.0);
  e.negative_area = e.positive_area = 0.0;
  for (std::size_t face = 0; face < faces_.size(); ++face) {
    const auto& f = faces_[face];
    const Vec3d base = f[0];
    Vec3d neg(0.0), pos(0.0);
    Vec3d neg_first, neg_prev, pos_first, pos_prev;
    bool neg_started = false, pos_started = false;
    auto emit = [](const Vec3d& q, Vec3d& first, Vec3d& prev, bool& started, Vec3d& sum) {
      if (started) sum += cross(prev, q);
      else first = q, started = true;
      prev = q;
    };
    const std::size_t m = f.size();
    const double d_first = plane.signed_distance(f[0]);
    double db = d_first;
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3d& a = f[i];
      const Vec3d& b = i + 1 < m ? f[i + 1] : f[0];
      const double da = db;  // each vertex's distance computed once, as the end of one edge and the start of the next
      db = i + 1 < m ? plane.signed_distance(b) : d_first;
      if (da <= 0.0) emit(a - base, neg_first, neg_prev, neg_started, neg), neg_box.extend(a);
      if (da >= 0.0) emit(a - base, pos_first, pos_prev, pos_started, pos), pos_box.extend(a);
      any_neg = any_neg || da < 0.0;
      any_pos = any_pos || da > 0.0;
      if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
        const Vec3d p = a + (b - a) * (da / (da - db));
        emit(p - base, neg_first, neg_prev, neg_started, neg);
        emit(p - base, pos_first, pos_prev, pos_started, pos);
        neg_box.extend(p);
        pos_box.extend(p);
      }
    }
    if (neg_started) neg += cross(neg_prev, neg_first);
    if (pos_started) pos += cross(pos_prev, pos_first);
    pos_outward += pos * outward_[face];
    e.negative_area += 0.5 * length(neg);
    e.positive_area += 0.5 * length(pos);
  }
  if (!any_neg || !any_pos) return false;
  const double cap = 0.5 * length(pos_outward);
  e.negative_area += cap;
  e.positive_area += cap;
  auto to_float = [](const Bounds3d& b) {
    Bounds3f out;
    for (int k = 0; k < 3; ++k) {
      out.lo[k] = std::nextafter(static_cast<float>(b.lo[k]), -std::numeric_limits<float>::infinity());
      out.hi[k] = std::nextafter(static_cast<float>(b.hi[k]), std::numeric_limits<float>::infinity());
    }
    return out;
  };
  e.negative_box = to_float(neg_box);
  e.positive_box = to_float(pos_box);
  return true;
}

void ConvexCell::split(const BspPlane& plane, ConvexCell& negative, ConvexCell& positive) const {
  negative.faces_.clear();
  positive.faces_.clear();
  // The exact cell's vertices on a side are the exact vertices there and the exact crossings of
  // the plane with the exact edges. A computed vertex v is within error_ of its exact one, so the
  // exact plane's value there is within err(v) = |n|_1·error_ + kBspRelError·scale·|v - o|_1 of
  // the computed d(v): v counts for each side it may lie on, and on an edge [u, w] that may
  // cross, the crossing's parameter from u lies in [f_lo, f_hi] from the bounds on d(u), d(w).
  const double n1 = std::abs(plane.normal.x) + std::abs(plane.normal.y) + std::abs(plane.normal.z);
  auto distance_error = [&](const Vec3d& v) {
    const Vec3d q = abs(v - plane.origin);
    return n1 * error_ + kBspRelError * plane.scale * (q.x + q.y + q.z);
  };
  Bounds3d neg_box, pos_box;
  double child_error = error_;
  for (const auto& f : faces_)
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3d& u = f[i];
      const Vec3d& w = f[(i + 1) % f.size()];
      const double du = plane.signed_distance(u), dw = plane.signed_distance(w);
      const double eu = distance_error(u), ew = distance_error(w);
      if (du <= eu) neg_box.extend(u);
      if (du >= -eu) pos_box.extend(u);
      const bool u_neg = du < -eu, u_pos = du > eu, w_neg = dw < -ew, w_pos = dw > ew;
      if ((u_neg && w_neg) || (u_pos && w_pos)) continue;
      // At the crossing f = |d(u)| / (|d(u)| + |d(w)|) of the exact values, each within eu, ew of
      // the computed ones; a vertex that may lie in the plane leaves its end of [0, 1] open.
      const double au = std::abs(du), aw = std::abs(dw);
      double f_lo = u_neg || u_pos ? (au - eu) / (au - eu + aw + ew) : 0.0;
      double f_hi = w_neg || w_pos ? (au + eu) / (au + eu + aw - ew) : 1.0;
      f_lo = std::clamp(f_lo, 0.0, 1.0);
      f_hi = std::clamp(f_hi, f_lo, 1.0);
      const Vec3d a = u + (w - u) * f_lo, b = u + (w - u) * f_hi;
      neg_box.extend(a);
      neg_box.extend(b);
      pos_box.extend(a);
      pos_box.extend(b);
      child_error = std::max(child_error, error_ + max_component(abs(w - u)) * (f_hi - f_lo));
    }
  child_error += kClipRounding * magnitude_;
  auto finish = [&](ConvexCell& c, Bounds3d box) {
    c.magnitude_ = magnitude_;
    c.error_ = child_error;
    box.lo = box.lo - Vec3d(child_error);
    box.hi = box.hi + Vec3d(child_error);
    c.box_ = intersect(box, box_);
  };
  finish(negative, neg_box);
  finish(positive, pos_box);

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
  negative.orient_faces();
  positive.orient_faces();
}

}  // namespace raylab
