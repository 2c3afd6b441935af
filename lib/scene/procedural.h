#pragma once
/// Procedural scenes for the lecture's cases and for scale. Every generator is deterministic:
/// random ones draw from std::mt19937_64 seeded with `seed` (default 1). Coordinates: y is up.
/// Parameter ranges are checked by the spec parser (scene_spec.cpp), which documents them in
/// `scene_kinds()`; the functions here throw InputError for values outside the ranges below.
#include <cstdint>
#include <memory>
#include <vector>

#include "geometry/ray.h"
#include "geometry/triangle_mesh.h"
#include "scene/scene.h"

namespace raylab {

/// A UV sphere: `stacks` bands in latitude, `slices` in longitude, closed by a triangle fan
/// at each pole; shared vertices, outward counter-clockwise winding, 2·slices·(stacks-1)
/// triangles. stacks >= 2, slices >= 3.
TriangleMesh uv_sphere(const Vec3f& center, float radius, int stacks, int slices);

/// `sphere:n=N,radius=R` — a UV sphere of about N triangles (slices = 2·stacks), centred at the
/// origin. n in [8, 2^27], default 5000; radius default 1.
struct SphereConfig {
  std::int64_t triangles = 5000;
  double radius = 1.0;
};
Scene make_sphere(const SphereConfig& c);

/// `sphereflake:depth=D,as=spheres|triangles,tess=T` — Haines' sphereflake from the Standard
/// Procedural Databases (Haines, "A Proposal for Standard Graphics Environments", IEEE CG&A
/// 7(11), 1987): a unit sphere at the origin carries nine spheres of a third of its radius
/// (six around its equator, three above it, relative to the direction it grew from), each of
/// which carries nine more, to `depth` levels: (9^(depth+1) - 1) / 8 spheres. depth in [0, 7],
/// default 4 (7381 spheres, SPD's size factor 4). as=triangles tessellates every sphere as a UV
/// sphere with `tess` stacks and 2·tess slices (tess in [2, 64], default 8: 224 triangles).
struct SphereflakeConfig {
  int depth = 4;
  bool as_triangles = false;
  int tess = 8;
};
Scene make_sphereflake(const SphereflakeConfig& c);

/// `stadium:object=SPEC,ratio=R,segments=S,tiers=K` — the "teapot in a stadium" problem named
/// by Eric Haines in the Ray Tracing News (a small detailed object in a large sparse scene,
/// which defeats uniform grids): a flat
/// elliptical ground (a fan of `segments` triangles) ringed by `tiers` stepped stands (a tread
/// and a riser per tier and segment, 4 triangles each), the field's length R times the object's
/// bounding-box diagonal. The object (default `sphere:n=5000`) stands on the ground at one goal
/// line. ratio in [1, 1e6], default 1000; segments in [8, 4096], default 96; tiers in [1, 256],
/// default 8 (3168 stadium triangles). The object must not be instanced.
struct StadiumConfig {
  double ratio = 1000.0;
  int segments = 96;
  int tiers = 8;
};
Scene make_stadium(const Scene& object, const StadiumConfig& c);

/// `grass:blades=N,height=H,width=W,seed=S` — N blades of identical size, each a tapered,
/// leaning strip of 3 triangles, uniformly distributed (position and heading) on the unit
/// square field [0,1]x[0,1] of the xz plane. blades in [1, 2^26], default 10000; height default
/// 0.05; width default 0.004.
struct GrassConfig {
  std::int64_t blades = 10000;
  double height = 0.05, width = 0.004;
  std::uint64_t seed = 1;
};
Scene make_grass(const GrassConfig& c);

/// `walls:n=N,angle=DEG,length=L,thickness=T,spacing=D` — N long thin walls (boxes of 12
/// triangles, length L along x, height 1, thickness T) in parallel rows D apart, the rows laid
/// out so the whole block is roughly square, then rotated by DEG degrees about the vertical
/// axis through its centre (a rotation away from the axes defeats axis-aligned splits).
/// n in [1, 2^24], default 100; angle in [-360, 360], default 30; length default 10;
/// thickness default 0.05; spacing default 0.5.
struct WallsConfig {
  std::int64_t walls = 100;
  double angle_degrees = 30.0, length = 10.0, thickness = 0.05, spacing = 0.5;
};
Scene make_walls(const WallsConfig& c);

/// `room:of=SPEC,margin=M,window=W` — the object SPEC inside a room: an axis-aligned box around
/// the object's bounding box, grown on every side by M times the box's largest extent.
/// With W > 0 the three faces turned to the default camera (+x, +y, +z) each have a central
/// square window of W times the face's side, so an outside camera sees the object; the other
/// faces are solid. Of diffuse rays from all the surfaces the outside camera sees (the frames'
/// outsides included) about 37% hit, against a few percent for the bare object.
/// With W = 0 every face is solid: a closed room, the path-tracing workload in which every
/// bounce hits; trace it with rays from an inside camera (`diffuse:N,camera=inside`,
/// rays/ray_generators.h). margin in [0.01, 100], default 0.25; window 0 or in [0.05, 0.95],
/// default 0.8.
struct RoomConfig {
  double margin = 0.25;
  double window = 0.8;
};
Scene make_room(const Scene& object, const RoomConfig& c);

/// `soup:n=N,size=S,seed=K` — N independent random triangles inside the unit cube: each has a
/// uniform random centre and corners offset from it uniformly in [-S/2, S/2]^3 (clamped to the
/// cube). n in [1, 2^27], default 10000; size default 0 = N^(-1/3) (about one cell of an
/// N-cell grid).
struct SoupConfig {
  std::int64_t triangles = 10000;
  double size = 0.0;
  std::uint64_t seed = 1;
};
Scene make_soup(const SoupConfig& c);

/// The scenes where |Image| x log|Objects| fails (the lecture's opening claim, tested in
/// experiments/exp_image_log_objects.cpp): each defeats every structure that bounds its cells by
/// axis-aligned boxes in its own way.

/// `dust:n=N,size=S,seed=K` — N tiny random triangles in the unit cube (a soup, make_soup, of
/// triangle size S; default 0 = 0.1/√N, so that N·S², the expected number of triangles a line
/// through the cube meets, stays about 0.01 as N grows). Almost every ray escapes, and a ray that
/// hits nothing crosses every cell along its chord: ∝ N^(1/3) cells of a grid of ∛N cells per
/// axis, and as many leaves of a balanced tree. n in [1, 2^27], default 10000; size in [0, 1].
struct DustConfig {
  std::int64_t triangles = 10000;
  double size = 0.0;
  std::uint64_t seed = 1;
};
Scene make_dust(const DustConfig& c);

/// `needles:n=N,length=L,width=W` — N parallel needles (each one long thin triangle) along the
/// cube diagonal (1,1,1)/√3, centred on a ⌈√N⌉×⌈√N⌉ lattice of side 0.2 in the plane through
/// (0.5, 0.5, 0.5) perpendicular to it. A needle of length L spans L/√3 along every axis, far more
/// than the lattice, so the bounding boxes of all needles overlap in most of the scene and every
/// ray that meets one box meets nearly all: boxes cannot separate the needles, only cuts of the
/// needles themselves (split clipping) can. n in [1, 2^27], default 1024; length default 1.5;
/// width (of a needle at its middle) default 0 = a quarter of the lattice spacing.
struct NeedlesConfig {
  std::int64_t needles = 1024;
  double length = 1.5;
  double width = 0.0;
};
Scene make_needles(const NeedlesConfig& c);

/// `fan:n=N,radius=R,height=H` — a vertex of valence N: the cone of N triangles from the apex
/// (0, H, 0) to N points evenly spaced on the circle of radius R in the plane y = 0 (open at the
/// bottom; outward counter-clockwise winding). Every triangle's bounding box contains the apex
/// and reaches out to the rim, so a point of the cone lies in the boxes of a constant fraction
/// of the triangles: any box-bounded hierarchy tests ∝ N triangles near the apex. n in
/// [3, 2^27], default 4096; radius default 1; height default 0.5.
struct FanConfig {
  std::int64_t triangles = 4096;
  double radius = 1.0, height = 0.5;
};
Scene make_fan(const FanConfig& c);

/// `row:n=N,gap=G,radius=R` — a near-miss row: N triangles in the planes x = (i + 1/2)/N,
/// i = 0 .. N-1, each with one edge at distance G from the x axis (its supporting line
/// perpendicular to the radius at angle i·(golden angle) about the axis, the edge 2R long) and
/// its third vertex at distance R on that radius. A ray along the axis passes within G of every
/// triangle, inside the bounding boxes of most of them, and hits none (near_miss_row_rays). n in
/// [1, 2^27], default 1024; gap in (0, R/4], default 0.001; radius default 0.25.
struct NearMissRowConfig {
  std::int64_t triangles = 1024;
  double gap = 1e-3, radius = 0.25;
};
Scene make_near_miss_row(const NearMissRowConfig& c);

/// `n` rays along the axis of make_near_miss_row(c): origins at x = -0.05 within G/4 of the
/// axis, unit directions within G/(8·1.1) radians of +x, so that each ray stays within G/2 of
/// the axis over the row and misses every triangle. Deterministic for a given seed.
std::vector<Ray> near_miss_row_rays(const NearMissRowConfig& c, std::size_t n, std::uint64_t seed);

/// `subdivided:of=SPEC,levels=K` — Loop subdivision (Loop, "Smooth Subdivision Surfaces Based
/// on Triangles", MSc thesis, Utah 1987) of a triangle scene via OpenMesh's LoopT; each level
/// multiplies the triangle count by 4. levels in [0, kMaxSubdivisionLevels], default 1; refused,
/// before anything is allocated, when the result (T·4^levels triangles) would exceed
/// subdivision_triangle_limit(), and when the scene has spheres or instances.
Scene make_subdivided(const Scene& of, int levels);

/// 4^14 > 2^27: past 13 levels not even one triangle stays within the limit.
inline constexpr int kMaxSubdivisionLevels = 13;

/// Peak memory of make_subdivided per output triangle, an upper estimate (OpenMesh's halfedge
/// mesh with LoopT's properties, then the TriangleMesh): the peak RSS of `raylab info` on
/// subdivided:of=cgal:bunny00 was 83 bytes per triangle at levels=3 (4.8 M triangles) and 80 at
/// levels=4 (19.3 M), rounded up.
inline constexpr double kSubdivisionBytesPerTriangle = 96;

/// The most triangles make_subdivided makes: 2^27, and no more than the machine's physical
/// memory (sysconf _SC_PHYS_PAGES; ignored when unknown) holds at kSubdivisionBytesPerTriangle.
std::uint64_t subdivision_triangle_limit();

/// `decimated:of=SPEC,faces=N` — quadric-error edge-collapse decimation (Garland & Heckbert,
/// "Surface Simplification Using Quadric Error Metrics", SIGGRAPH 1997) via OpenMesh's
/// DecimaterT + ModQuadricT, down to about N faces (a mesh already at most N is kept).
/// faces in [1, 2^27], default 1000; triangles only.
Scene make_decimated(const Scene& of, std::int64_t faces);

/// `instances:of=SPEC,count=N,seed=S` — N copies of a base scene on a cubic grid (spacing 1.5
/// times the base's bounding-box diagonal), each turned by a small deterministic random
/// rotation (up to 15 degrees about a random axis). Only the instances are stored (104 bytes
/// each: transform and base index), so N is capped at 2^24 (1.7 GB); kLectureInstancedSceneSpec below makes the lecture's
/// 3.1 billion triangles from 10,300 of them. The base must be non-empty and not itself instanced.
struct InstancesConfig {
  std::int64_t count = 1000;
  std::uint64_t seed = 1;
};
Scene make_instances(std::shared_ptr<const Scene> base, const InstancesConfig& c);

/// `transformed:of=SPEC,rotate=AXIS:DEG,translate=X:Y:Z,scale=S` — a scene placed under the
/// similarity p -> translate + scale·R(AXIS, DEG)·p, so that "far from the origin" (translate
/// 1e6:0:0) and "tiny" (scale=1e-6) are one spec away. AXIS is x, y, z or a vector a;b;c (not 0).
/// The transform is applied in double to every vertex and sphere centre, then rounded to float
/// (radius: scale·radius rounded); an instanced scene keeps its bases and composes the transform
/// with every instance's. scale in [1e-30, 1e30], default 1; DEG default 0; translate default 0.
struct TransformedConfig {
  Vec3d axis{0.0, 0.0, 1.0};
  double degrees = 0.0;
  Vec3d translate{0.0, 0.0, 0.0};
  double scale = 1.0;
};
Scene make_transformed(const Scene& of, const TransformedConfig& c);

/// The lecture's largest scene, "3.1 billion triangles" by instancing: 10,300 instances (a
/// 22x22x22 grid, partly filled) of the Stanford bunny (cgal:bunny00, 75,408 triangles) after
/// one level of Loop subdivision (301,632 triangles): 3,106,809,600 triangles. Only the base
/// mesh and the transforms are stored; accelerators build once on the base and put the
/// instances in a BVH top level (accel_factory.h, make_instanced_aggregate).
inline constexpr const char* kLectureInstancedSceneSpec =
    "instances:of=(subdivided:of=cgal:bunny00,levels=1),count=10300";

}  // namespace raylab
