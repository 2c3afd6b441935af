#include "accel/common/hit_comparison.h"

#include <cmath>
#include <stdexcept>

namespace raylab {

HitComparison compare_hits(const std::vector<Ray>& rays, const std::vector<Hit>& hits, const std::vector<Hit>& reference,
                           double scene_diagonal) {
  if (rays.size() != hits.size() || rays.size() != reference.size())
    throw std::invalid_argument("compare_hits: rays, hits and reference differ in size");
  HitComparison c;
  c.rays = rays.size();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& h = hits[i];
    const Hit& r = reference[i];
    bool mismatch = false;
    if (h.valid() && !r.valid()) {
      ++c.false_hits;
      mismatch = true;
    } else if (!h.valid() && r.valid()) {
      ++c.missed_hits;
      mismatch = true;
    } else if (h.valid()) {
      const double dir_len = length(Vec3d(rays[i].dir));
      const double tol =
          kHitTolerance * (std::abs(double(r.t)) + (length(Vec3d(rays[i].org)) + scene_diagonal) / dir_len);
      if (!(std::abs(double(h.t) - double(r.t)) <= tol)) {
        ++c.wrong_t;
        mismatch = true;
      } else if (h.prim != r.prim || h.instance != r.instance) {
        ++c.ties;
      }
    }
    if (mismatch) {
      ++c.mismatches;
      if (c.first_mismatches.size() < 16) c.first_mismatches.push_back(i);
    }
  }
  return c;
}

HitComparison compare_occlusion(const std::vector<std::uint8_t>& blocked, const std::vector<std::uint8_t>& reference) {
  if (blocked.size() != reference.size()) throw std::invalid_argument("compare_occlusion: sizes differ");
  HitComparison c;
  c.rays = blocked.size();
  for (std::size_t i = 0; i < blocked.size(); ++i) {
    if (bool(blocked[i]) == bool(reference[i])) continue;
    if (blocked[i]) ++c.false_hits;
    else ++c.missed_hits;
    ++c.mismatches;
    if (c.first_mismatches.size() < 16) c.first_mismatches.push_back(i);
  }
  return c;
}

}  // namespace raylab
