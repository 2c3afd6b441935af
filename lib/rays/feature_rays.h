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

/// weld[i] = the smallest vertex index with the same position as vertex i.
std::vector<std::uint32_t> weld_vertices(const TriangleMesh& mesh);

/// A ray exactly through `p`: its direction is `w` with every component rounded to 8 significant
/// bits (components below 2^-8 of the largest set to 0), its origin p - 2^k·d with the smallest
/// k >= log2(distance / |w|) (up to 40 more) for which every coordinate is a float, so that
/// o + 2^k·d = p holds exactly. tmin = 0, tmax = inf. False when no such k exists (or w is 0).
bool ray_exactly_through(const Vec3f& p, const Vec3d& w, double distance, Ray& out);

/// `n` rays that touch the mesh at a vertex without crossing it there (touching rays, the
/// class of geometry/exact_contact.h): each passes exactly through a vertex v (ray_exactly_through,
/// at distance `distance`) in a direction w = (tangent + tan(β)·normal) with a uniform tangent
/// direction of the plane normal to the mean normal of v's fan and β uniform within ± the fan's
/// spread (the largest angle between the mean normal and a face normal; flat fans are skipped),
/// kept when some faces of the fan face w and some face away, and the exact classification
/// against v's fan says the ray first meets the fan at v and touches it there: w lies outside
/// the fan's tangent cone and its mirror. Directions are
/// retried (64 per vertex, then another vertex). Deterministic for a given seed. Throws
/// InputError when fewer than n can be made from 4·n + 64 vertices (no vertex with a touching
/// direction: e.g. a flat mesh).
std::vector<Ray> touching_vertex_rays(const TriangleMesh& mesh, std::size_t n, double distance, std::uint64_t seed);

/// `n` rays aimed at points of silhouette edges, grazing: for an edge shared by two triangles
/// with unit normals n1, n2 (not coplanar), a direction in the wedge where the two faces lie on
/// the same side of the line, w = (n1 - n2) + γ·(n1 + n2) with |γ| < (1 - n1·n2)/(1 + n1·n2)
/// (half of the rays uniform in the wedge, half within a relative 10^-6..1 of its ends, nearly in
/// one face's plane), plus a uniform component along the edge of up to 60°; the target is a
/// uniform point of the edge rounded to float, so the ray passes within rounding of the edge:
/// touching, a near-miss or a crossing by a few ulps (ill-conditioned rays). Origin at
/// `distance` before the target. Deterministic for a given seed. Throws InputError when the mesh
/// has no edge shared by two non-coplanar triangles.
std::vector<Ray> grazing_edge_rays(const TriangleMesh& mesh, std::size_t n, double distance, std::uint64_t seed);

}  // namespace raylab
