// The lecture's "objects overlapping multiple cells": a big slanted triangle that reaches into
// the first cell a ray visits but is hit far behind a small triangle in a later cell. Accepting
// the first hit found in a cell (accept=first, the lecture's mistake) returns the far hit;
// in-cell acceptance returns the near one, as the exact oracle does.
#include <gtest/gtest.h>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "accel/grid/uniform_grid.h"

namespace raylab {
namespace {

/// B: in the plane x = 8 - 7(z - 0.5), hit by the rays at x = 8 but reaching x ≈ 1 at z ≈ 1.5,
/// i.e. into the first column of cells. A: small, at x = 5, in front of B.
std::shared_ptr<const Scene> overlap_scene() {
  auto s = std::make_shared<Scene>();
  s->spec = "test:overlap";
  auto add = [&](Vec3f a, Vec3f b, Vec3f c) {
    const auto base = static_cast<std::uint32_t>(s->mesh.vertices.size());
    s->mesh.vertices.insert(s->mesh.vertices.end(), {a, b, c});
    s->mesh.triangles.push_back({base, base + 1, base + 2});
  };
  add({11.5f, -10, 0}, {11.5f, 10, 0}, {0.3f, 0.5f, 1.6f});  // B
  add({5, 0, 0}, {5, 1.5f, 0.2f}, {5, 0.2f, 1.2f});          // A
  return s;
}

std::vector<Ray> parallel_rays() {
  std::vector<Ray> rays;
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) rays.push_back(Ray{{-1, 0.4f + 0.025f * i, 0.4f + 0.025f * j}, {1, 0, 0}});
  return rays;
}

TEST(GridAccept, FirstIsWrongAndInCellIsRightOnAnObjectSpanningCells) {
  const auto scene = overlap_scene();
  const auto rays = parallel_rays();
  const double diagonal = length(Vec3d(scene->bounds().diagonal()));
  const TraceResult exact = trace_rays(*make_accelerator("exact", scene), rays, TraceOptions{1, false, false});
  ASSERT_EQ(exact.hit_count, rays.size());
  for (const Hit& h : exact.hits) ASSERT_EQ(h.prim, 1u);  // A, at t = 6

  // d=8 gives 6 cells along x: B lies in the rays' first cell, A in the third.
  const auto grid = make_accelerator("grid:d=8", scene);
  const auto& g = dynamic_cast<const UniformGrid&>(*grid).geometry();
  ASSERT_GE(g.res[0], 4);
  for (const std::string spec : {"grid:d=8", "grid:d=8,mailbox=off", "grid:d=8,place=exact"}) {
    const TraceResult got = trace_rays(*make_accelerator(spec, scene), rays, TraceOptions{1, false, false});
    EXPECT_EQ(compare_hits(rays, got.hits, exact.hits, diagonal).mismatches, 0u) << spec;
  }
  for (const std::string spec : {"grid:d=8,accept=first", "grid:d=8,accept=first,mailbox=off"}) {
    const TraceResult got = trace_rays(*make_accelerator(spec, scene), rays, TraceOptions{1, false, false});
    const HitComparison c = compare_hits(rays, got.hits, exact.hits, diagonal);
    EXPECT_EQ(c.mismatches, rays.size()) << spec << ": the lecture's mistake must return B for every ray";
    for (const Hit& h : got.hits) EXPECT_EQ(h.prim, 0u) << spec;
  }
}

TEST(GridAccept, MailboxRemembersAHitBeyondItsCell) {
  // With the mailbox, B is tested once (in the first cell, hit beyond it) and its stored hit is
  // re-used, not re-tested, in later cells; A is still found first.
  const auto scene = overlap_scene();
  const auto rays = parallel_rays();
  const auto with = make_accelerator("grid:d=8", scene);
  const auto without = make_accelerator("grid:d=8,mailbox=off", scene);
  const TraceResult a = trace_rays(*with, rays, TraceOptions{1, true, false});
  const TraceResult b = trace_rays(*without, rays, TraceOptions{1, true, false});
  EXPECT_GT(a.counters.mailbox_skips, 0u);
  EXPECT_LT(a.counters.prim_tests, b.counters.prim_tests);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(a.hits[i].prim, b.hits[i].prim);
    EXPECT_EQ(a.hits[i].t, b.hits[i].t);
  }
  // A ray that meets only B: its hit, found in the first cell and remembered, must be returned.
  std::vector<Ray> only_b = {Ray{{-1, -3, 0.5f}, {1, 0, 0}}};
  const TraceResult e = trace_rays(*make_accelerator("exact", scene), only_b, TraceOptions{1, false, false});
  ASSERT_EQ(e.hits[0].prim, 0u);
  const TraceResult m = trace_rays(*with, only_b, TraceOptions{1, true, false});
  EXPECT_EQ(m.hits[0].prim, 0u);
  EXPECT_NEAR(m.hits[0].t, e.hits[0].t, 1e-5);
}

}  // namespace
}  // namespace raylab
