// The uniform and nested grids against the exact oracle on the 3D-DDA's edge cases: rays along
// cell faces and cell edges (±0 direction components), rays starting inside the grid, rays
// missing it, rays with tmin > 0; plus the structure (CSR, resolution heuristic) and parameter
// errors. The oracle suite (test_oracle.cpp) covers the general scenes and ray sets.
#include <gtest/gtest.h>

#include <algorithm>

#include <random>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "accel/grid/uniform_grid.h"
#include "accel/nested_grid/nested_grid.h"
#include "geometry/input_error.h"
#include "geometry/spec_string.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

const std::vector<std::string> kGridSpecs = {"grid",           "grid:place=exact",          "grid:mailbox=off",
                                             "grid:d=0.5",     "grid:d=8",                  "nested-grid",
                                             "nested-grid:mode=two-level", "nested-grid:threshold=2,depth=4,place=exact"};

/// Rays in the boundary planes of the cells of `g`: along faces (one zero component, of either
/// sign), along edges (two zero components), and from inside the grid.
std::vector<Ray> edge_case_rays(const GridGeometry& g, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  auto inside = [&](int a) { return g.box.lo[a] + u01(rng) * (g.box.hi[a] - g.box.lo[a]); };
  auto plane = [&](int a) { return g.plane(a, std::uniform_int_distribution<int>(0, g.res[a])(rng)); };
  std::vector<Ray> rays;
  for (int n = 0; n < 600; ++n) {
    const int a = n % 3, b = (a + 1) % 3, c = (a + 2) % 3;
    const float zero = (n / 3) % 2 ? -0.0f : 0.0f;
    Ray r;
    // In a face plane of axis a: d[a] = ±0, the origin outside the grid along b.
    r.org[a] = plane(a);
    r.org[b] = g.box.lo[b] - 0.5f * (g.box.hi[b] - g.box.lo[b]);
    r.org[c] = inside(c);
    r.dir[a] = zero;
    r.dir[b] = 1.0f;
    r.dir[c] = u01(rng) - 0.5f;
    rays.push_back(r);
    // Along a cell edge: d[a] = d[c] = ±0.
    Ray e;
    e.org[a] = plane(a);
    e.org[c] = plane(c);
    e.org[b] = g.box.hi[b] + 1.0f;
    e.dir[a] = zero;
    e.dir[c] = -zero;
    e.dir[b] = -1.0f;
    rays.push_back(e);
    // From inside the grid, in a random direction, sometimes with tmin > 0.
    Ray i;
    i.org = {inside(0), inside(1), inside(2)};
    i.dir = {u01(rng) - 0.5f, u01(rng) - 0.5f, u01(rng) - 0.5f};
    if (n % 4 == 0) i.tmin = 0.05f;
    if (n % 5 == 0) i.dir[a] = zero;
    rays.push_back(i);
    // Missing the grid: beside it, parallel to a face.
    Ray m;
    m.org = {inside(0), inside(1), inside(2)};
    m.org[a] = g.box.hi[a] + 0.25f;
    m.dir = {0, 0, 0};
    m.dir[b] = 1.0f;
    rays.push_back(m);
  }
  return rays;
}

/// Every grid spec agrees with `reference` (the exact oracle; brute force with the grids' own
/// watertight kernel where rays lie in the planes of triangles, which no float kernel follows).
void expect_agrees_with_oracle(const std::string& scene_spec, std::shared_ptr<const Scene> scene,
                               const std::string& reference = "exact") {
  const auto oracle = make_accelerator(reference, scene);
  const auto layout = make_accelerator("grid", scene);
  const auto& grid = dynamic_cast<const UniformGrid&>(*layout);
  auto rays = edge_case_rays(grid.geometry(), 7);  // in the grid's frame (grid_frame.h): moved to the world
  for (Ray& r : rays) r.org = r.org + grid.frame_origin();
  const double diagonal = length(Vec3d(scene->bounds().diagonal()));
  const TraceResult exact = trace_rays(*oracle, rays, TraceOptions{1, false, false});
  const TraceResult exact_any = trace_rays(*oracle, rays, TraceOptions{1, false, true});
  ASSERT_GT(exact.hit_count, rays.size() / 10) << scene_spec;
  for (const auto& spec : kGridSpecs) {
    const auto accel = make_accelerator(spec, scene);
    for (bool counted : {false, true}) {
      const TraceResult got = trace_rays(*accel, rays, TraceOptions{1, counted, false});
      const HitComparison c = compare_hits(rays, got.hits, exact.hits, diagonal);
      EXPECT_EQ(c.mismatches, 0u) << spec << " on " << scene_spec << ": " << c.false_hits << " false, " << c.missed_hits
                                  << " missed, " << c.wrong_t << " wrong t; first ray "
                                  << (c.first_mismatches.empty() ? -1 : long(c.first_mismatches[0]));
      const TraceResult any = trace_rays(*accel, rays, TraceOptions{1, counted, true});
      EXPECT_EQ(compare_occlusion(any.blocked, exact_any.blocked).mismatches, 0u) << spec << " (any hit) on " << scene_spec;
    }
  }
}

TEST(GridDda, RaysAlongCellFacesAndEdgesAndFromInsideAgreeWithTheOracle) {
  for (const std::string spec : {"soup:n=2000", "walls:n=6,angle=0", "sphereflake:depth=2",
                                 "transformed:of=(soup:n=2000),translate=3e4:-1e4:2e4"})
    expect_agrees_with_oracle(spec, make_scene(spec));
}

TEST(GridDda, AxisAlignedBoxesOnCellPlanes) {
  // Triangles lying exactly in the cell planes of a 4x4x4 grid over [0,4]^3 (the 64 unit cubes'
  // faces at integer coordinates), hit by rays that run in those planes. A ray in a triangle's
  // plane is a graze the watertight kernel does not report, so the reference here is brute force
  // with the same kernel: any disagreement is the grid's.
  auto s = std::make_shared<Scene>();
  s->spec = "test:lattice";
  auto add = [&](Vec3f a, Vec3f b, Vec3f c) {
    const auto base = static_cast<std::uint32_t>(s->mesh.vertices.size());
    s->mesh.vertices.insert(s->mesh.vertices.end(), {a, b, c});
    s->mesh.triangles.push_back({base, base + 1, base + 2});
  };
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        const float x = float(i), y = float(j), z = float(k);
        add({x, y, z}, {x, y + 1, z}, {x, y, z + 1});          // x = i planes, half squares
        add({y, x, z + 0.5f}, {y + 1, x, z}, {y + 0.5f, x, z + 1});  // y = i planes
      }
  expect_agrees_with_oracle("lattice", s, "brute");
}

TEST(GridBuild, ResolutionFollowsTheLectureHeuristic) {
  Bounds3f cube({0, 0, 0}, {1, 1, 1});
  auto r = grid_resolution(cube, 1000, 3.0, 1 << 27);
  EXPECT_EQ(r[0], 30);
  EXPECT_EQ(r[1], 30);
  EXPECT_EQ(r[2], 30);
  Bounds3f slab({0, 0, 0}, {2, 0.1f, 1});
  r = grid_resolution(slab, 1000, 3.0, 1 << 27);
  EXPECT_EQ(r[0], 30);
  EXPECT_EQ(r[1], 2);
  EXPECT_EQ(r[2], 15);
  r = grid_resolution(cube, 1e9, 3.0, 1 << 20);
  EXPECT_LE(std::int64_t(r[0]) * r[1] * r[2], 1 << 20);
  EXPECT_GE(r[0], 90);
  r = grid_resolution(Bounds3f({1, 1, 1}, {1, 1, 1}), 10, 3.0, 1 << 27);
  EXPECT_EQ(r[0] * r[1] * r[2], 1);
}

TEST(GridBuild, CompactStorageAndStats) {
  const auto scene = make_scene("grass:blades=2000");
  GridConfig bbox_cfg;
  bbox_cfg.placement = GridPlacement::bbox;
  UniformGrid bbox(scene, bbox_cfg);
  GridConfig exact_cfg;
  exact_cfg.placement = GridPlacement::exact;
  UniformGrid exact(scene, exact_cfg);
  const CellLists& l = bbox.cells();
  EXPECT_EQ(l.offsets.size(), bbox.geometry().cell_count() + 1);
  EXPECT_EQ(l.offsets.back(), l.refs.size());
  EXPECT_GE(l.refs.size(), scene->primitive_count());
  EXPECT_EQ(bbox.stats().nodes, bbox.geometry().cell_count());
  EXPECT_EQ(bbox.stats().bytes, (l.offsets.size() + l.refs.size()) * 4 + scene->primitive_count() * (36 + 4));
  // exact placement keeps a subset of the bbox cells of each primitive
  EXPECT_LE(exact.cells().refs.size(), l.refs.size());
  EXPECT_GE(exact.cells().refs.size(), scene->primitive_count());
  for (std::size_t c = 0; c < bbox.geometry().cell_count(); ++c) EXPECT_LE(exact.cells().count(c), l.count(c));
}

// Tall, wide grass blades overlap many cells each at d = 3, so placement counts references with its 3D
// difference array (grid_placement.cpp); at d = 0.5 it counts them one by one. Either way every
// cell must hold exactly the primitives whose widened bounding box overlaps it.
TEST(GridBuild, BboxCellCountsMatchTheCellRangesOfTheBoundingBoxes) {
  const auto scene = make_scene("grass:blades=2000,height=0.4,width=0.03");
  for (const double d : {3.0, 0.5}) {
    GridConfig cfg;
    cfg.density = d;
    cfg.placement = GridPlacement::bbox;
    const UniformGrid grid(scene, cfg);
    const GridGeometry& g = grid.geometry();
    const float margin = grid_margin(scene->bounds());
    std::vector<std::uint32_t> expected(g.cell_count(), 0);
    for (std::uint32_t p = 0; p < scene->primitive_count(); ++p) {
      const Bounds3f b = scene->primitive_bounds(p);
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = g.cell_of(a, b.lo[a] - margin);
        hi[a] = g.cell_of(a, b.hi[a] + margin);
      }
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i) ++expected[g.index(i, j, k)];
    }
    const std::size_t n = scene->primitive_count(), refs = grid.cells().refs.size();
    EXPECT_EQ(refs > 8 * n + 3 * g.cell_count(), d == 3.0) << "d = " << d << " does not take the intended path";
    for (std::size_t c = 0; c < g.cell_count(); ++c) ASSERT_EQ(grid.cells().count(c), expected[c]) << "d = " << d << ", cell " << c;
  }
}

// The uniform grid's cells reference its copied triangles (cell_triangles.h); mapped back, every
// cell must list exactly the primitives placement with scene ids puts there, and every copy must
// be its primitive's triangle.
TEST(GridBuild, CopiedTrianglesMapBackToThePlacedPrimitives) {
  const auto scene = make_scene("grass:blades=3000");
  for (const GridPlacement placement : {GridPlacement::bbox, GridPlacement::exact, GridPlacement::clipped}) {
    GridConfig cfg;
    cfg.placement = placement;
    const UniformGrid grid(scene, cfg);
    const CellTriangles& tris = grid.triangles();
    ASSERT_EQ(tris.tris.size(), scene->primitive_count());
    for (std::size_t local = 0; local < tris.tris.size(); ++local) {
      const auto& t = scene->mesh.triangles[tris.prim_of[local]];
      const auto& v = scene->mesh.vertices;
      ASSERT_TRUE(tris.tris[local].v0 == v[t[0]] && tris.tris[local].v1 == v[t[1]] && tris.tris[local].v2 == v[t[2]]);
    }
    const CellLists by_prim =
        place_all_primitives(*scene, grid.geometry(), placement, grid_margin(scene->bounds()), CellRefIds::primitive);
    ASSERT_EQ(by_prim.offsets, grid.cells().offsets);
    for (std::size_t c = 0; c + 1 < by_prim.offsets.size(); ++c) {
      std::vector<std::uint32_t> mapped, placed;
      for (std::uint32_t r = by_prim.offsets[c]; r < by_prim.offsets[c + 1]; ++r) {
        mapped.push_back(tris.prim_of[grid.cells().refs[r]]);
        placed.push_back(by_prim.refs[r]);
      }
      std::sort(mapped.begin(), mapped.end());
      std::sort(placed.begin(), placed.end());
      ASSERT_EQ(mapped, placed) << "cell " << c;
    }
  }
}

// Clipped placement keeps every cell exact placement keeps (the cells the triangle meets, widened by
// the margin) and no cell outside the bounding box's: per cell, exact ⊆ clipped ⊆ bbox as sets, on
// tilted thin blades (upright: few slabs along z, many rows along y; and lying along z: slabs along
// y), a soup of random triangles, long needles and axis-aligned walls (edges parallel to the rows,
// whose reciprocal slope overflows). The last soup's large triangles span more than 16 rows in a
// slab (several passes of the scan conversion) and have more rows than clipped placement records
// in its one clipping pass (32 per triangle plus one per cell, grid_placement.cpp): its fill clips
// them again.
TEST(GridBuild, ClippedCellsLieBetweenExactAndBbox) {
  for (const auto& [spec, density] : std::vector<std::pair<std::string, double>>{
           {"grass:blades=800,height=0.4,width=0.03", 4.0},
           {"transformed:of=(grass:blades=800,height=0.4,width=0.03),rotate=x:90", 4.0}, {"soup:n=800", 4.0},
           {"needles:n=150", 4.0}, {"walls:n=20", 4.0}, {"walls:n=20,angle=0", 4.0}, {"soup:n=1000,size=1", 2.6}}) {
    const auto scene = make_scene(spec);
    const float margin = grid_margin(scene->bounds());
    const Bounds3f box = widened(scene->bounds(), margin);
    const GridGeometry g(box, grid_resolution(box, static_cast<double>(scene->primitive_count()), density, 1 << 27));
    auto lists = [&](GridPlacement placement) {
      return place_all_primitives(*scene, g, placement, margin, CellRefIds::primitive);
    };
    const CellLists exact = lists(GridPlacement::exact), clipped = lists(GridPlacement::clipped),
                    bbox = lists(GridPlacement::bbox);
    auto cell_set = [](const CellLists& l, std::size_t c) {
      std::vector<std::uint32_t> v(l.refs.begin() + l.offsets[c], l.refs.begin() + l.offsets[c + 1]);
      std::sort(v.begin(), v.end());
      return v;
    };
    EXPECT_LT(clipped.refs.size(), bbox.refs.size()) << spec;
    EXPECT_EQ(count_placed_references(*scene, g, GridPlacement::clipped, margin), clipped.refs.size()) << spec;
    EXPECT_EQ(count_placed_references(*scene, g, GridPlacement::bbox, margin), bbox.refs.size()) << spec;
    for (std::size_t c = 0; c < g.cell_count(); ++c) {
      const auto e = cell_set(exact, c), k = cell_set(clipped, c), b = cell_set(bbox, c);
      ASSERT_TRUE(std::includes(k.begin(), k.end(), e.begin(), e.end())) << spec << ", cell " << c;
      ASSERT_TRUE(std::includes(b.begin(), b.end(), k.begin(), k.end())) << spec << ", cell " << c;
    }
  }
}

TEST(GridBuild, NestedGridRefinesTheCrowdedCellsOfTheStadium) {
  const auto scene = make_scene("stadium:object=(sphere:n=2000),ratio=200");
  NestedGrid nested(scene, NestedGridConfig{});
  EXPECT_GT(nested.level_count(), 1u);
  NestedGridConfig two;
  two.mode = NestedGridMode::two_level;
  EXPECT_GT(NestedGrid(scene, two).level_count(), 1u);
}

// A ray from thousands of grid extents away rounds its 3D-DDA to the ulps of its origin, beyond the
// placement margin; the certified grids walk it from where it enters the grid (EntryRay,
// grid_geometry.h). Both ways round (a camera far from a scene at the origin, and a camera at the
// origin looking at a scene far from it), their first hits are the oracle's by the exact rule, and
// they test a few triangles per ray, where offering every primitive tested hundreds.
TEST(GridDda, RaysFromFarAwayAreWalkedFromWhereTheyEnterTheGrid) {
  for (const auto& [spec, eye] : std::vector<std::pair<std::string, Vec3f>>{
           {"soup:n=3000", {3000.0f, -7000.0f, 5000.0f}},
           {"transformed:of=(soup:n=3000),translate=3e4:-1e4:2e4", {0.0f, 0.0f, 0.0f}}}) {
    const auto scene = make_scene(spec);
    const Bounds3f b = scene->bounds();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < 2000; ++i) {
      Ray r;
      r.org = eye;
      const Vec3f target = b.lo + b.diagonal() * Vec3f(unit(rng), unit(rng), unit(rng));
      r.dir = normalize(target - eye);
      rays.push_back(r);
    }
    const auto oracle = make_accelerator("exact", scene);
    const TraceResult exact = trace_rays(*oracle, rays, TraceOptions{1, false, false});
    const TraceResult exact_any = trace_rays(*oracle, rays, TraceOptions{1, false, true});
    ASSERT_GT(exact.hit_count, rays.size() / 4) << spec;
    for (const std::string accel : {"grid", "nested-grid", "grid:mailbox=off"}) {
      const auto grid = make_accelerator(accel, scene);
      const TraceResult got = trace_rays(*grid, rays, TraceOptions{1, true, false});
      const HitComparison c = compare_hits_exact(*scene, rays, got.hits, exact.hits);
      EXPECT_EQ(c.mismatches, 0u) << accel << " on " << spec;
      EXPECT_LT(double(got.counters.prim_tests), 20.0 * double(rays.size())) << accel << " on " << spec;
      const TraceResult any = trace_rays(*grid, rays, TraceOptions{1, true, true});
      EXPECT_EQ(compare_occlusion(any.blocked, exact_any.blocked).mismatches, 0u) << accel << " (any hit) on " << spec;
      EXPECT_LT(double(any.counters.prim_tests), 20.0 * double(rays.size())) << accel << " (any hit) on " << spec;
    }
  }
}

// A ray outside the x slab and parallel to it (d.x = 0), whose z distances overflow (d.z = 2e-38,
// a normal float, its inverse 5e37): the slab test enters the box at t0 = +inf, where the entry
// point o + t0·d is NaN on x. The 3D-DDA walked from there (UndefinedBehaviorSanitizer: a NaN cell
// index; found by fuzz_build_trace). It reaches the box at no finite t and misses, as the oracle
// says.
TEST(GridDda, ARayThatEntersTheBoxOnlyAtInfinityMisses) {
  const auto scene = make_scene("soup:n=200");
  const Bounds3f b = scene->bounds();
  const Vec3f c = b.center(), d = b.diagonal();
  std::vector<Ray> rays;
  for (const float side : {-1.0f, 1.0f}) {
    Ray r;
    r.org = {c.x + side * (d.x + 1.0f), c.y, b.lo.z - 10.0f - d.z};
    r.dir = {side > 0.0f ? -0.0f : 0.0f, 0.0f, 2e-38f};
    rays.push_back(r);
  }
  const auto oracle = make_accelerator("exact", scene);
  ASSERT_EQ(trace_rays(*oracle, rays, TraceOptions{1, false, false}).hit_count, 0u);
  for (const auto& spec : kGridSpecs)
    for (const std::string kernel : {"", "kernel=watertight"}) {
      const std::string accel = kernel.empty() ? spec : with_param(spec, kernel);
      const auto grid = make_accelerator(accel, scene);
      EXPECT_EQ(trace_rays(*grid, rays, TraceOptions{1, true, false}).hit_count, 0u) << accel;
      EXPECT_EQ(trace_rays(*grid, rays, TraceOptions{1, true, true}).hit_count, 0u) << accel << " (any hit)";
    }
}

// A scene far from the world origin is placed and walked in a frame near it (grid_frame.h): the
// frame's translation is exact, and its grids hold about as many references as the same scene's
// at the origin. In the world frame the placement margin, 2^-16 of the coordinates' magnitude,
// spread every triangle of this soup over hundreds of cells. A scene near the origin keeps the
// world frame.
TEST(GridFrame, AFarSceneIsPlacedAsTightlyAsTheSameSceneAtTheOrigin) {
  const auto near = make_scene("soup:n=3000");
  const auto far = make_scene("transformed:of=(soup:n=3000),translate=3e4:-1e4:2e4");
  const GridFrame near_frame = make_grid_frame(near);
  EXPECT_TRUE(near_frame.is_world());
  EXPECT_EQ(near_frame.scene, near);
  const GridFrame frame = make_grid_frame(far);
  ASSERT_FALSE(frame.is_world());
  ASSERT_EQ(frame.scene->mesh.vertices.size(), far->mesh.vertices.size());
  for (std::size_t i = 0; i < far->mesh.vertices.size(); ++i)
    ASSERT_TRUE(frame.scene->mesh.vertices[i] + frame.origin == far->mesh.vertices[i]) << "vertex " << i;
  EXPECT_LT(4.0f * grid_margin(frame.scene->bounds()), grid_margin(far->bounds()));
  for (const std::string spec : {"grid", "grid:place=exact", "nested-grid"}) {
    const double near_bytes = double(make_accelerator(spec, near)->stats().bytes),
                 far_bytes = double(make_accelerator(spec, far)->stats().bytes);
    EXPECT_LT(far_bytes, 1.25 * near_bytes) << spec;
  }
  const auto grid = make_accelerator("grid", far);
  EXPECT_TRUE(dynamic_cast<const UniformGrid&>(*grid).frame_origin() == frame.origin);
}

TEST(GridParams, BadParametersAreInputErrors) {
  const auto scene = make_scene("soup:n=100");
  for (const std::string spec : {"grid:d=0", "grid:d=100", "grid:place=sphere", "grid:accept=last", "grid:mailbox=maybe",
                                 "grid:cells=3", "nested-grid:depth=0", "nested-grid:mode=three-level",
                                 "nested-grid:threshold=0"})
    EXPECT_THROW(make_accelerator(spec, scene), InputError) << spec;
  EXPECT_NO_THROW(make_accelerator("grid:d=0.5,place=exact,accept=first,mailbox=off", scene));
  EXPECT_NO_THROW(make_accelerator("nested-grid:mode=two-level,top_d=2,d=4", scene));
}

TEST(GridParams, InstancedScenesAreBuiltOnceUnderEveryInstance) {
  const auto scene = make_scene("instances:of=(sphere:n=400),count=6");
  const auto oracle = make_accelerator("exact", scene);
  std::vector<Ray> rays;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const Bounds3f b = scene->bounds();
  for (int i = 0; i < 500; ++i)
    rays.push_back(Ray{b.center() + b.diagonal() * 2.0f, b.center() + b.diagonal() * 0.3f * Vec3f(u(rng), u(rng), u(rng)) -
                                                              (b.center() + b.diagonal() * 2.0f)});
  const TraceResult exact = trace_rays(*oracle, rays, TraceOptions{1, false, false});
  ASSERT_GT(exact.hit_count, 0u);
  for (const std::string spec : {"grid", "nested-grid"}) {
    const TraceResult got = trace_rays(*make_accelerator(spec, scene), rays, TraceOptions{1, false, false});
    EXPECT_EQ(compare_hits(rays, got.hits, exact.hits, length(Vec3d(b.diagonal()))).mismatches, 0u) << spec;
  }
}

}  // namespace
}  // namespace raylab
