#include <gtest/gtest.h>

#include <bit>
#include <random>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "accel/common/structure_hash.h"
#include "accel/kdtree/kdtree.h"
#include "accel/kdtree/sah_sweep_events.h"
#include "geometry/exact_predicates.h"
#include "geometry/triangle_clipping.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

std::shared_ptr<const Scene> make(const std::string& spec) { return make_scene(spec); }

/// Axis-aligned unit squares (two triangles each) on the integer planes of a 4x4x4 lattice, so
/// that SAH picks split planes that contain triangles, and triangles touch cells only at faces.
std::shared_ptr<const Scene> lattice_scene() {
  auto s = std::make_shared<Scene>();
  s->spec = "lattice";
  auto& m = s->mesh;
  auto quad = [&](Vec3f o, Vec3f e1, Vec3f e2) {
    const auto b = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {o, o + e1, o + e1 + e2, o + e2});
    m.triangles.push_back({b, b + 1, b + 2});
    m.triangles.push_back({b, b + 2, b + 3});
  };
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        if ((i + j + k) % 2) continue;
        const Vec3f o{float(i), float(j), float(k)};
        quad(o, {1, 0, 0}, {0, 1, 0});
        quad(o, {0, 1, 0}, {0, 0, 1});
        quad(o, {0, 0, 1}, {1, 0, 0});
      }
  return s;
}

KdTreeConfig config_for(const std::string& params) {
  SpecReader r(parse_spec("kdtree" + (params.empty() ? "" : ":" + params)));
  return read_kdtree_config(r);
}

/// The default C_isect (kKdDefaultIsect) keeps scenes of a few dozen triangles in one leaf; tests
/// that need split planes in small scenes take the fitted model's ratio instead.
const std::string kSplitsSmallScenes = "c_isect=0.2";

/// Random and adversarial triangles and boxes: coordinates drawn from a few values that put
/// vertices and edges on the box faces, edges and corners (and ±0), or drawn at random.
struct ClipCase {
  Vec3f p[3];
  Bounds3f box;
};
std::vector<ClipCase> clip_cases(int count) {
  std::mt19937 rng(12345);
  const float grid[] = {-1.0f, -0.5f, -0.0f, 0.0f, 0.25f, 0.5f, 0.75f, 1.0f, 1.5f, 0.3f, 1e-7f, 1.0000001f};
  std::uniform_int_distribution<int> pick(0, 11);
  std::uniform_real_distribution<float> uni(-1.5f, 2.5f);
  std::vector<ClipCase> cases;
  for (int i = 0; i < count; ++i) {
    ClipCase c;
    const int mode = i % 3;  // 0: grid, 1: random, 2: mixed
    auto coord = [&](int m) { return m == 0 || (m == 2 && rng() % 2) ? grid[pick(rng)] : uni(rng); };
    for (auto& v : c.p) v = {coord(mode), coord(mode), coord(mode)};
    if (i % 7 == 0) c.p[2] = c.p[1];                                       // degenerate: segment
    if (i % 11 == 0) c.p[2] = c.p[0] + (c.p[1] - c.p[0]) * 0.5f;           // nearly collinear
    Vec3f a{coord(0), coord(0), coord(0)}, b{coord(mode), coord(mode), coord(mode)};
    c.box = Bounds3f(a, b);
    cases.push_back(c);
  }
  return cases;
}

/// A scene of the cases' triangles, triangle i from case i.
Scene scene_of(const std::vector<ClipCase>& cases) {
  Scene scene;
  for (const ClipCase& c : cases) {
    const auto b = static_cast<std::uint32_t>(scene.mesh.vertices.size());
    scene.mesh.vertices.insert(scene.mesh.vertices.end(), {c.p[0], c.p[1], c.p[2]});
    scene.mesh.triangles.push_back({b, b + 1, b + 2});
  }
  return scene;
}

TEST(KdTree, FilteredExactPlacementEqualsTheExactPredicate) {
  const std::vector<ClipCase> cases = clip_cases(100000);
  const Scene scene = scene_of(cases);
  const std::vector<PrimRef> refs = make_root_refs(scene);
  std::size_t met = 0;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const ClipCase& c = cases[i];
    const bool expected =
        refs[i].box.overlaps(c.box) && exact_triangle_intersects_box(c.p[0], c.p[1], c.p[2], c.box);
    ASSERT_EQ(ref_meets_box(scene, refs[i], c.box, ClipMode::exact), expected) << i;
    met += expected;
  }
  EXPECT_GT(met, cases.size() / 10);
  EXPECT_LT(met, cases.size() * 9 / 10);
}

TEST(KdTree, FilteredChildPlacementEqualsTheExactPredicate) {
  const std::vector<ClipCase> cases = clip_cases(100000);
  const Scene scene = scene_of(cases);
  const std::vector<PrimRef> refs = make_root_refs(scene);
  std::mt19937 rng(777);
  std::size_t both = 0;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const ClipCase& c = cases[i];
    const int axis = static_cast<int>(i % 3);
    // Split planes through a vertex, through the box middle, or at random inside the box.
    float s = c.box.lo[axis] + (c.box.hi[axis] - c.box.lo[axis]) * std::uniform_real_distribution<float>(0, 1)(rng);
    if (i % 4 == 1) s = c.p[i % 3 == 0 ? 1 : 0][axis];
    if (i % 4 == 2) s = 0.5f * (c.box.lo[axis] + c.box.hi[axis]);
    if (!(s >= c.box.lo[axis] && s <= c.box.hi[axis])) s = c.box.lo[axis];
    Bounds3f lbox = c.box, rbox = c.box;
    lbox.hi[axis] = s;
    rbox.lo[axis] = s;
    const bool el = refs[i].box.overlaps(lbox) && exact_triangle_intersects_box(c.p[0], c.p[1], c.p[2], lbox);
    const bool er = refs[i].box.overlaps(rbox) && exact_triangle_intersects_box(c.p[0], c.p[1], c.p[2], rbox);
    bool in_l = false, in_r = false;
    ref_meets_children(scene, refs[i], c.box, axis, s, ClipMode::exact, in_l, in_r);
    ASSERT_EQ(in_l, el) << i;
    ASSERT_EQ(in_r, er) << i;
    both += el && er;
  }
  EXPECT_GT(both, cases.size() / 20);
}

TEST(KdTree, RootEventSortGivesStdSortsKeySequence) {
  std::mt19937 rng(99);
  const float values[] = {-2.5f, -1.0f, -1e-30f, 0.0f, 1e-30f, 0.5f, 1.0f, 3.0f, 1e30f, -1e30f};
  for (int variant = 0; variant < 3; ++variant) {
    EventVector events;
    for (std::uint32_t i = 0; i < 50000; ++i) {
      float pos = variant == 0 ? values[rng() % 10] : std::uniform_real_distribution<float>(-4, 4)(rng);
      if (variant == 2 && i == 777) pos = -0.0f;  // -0 present: std::sort itself
      events.push_back(SplitEvent::make(pos, static_cast<SplitEvent::Type>(rng() % 3), i));
    }
    EventVector expected = events;
    std::sort(expected.begin(), expected.end());
    sort_root_events(events);
    ASSERT_EQ(events.size(), expected.size());
    for (std::size_t i = 0; i < events.size(); ++i) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(events[i].pos), std::bit_cast<std::uint32_t>(expected[i].pos)) << i;
      ASSERT_EQ(events[i].type(), expected[i].type()) << i;
      if (variant == 2) {
        ASSERT_EQ(events[i].prim(), expected[i].prim()) << i;
      }
    }
  }
}

/// split_events keeps the parent's events only where a child's bounds are unchanged: each child's
/// lists hold the key sequence of its references' events, sorted anew. Straddlers get bounds
/// clipped to the child box along the split axis and, for some, shrunk along another axis.
TEST(KdTree, SplitEventsGiveEachChildTheSortedEventsOfItsReferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(0.0f, 8.0f);
  std::size_t straddlers_keeping = 0, straddlers_renewing = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int axis = trial % 3;
    const float s = std::floor(coord(rng) * 4) / 4;  // on a grid, so that bounds touch the plane
    std::vector<PrimRef> refs;
    for (std::uint32_t i = 0; i < 300; ++i) {
      Bounds3f b;
      for (int a = 0; a < 3; ++a) {
        float lo = std::floor(coord(rng) * 4) / 4, hi = std::floor(coord(rng) * 4) / 4;
        if (lo > hi) std::swap(lo, hi);
        if (rng() % 8 == 0) hi = lo;  // planar along a
        b.lo[a] = lo;
        b.hi[a] = hi;
      }
      refs.push_back({b, i});
    }
    NodeEvents parent;
    for (int a = 0; a < 3; ++a) {
      append_events(refs, a, parent.axis[a]);
      std::sort(parent.axis[a].begin(), parent.axis[a].end());
    }
    std::vector<KeptEvents> kept(refs.size() + kKeptPadding, 0);
    std::vector<PrimRef> left, right, left_new, right_new;
    std::size_t kept_l[3] = {0, 0, 0}, kept_r[3] = {0, 0, 0};
    auto count = [](const Bounds3f& b, KeptEvents bits, int child, std::size_t(&k)[3]) {
      for (int a = 0; a < 3; ++a)
        if ((bits >> (2 * a + child)) & 1u) k[a] += b.lo[a] == b.hi[a] ? 1 : 2;
    };
    for (const PrimRef& r : refs) {
      if (r.box.hi[axis] < s) {
        left.push_back(r);
        kept[r.prim] = kKeepAllLower;
        count(r.box, kKeepAllLower, 0, kept_l);
      } else if (r.box.lo[axis] > s) {
        right.push_back(r);
        kept[r.prim] = kKeepAllUpper;
        count(r.box, kKeepAllUpper, 1, kept_r);
      } else {
        for (int child = 0; child < 2; ++child) {
          PrimRef c = r;
          (child == 0 ? c.box.hi[axis] : c.box.lo[axis]) = s;
          const int other = (axis + 1 + static_cast<int>(rng() % 2)) % 3;
          if (rng() % 3 == 0) c.box.hi[other] = c.box.lo[other];
          const KeptEvents bits = kept_events(r.box, c.box, child);
          (bits == (child == 0 ? kKeepAllLower : kKeepAllUpper) ? straddlers_keeping : straddlers_renewing) += 1;
          kept[r.prim] |= bits;
          count(r.box, bits, child, child == 0 ? kept_l : kept_r);
          (child == 0 ? left : right).push_back(c);
          (child == 0 ? left_new : right_new).push_back(c);
        }
      }
    }
    NodeEvents out_l, out_r;
    SplitEventsScratch scratch;
    split_events(parent, kept, left_new, right_new, kept_l, kept_r, out_l, out_r, scratch);
    for (int a = 0; a < 3; ++a)
      for (const auto& [child_refs, got] : {std::pair{&left, &out_l.axis[a]}, std::pair{&right, &out_r.axis[a]}}) {
        EventVector expected;
        append_events(*child_refs, a, expected);
        std::sort(expected.begin(), expected.end());
        ASSERT_EQ(got->size(), expected.size()) << "trial " << trial << " axis " << a;
        for (std::size_t i = 0; i < expected.size(); ++i) {
          ASSERT_EQ(got->at(i).pos, expected[i].pos) << "trial " << trial << " axis " << a << " event " << i;
          ASSERT_EQ(got->at(i).type(), expected[i].type()) << "trial " << trial << " axis " << a << " event " << i;
        }
      }
  }
  EXPECT_GT(straddlers_keeping, 100u);
  EXPECT_GT(straddlers_renewing, 100u);
}

/// The event sweep against a brute-force scan of the same candidates: at every distinct event
/// position strictly inside the box, N(L) and N(R) counted from the primitives' bounds, the cost
/// in the sweep's documented form; the two empty-space cut-offs by SahCost::split. The cheapest
/// wins, the first in position order among equal costs. Lists of every length from 1 to 90 (both
/// sides of the sweep's blocks of eight), with runs of equal positions, planar events, bounds
/// on and beyond the box faces, and mirror-symmetric sets, whose mirrored planes cost exactly
/// the same (the lower one must win).
TEST(KdTree, EventSweepChoosesTheFirstCheapestCandidate) {
  std::mt19937 rng(2024);
  const Bounds3f box({0.0f, 0.0f, 0.0f}, {6.0f, 3.0f, 2.0f});
  const SahCost cost{1.0, 0.2, 0.2, 0.0};
  const double sa = surface_area_d(box);
  std::size_t ties = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const bool mirrored = trial % 3 == 0;
    const std::size_t n = 1 + static_cast<std::size_t>(trial) % 45;
    std::vector<PrimRef> refs;
    auto coordinate = [&] { return static_cast<float>(static_cast<int>(rng() % 27) - 1) * 0.25f; };  // -0.25 .. 6.25
    while (refs.size() < n) {
      float lo = coordinate(), hi = rng() % 5 == 0 ? lo : coordinate();
      if (lo > hi) std::swap(lo, hi);
      auto add = [&](float l, float h) {
        refs.push_back({Bounds3f({l, 0.0f, 0.0f}, {h, 3.0f, 2.0f}), static_cast<std::uint32_t>(refs.size())});
      };
      add(lo, hi);
      if (mirrored && refs.size() < n) add(6.0f - hi, 6.0f - lo);
    }
    EventVector events;
    append_events(refs, 0, events);
    std::sort(events.begin(), events.end());
    SplitCandidate got;
    sweep_events(events, 0, box, n, cost, got);

    SplitCandidate expected;
    std::vector<double> costs;
    const double a0 = 2.0 * 3.0 * 2.0, per_extent = 2.0 * (3.0 + 2.0);
    auto consider = [&](float p, double c, int empty_child) {
      costs.push_back(c);
      if (c < expected.cost) expected = {0, p, c, empty_child};
    };
    const float first = events.front().pos, last = events.back().pos;
    if (const float below = std::nextafter(first, 0.0f); first > 0.0f && below > 0.0f)
      consider(below, cost.split(sa, a0 + per_extent * below, a0 + per_extent * (6.0 - below), 0, n), 0);
    std::vector<float> positions;
    for (const SplitEvent& e : events) positions.push_back(e.pos);
    positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
    for (const float p : positions) {
      if (!(p > 0.0f && p < 6.0f)) continue;
      std::size_t n_l = 0, n_r = 0;
      for (const PrimRef& r : refs) {
        n_l += r.box.lo.x <= p;
        n_r += r.box.hi.x >= p;
      }
      const double sa_l = a0 + per_extent * (double(p) - 0.0), sa_r = a0 + per_extent * (6.0 - double(p));
      consider(p, cost.c_trav + cost.c_isect / sa * (sa_l * double(n_l) + sa_r * double(n_r)), -1);
    }
    if (const float above = std::nextafter(last, 6.0f); last < 6.0f && above < 6.0f)
      consider(above, cost.split(sa, a0 + per_extent * above, a0 + per_extent * (6.0 - above), n, 0), 1);
    std::sort(costs.begin(), costs.end());
    ties += costs.size() > 1 && costs[0] == costs[1];

    ASSERT_EQ(got.axis, expected.axis) << "trial " << trial;
    ASSERT_EQ(std::bit_cast<std::uint32_t>(got.pos), std::bit_cast<std::uint32_t>(expected.pos)) << "trial " << trial;
    ASSERT_EQ(std::bit_cast<std::uint64_t>(got.cost), std::bit_cast<std::uint64_t>(expected.cost)) << "trial " << trial;
    ASSERT_EQ(got.empty_child, expected.empty_child) << "trial " << trial;
  }
  EXPECT_GT(ties, 50u);  // the tie rule was exercised
}

TEST(KdTree, SortAndEventSweepsBuildTheSameTree) {
  for (const std::string scene_spec : {"soup:n=2000", "sphere:n=1500", "grass:blades=200", "walls:n=8,angle=30"}) {
    const auto scene = make(scene_spec);
    for (const std::string clip : {"none", "bbox", "exact"}) {
      const KdTree sort(scene, config_for("sweep=sort,clip=" + clip + "," + kSplitsSmallScenes));
      const KdTree events(scene, config_for("sweep=events,clip=" + clip + "," + kSplitsSmallScenes));
      EXPECT_GT(sort.stats().nodes, 1u) << scene_spec;
      EXPECT_EQ(sort.structure_hash(), events.structure_hash()) << scene_spec << " clip=" << clip;
      EXPECT_DOUBLE_EQ(sort.stats().sah_cost, events.stats().sah_cost);
    }
  }
  const auto lattice = lattice_scene();
  const KdTree sort(lattice, config_for("sweep=sort"));
  const KdTree events(lattice, config_for("sweep=events"));
  EXPECT_EQ(sort.structure_hash(), events.structure_hash());
}

/// Every triangle that exactly meets a leaf's closed box is listed in that leaf.
void expect_no_triangle_lost(const Scene& scene, const KdTreeData& data) {
  std::size_t leaves = 0;
  for_each_kd_leaf(data, [&](const Bounds3f& box, std::uint32_t first, std::uint32_t count) {
    ++leaves;
    std::vector<bool> listed(scene.mesh.size(), false);
    for (std::uint32_t i = 0; i < count; ++i)
      if (data.prims[first + i] < scene.mesh.size()) listed[data.prims[first + i]] = true;
    for (std::uint32_t t = 0; t < scene.mesh.size(); ++t) {
      if (listed[t]) continue;
      const auto& tri = scene.mesh.triangles[t];
      const auto& v = scene.mesh.vertices;
      ASSERT_FALSE(exact_triangle_intersects_box(v[tri[0]], v[tri[1]], v[tri[2]], box))
          << "triangle " << t << " lost from a leaf";
    }
  });
  EXPECT_GT(leaves, 1u);
}

TEST(KdTree, ExactClippingLosesNoTriangle) {
  for (const auto& scene : {make("soup:n=600"), make("walls:n=6,angle=30"), lattice_scene()}) {
    for (const std::string& params : {"clip=exact," + kSplitsSmallScenes, std::string("clip=exact,builder=midpoint"),
                                     std::string("clip=exact,builder=median")}) {
      expect_no_triangle_lost(*scene, build_kdtree(*scene, config_for(params)));
    }
  }
}

TEST(KdTree, ExactClippingListsOnlyTrianglesThatMeetTheLeaf) {
  const auto scene = make("soup:n=600");
  const KdTreeData data = build_kdtree(*scene, config_for("clip=exact"));
  for_each_kd_leaf(data, [&](const Bounds3f& box, std::uint32_t first, std::uint32_t count) {
    for (std::uint32_t i = 0; i < count; ++i) {
      const auto& tri = scene->mesh.triangles[data.prims[first + i]];
      const auto& v = scene->mesh.vertices;
      EXPECT_TRUE(exact_triangle_intersects_box(v[tri[0]], v[tri[1]], v[tri[2]], box));
    }
  });
}

/// Adversarial rays built from the tree's own split planes: axis-parallel rays whose origins lie
/// on split planes, and rays running along cell faces and edges, against brute force.
std::vector<Ray> split_plane_rays(const KdTreeData& data) {
  std::vector<Ray> rays;
  const Bounds3f b = data.bounds;
  const Vec3f c = b.center(), d = b.diagonal();
  for (std::size_t i = 0; i < data.nodes.size() && rays.size() < 3000; ++i) {
    const KdNode& n = data.nodes[i];
    if (n.is_leaf()) continue;
    const int a = n.axis(), a1 = (a + 1) % 3, a2 = (a + 2) % 3;
    for (int k = 0; k < 3; ++k) {
      Vec3f o = c;
      o[a] = n.split;
      o[a1] = b.lo[a1] + d[a1] * (0.17f + 0.31f * float(k));
      o[a2] = b.lo[a2] - d[a2];
      Vec3f dir(0.0f);
      dir[a2] = 1.0f;
      rays.push_back({o, dir});  // in the split plane, axis-parallel
      o[a2] = b.lo[a2] + d[a2] * (0.23f + 0.29f * float(k));
      o[a1] = b.lo[a1] - d[a1];
      dir = Vec3f(0.0f);
      dir[a1] = 1.0f;
      rays.push_back({o, dir});
      Vec3f dir2(0.0f);
      dir2[a] = (k % 2) ? 1.0f : -1.0f;  // origin on the plane, crossing it
      rays.push_back({Vec3f(o.x, o.y, o.z) + Vec3f(0.0f), dir2});
      rays.back().org[a1] = c[a1] + 0.1f * d[a1] * float(k - 1);
      Vec3f diag(0.0f);  // in the plane, oblique
      diag[a1] = 0.6f;
      diag[a2] = 0.8f;
      Vec3f o2 = b.lo - d * 0.1f;
      o2[a] = n.split;
      rays.push_back({o2, diag});
    }
  }
  return rays;
}

void expect_matches_brute(const std::shared_ptr<const Scene>& scene, const std::string& spec, const std::vector<Ray>& rays) {
  const auto brute = make_accelerator("brute", scene);
  const auto accel = make_accelerator(spec, scene);
  const TraceResult ref = trace_rays(*brute, rays, TraceOptions{1, false, false});
  const TraceResult got = trace_rays(*accel, rays, TraceOptions{1, false, false});
  const double diag = length(Vec3d(scene->bounds().diagonal()));
  const HitComparison c = compare_hits(rays, got.hits, ref.hits, diag);
  EXPECT_EQ(c.mismatches, 0u) << spec << " on " << scene->spec << ": " << c.missed_hits << " missed, " << c.false_hits
                              << " false, " << c.wrong_t << " wrong t of " << c.rays;
  EXPECT_GT(ref.hit_count, 0u);
  const TraceResult ref_o = trace_rays(*brute, rays, TraceOptions{1, false, true});
  const TraceResult got_o = trace_rays(*accel, rays, TraceOptions{1, false, true});
  EXPECT_EQ(compare_occlusion(got_o.blocked, ref_o.blocked).mismatches, 0u) << spec << " (occlusion)";
}

TEST(KdTree, RaysInAndAlongSplitPlanesAgreeWithBruteForce) {
  for (const auto& scene : {lattice_scene(), make("soup:n=800"), make("walls:n=6,angle=30")}) {
    const KdTree probe(scene, config_for(kSplitsSmallScenes));
    const auto rays = split_plane_rays(probe.data());
    ASSERT_FALSE(rays.empty());
    for (const std::string params : {"", "clip=none", "clip=bbox", "builder=midpoint", "builder=median",
                                     "traversal=recursive", "mailbox=on"}) {
      expect_matches_brute(scene, "kdtree:" + kSplitsSmallScenes + (params.empty() ? "" : "," + params), rays);
    }
  }
}

/// The cache-line layout holds the same tree: walked in parallel with the build layout, every
/// node has the same split or leaf range, and children pairs are adjacent in a 64-byte line
/// where they fit; the triangle soup copies the scene's vertices.
TEST(KdTree, NodeLinesAndTriangleSoupMatchTheBuiltTree) {
  const auto scene = make("soup:n=3000");
  const KdTreeConfig config;
  const KdTreeData data = build_kdtree(*scene, config);
  const std::vector<KdNodeLine> lines = kd_node_lines(data.nodes);
  const KdNode* packed = lines.front().node;
  ASSERT_EQ(reinterpret_cast<std::uintptr_t>(packed) % 64, 0u);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> todo = {{0, 0}};  // build index, line index
  std::size_t visited = 0;
  while (!todo.empty()) {
    const auto [b, l] = todo.back();
    todo.pop_back();
    ++visited;
    const KdNode& n = data.nodes[b];
    const KdNode& m = packed[l];
    ASSERT_EQ(n.is_leaf(), m.is_leaf());
    if (n.is_leaf()) {
      EXPECT_EQ(n.first, m.first);
      EXPECT_EQ(n.count(), m.count());
      continue;
    }
    EXPECT_EQ(n.axis(), m.axis());
    EXPECT_EQ(n.split, m.split);
    EXPECT_EQ(m.above_child() % 2, 0u);
    todo.push_back({b + 1, m.above_child()});
    todo.push_back({n.above_child(), m.above_child() + 1});
  }
  EXPECT_EQ(visited, data.nodes.size());
  EXPECT_LT(lines.size() * 8, 3 * data.nodes.size());
  const auto tris = make_triangle_soup(*scene);
  ASSERT_EQ(tris.size(), scene->mesh.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const auto& t = scene->mesh.triangles[i];
    EXPECT_TRUE(tris[i].v0 == scene->mesh.vertices[t[0]] && tris[i].v1 == scene->mesh.vertices[t[1]] &&
                tris[i].v2 == scene->mesh.vertices[t[2]]);
  }
  EXPECT_TRUE(make_triangle_soup(*make("sphereflake:depth=1")).empty());
}

/// The packed leaves hold each leaf's primitives in the leaf's order, ceil(count / 4) packets
/// from the leaf's new `first`, with the scene's vertices; unused lanes are invalid. Scenes with
/// spheres are not packed and keep the lines' prim offsets.
TEST(KdTree, PackedLeavesHoldEachLeafsTrianglesInOrder) {
  const auto scene = make("soup:n=3000");
  const KdTreeData data = build_kdtree(*scene, KdTreeConfig{});
  std::vector<KdNodeLine> lines = kd_node_lines(data.nodes);
  const std::vector<KdNodeLine> unpacked = lines;
  const std::vector<TrianglePacket> packets = kd_pack_leaves(*scene, data.prims, lines);
  std::vector<std::uint32_t> todo = {0};
  std::size_t leaves = 0, used = 0;
  while (!todo.empty()) {
    const std::uint32_t i = todo.back();
    todo.pop_back();
    const KdNode& n = lines[i / 8].node[i % 8];
    const KdNode& m = unpacked[i / 8].node[i % 8];
    ASSERT_EQ(n.is_leaf(), m.is_leaf());
    if (!n.is_leaf()) {
      todo.push_back(n.above_child());
      todo.push_back(n.above_child() + 1);
      continue;
    }
    ++leaves;
    ASSERT_EQ(n.count(), m.count());
    const std::uint32_t np = (n.count() + kPacketWidth - 1) / kPacketWidth;
    ASSERT_LE(n.first + np, packets.size());
    used += np;
    for (std::uint32_t k = 0; k < np * kPacketWidth; ++k) {
      const TrianglePacket& p = packets[n.first + k / kPacketWidth];
      const int lane = static_cast<int>(k % kPacketWidth);
      if (k >= n.count()) {
        EXPECT_EQ(p.prim[lane], kInvalidId);
        continue;
      }
      const std::uint32_t prim = data.prims[m.first + k];
      ASSERT_EQ(p.prim[lane], prim);
      const auto& t = scene->mesh.triangles[prim];
      for (int v = 0; v < 3; ++v) EXPECT_TRUE(p.vertex(lane, v) == scene->mesh.vertices[t[v]]);
    }
  }
  EXPECT_GT(leaves, 0u);
  EXPECT_EQ(used, packets.size());

  const auto spheres = make("sphereflake:depth=1");
  const KdTreeData sdata = build_kdtree(*spheres, KdTreeConfig{});
  std::vector<KdNodeLine> slines = kd_node_lines(sdata.nodes);
  EXPECT_TRUE(kd_pack_leaves(*spheres, sdata.prims, slines).empty());
  for (std::size_t i = 0; i < slines.size(); ++i)
    for (int k = 0; k < 8; ++k) EXPECT_EQ(slines[i].node[k].first, kd_node_lines(sdata.nodes)[i].node[k].first);
}

/// A tree keeps only what its traversal reads: the stack traversal over packed triangles drops
/// the leaf index array (the packets carry the ids) but keeps it when spheres leave the leaves
/// unpacked; the structure hash is that of the built tree either way.
TEST(KdTree, StackTraversalOverPackedLeavesReleasesThePrimitiveIndices) {
  const auto triangles = make("soup:n=2000");
  const KdTree stack(triangles, config_for(""));
  const KdTree recursive(triangles, config_for("traversal=recursive"));
  EXPECT_TRUE(stack.data().prims.empty());
  EXPECT_FALSE(recursive.data().prims.empty());
  EXPECT_EQ(stack.structure_hash(), recursive.structure_hash());
  const KdTreeData built = build_kdtree(*triangles, config_for(""));
  EXPECT_EQ(stack.structure_hash(), fnv1a(built.prims, fnv1a(built.nodes)));
  const auto spheres = make("sphereflake:depth=1");
  EXPECT_FALSE(KdTree(spheres, config_for("")).data().prims.empty());
}

TEST(KdTree, CostParametersShapeTheTree) {
  const auto scene = make("soup:n=2000");
  const KdTree cheap_trav(scene, config_for("c_trav=1,c_isect=80"));
  const KdTree dear_trav(scene, config_for("c_trav=1,c_isect=1.5"));
  EXPECT_GT(cheap_trav.stats().nodes, dear_trav.stats().nodes);
  const KdTree capped(scene, config_for("max_depth=3"));
  EXPECT_LE(capped.data().depth, 3);
}

/// Counts the leaves that hold no primitive but have a box of positive volume.
std::size_t empty_leaves_with_volume(const KdTreeData& data) {
  std::size_t n = 0;
  for_each_kd_leaf(data, [&](const Bounds3f& box, std::uint32_t, std::uint32_t count) {
    n += count == 0 && box.lo.x < box.hi.x && box.lo.y < box.hi.y && box.lo.z < box.hi.z;
  });
  return n;
}

TEST(KdTree, EmptySpaceBonusCutsOffEmptySpace) {
  // Splits at primitive bounds leave both closed children non-empty, so only the empty-space
  // planes next to the outermost bounds can earn the bonus: without them the parameter would
  // change nothing.
  const auto scene = make("soup:n=2000");
  for (const std::string sweep : {"sort", "events"}) {
    const KdTree none(scene, config_for("empty_bonus=0,sweep=" + sweep));
    const KdTree strong(scene, config_for("empty_bonus=0.9,sweep=" + sweep));
    EXPECT_NE(none.structure_hash(), strong.structure_hash()) << sweep;
    EXPECT_GT(empty_leaves_with_volume(strong.data()), empty_leaves_with_volume(none.data())) << sweep;
  }
}

TEST(KdTree, RejectsBadParameters) {
  const auto scene = make("soup:n=50");
  EXPECT_ANY_THROW(make_accelerator("kdtree:builder=magic", scene));
  EXPECT_ANY_THROW(make_accelerator("kdtree:clip=approx", scene));
  EXPECT_ANY_THROW(make_accelerator("kdtree:c_isect=-1", scene));
}

}  // namespace
}  // namespace raylab
