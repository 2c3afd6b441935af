#pragma once
/// Isotropic random lines: the lines that meet a ball, drawn from the motion-invariant measure
/// on lines (Santaló, "Integral Geometry and Geometric Probability", 1976, ch. 12-14). Under
/// this measure the Cauchy-Crofton formulas hold: for convex K ⊂ L ⊂ ball, P(line meets K |
/// line meets L) = area(K) / area(L), and the mean chord of K over the lines that meet it is
/// 4·volume(K) / area(K). These are the probabilities the lecture's cost models (SAH) assume.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry/ray.h"
#include "geometry/vec3.h"

namespace raylab {

/// `n` lines that meet the ball (centre, radius): a direction d uniform on the unit sphere, then
/// a point q uniform on the disk of that radius through the centre perpendicular to d. Each ray
/// starts at q − radius·d, on the plane tangent to the ball behind it, with unit direction d,
/// tmin = 0 and tmax = inf, so t ≥ 0 covers the whole chord. Computed in double, rounded to
/// float. Deterministic for a given seed.
std::vector<Ray> isotropic_lines(const Vec3d& centre, double radius, std::size_t n, std::uint64_t seed);

}  // namespace raylab
