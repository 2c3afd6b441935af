#pragma once
/// The report's columns of mismatches per class of first contact (accel/exact/contact_classes.h):
/// well-conditioned crossings (misses included), touching rays, rays starting on the surface, and
/// every ill-conditioned ray. Touching and on-surface rays are always ill-conditioned, so the last
/// column includes the two before it; the accuracy buckets (RayBucket) count each ray once, in the
/// first of ill-conditioned, touching, on-surface, crossing that applies.
#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <string>

#include "accel/common/hit_comparison.h"

namespace raylab::experiments {

struct ContactColumns {
  std::array<std::size_t, 4> rays{}, mismatches{};

  /// `c` must come from a comparison given the rays' classes.
  static ContactColumns of(const HitComparison& c) {
    const auto touching = static_cast<std::size_t>(Contact::touching);
    const auto on_surface = static_cast<std::size_t>(Contact::on_surface);
    const auto crossing = static_cast<std::size_t>(RayBucket::crossing);
    return {{c.bucket_rays[crossing], c.class_rays[touching], c.class_rays[on_surface], c.ill_conditioned},
            {c.bucket_mismatches[crossing], c.class_mismatches[touching], c.class_mismatches[on_surface],
             c.ill_conditioned_mismatches}};
  }

  void add(const ContactColumns& o) {
    for (std::size_t i = 0; i < rays.size(); ++i) rays[i] += o.rays[i], mismatches[i] += o.mismatches[i];
  }

  /// "| crossing, well-conditioned (N rays) | touching (N) | on-surface (N) | ill-conditioned, all (N) |", with
  /// these columns' ray counts.
  std::string header() const {
    return fmt::format("| crossing, well-conditioned ({} rays) | touching ({}) | on-surface ({}) | ill-conditioned, all "
                       "({}) |",
                       rays[0], rays[1], rays[2], rays[3]);
  }

  /// 100·k/n with two significant digits, without an exponent ("0.38", "7.3", "88", "100").
  static std::string percent(std::size_t k, std::size_t n) {
    const double p = 100.0 * static_cast<double>(k) / static_cast<double>(n);
    return p >= 10.0 ? fmt::format("{:.0f}", p) : fmt::format("{:.2g}", p);
  }

  /// " 0 | 12 (0.5%) | – | ... |": mismatches and their rate, "–" where the column has no ray.
  std::string cells() const {
    std::string s;
    for (std::size_t i = 0; i < rays.size(); ++i)
      s += rays[i] == 0       ? " – |"
           : mismatches[i] == 0 ? " 0 |"
                                : fmt::format(" {} ({}%) |", mismatches[i], percent(mismatches[i], rays[i]));
    return s;
  }
};

}  // namespace raylab::experiments
