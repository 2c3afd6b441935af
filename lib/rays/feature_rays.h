#pragma once
/// Rays aimed exactly at the edges and vertices of a triangle mesh: the adversarial rays of the
/// watertightness test (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT
/// 2(1) 2013).
///
/// Each ray crosses the surface from the outside (the side the adjacent faces' normals point
/// to) at a point of an edge or at a vertex, so on a closed, consistently oriented mesh the
/// exact line enters the solid there and a watertight kernel must report a hit at t ≈ 1, while
/// Möller–Trumbore, whose edge tests of neighbouring triangles round independently, may let the
/// ray slip through the crack between them.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "geometry/ray.h"
#include "geometry/triangle_mesh.h"

namespace raylab {

enum class MeshFeature { edge, vertex };

/// `n` rays aimed at features of `mesh` (at least one non-degenerate triangle is required; the
/// function throws InputError otherwise).
///
/// Vertices are welded by position and an edge is an unordered pair of welded vertices, so
/// triangle soups count shared edges once. A feature (edge or vertex of a triangle with a
/// non-zero cross product in double) is picked uniformly. The target p is the vertex itself
/// (exact) or a + s·(b − a) with s uniform in (0, 1), computed in double and rounded to float
/// (on the edge up to that rounding). n is the area-weighted mean normal of the adjacent
/// triangles (any adjacent face normal if the mean is zero). The direction w is uniform in the
/// cone about −n of half-angle min(30°, (90° − θ)/2), θ the largest angle between n and an
/// adjacent face normal, so the ray never grazes an adjacent face. Features with θ > 80° (folds
/// and fins, seen in silhouette from every direction) and features touching a zero-area
/// triangle (never hit, so the surface is cracked there) are skipped unless every feature is one.
/// The origin is
/// o = p − δ·w, δ = `distance`, rounded to float; the direction is p − o in double, rounded;
/// tmin = 0, tmax = inf. Deterministic for a given seed.
std::vector<Ray> feature_rays(const TriangleMesh& mesh, MeshFeature feature, std::size_t n, double distance,
                              std::uint64_t seed);

}  // namespace raylab
