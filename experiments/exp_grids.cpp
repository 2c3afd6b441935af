// The lecture's grids, measured: (1) the resolution heuristic max(nx,ny,nz) = d·∛n swept over d
// on a uniform scene (grass) and non-uniform ones (the sphereflake, the teapot-in-a-stadium);
// (2) placement by bounding box against exact placement; (3) mailboxes; (4) where uniform grids
// work and where they fail: uniform grid, nested grid, two-level grid and Embree on the three
// scenes; (5) the performance goals (grass of a million blades, build throughput with
// place=bbox). Every timing is single-threaded and paired with Embree on the same rays in the same run.
// Writes grids.csv and grids.md.
#include <fmt/format.h>

#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/grid/uniform_grid.h"
#include "experiment_common.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

struct Measured {
  double ns = 0, tests = 0, cells = 0, skips = 0, build_s = 0, hit_rate = 0;
  std::size_t bytes = 0, nodes = 0;
};

/// Seconds to allocate `count` 32-bit values with operator new, as a build allocates its
/// reference array, and write them once in order, best of three: the least time any build that
/// stores `count` cell references can take on this machine. Blocks beyond glibc's mmap threshold
/// (at most 32 MiB) are fresh pages each time, so the kernel's page faults and zeroing count;
/// smaller blocks reuse the heap's pages.
double first_touch_seconds(std::size_t count) {
  double best = 1e300;
  [[maybe_unused]] static volatile std::uint32_t sink;  // a value read back keeps the writes observable
  for (int rep = 0; rep < 3; ++rep) {
    std::unique_ptr<std::uint32_t[]> refs;
    best = std::min(best, seconds_of([&] {
      refs.reset(new std::uint32_t[count]);  // default-initialised: not zeroed by the allocator
      for (std::size_t i = 0; i < count; ++i) refs[i] = static_cast<std::uint32_t>(i);
    }));
    if (count > 0) sink = refs[count / 2];
  }
  return best;
}

Measured measure(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene, const std::vector<Ray>& rays,
                 double min_seconds) {
  Measured m;
  std::unique_ptr<Aggregate> accel;
  m.build_s = seconds_of([&] { accel = make_accelerator(accel_spec, scene); });
  const TraceResult counted = trace_rays(*accel, rays, TraceOptions{1, true, false});
  const double n = static_cast<double>(rays.size());
  m.tests = static_cast<double>(counted.counters.prim_tests) / n;
  m.cells = static_cast<double>(counted.counters.nodes) / n;
  m.skips = static_cast<double>(counted.counters.mailbox_skips) / n;
  m.hit_rate = static_cast<double>(counted.hit_count) / n;
  m.ns = ns_per_ray(*accel, rays, false, min_seconds);
  m.bytes = accel->stats().bytes;
  m.nodes = accel->stats().nodes;
  return m;
}

struct Case {
  std::string label;  ///< grass | sphereflake | stadium
  std::string spec;
  std::shared_ptr<const Scene> scene;
  std::vector<Ray> rays;
  Measured embree;
};

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "uniform and nested grids: resolution, placement, mailboxes");
  try {
    const bool full = opt.full();
    const double min_s = full ? 0.2 : 0.1;
    const std::string ray_spec = full ? "primary:65536" : "primary:16384";
    std::vector<Case> cases = {
        {"grass", full ? "grass:blades=1000000" : "grass:blades=30000", nullptr, {}, {}},
        {"sphereflake", full ? "sphereflake:depth=5" : "sphereflake:depth=4", nullptr, {}, {}},
        {"stadium", full ? "stadium:object=(sphere:n=100000),ratio=1000" : "stadium:object=(sphere:n=20000),ratio=1000",
         nullptr, {}, {}},
    };
    CsvWriter csv(opt.out + "/grids.csv",
                  {"experiment", "scene", "scene_spec", "primitives", "accel", "d", "rays", "ns_per_ray",
                   "embree_ns_per_ray", "ratio_to_embree", "prim_tests_per_ray", "cells_per_ray",
                   "mailbox_skips_per_ray", "build_s", "bytes", "cells", "hit_rate"});
    auto row = [&](const std::string& exp, const Case& c, const std::string& accel, double d, const Measured& m) {
      csv.row(exp, c.label, c.spec, c.scene->primitive_count(), accel, d, c.rays.size(), m.ns, c.embree.ns,
              m.ns / c.embree.ns, m.tests, m.cells, m.skips, m.build_s, m.bytes, m.nodes, m.hit_rate);
    };
    for (auto& c : cases) {
      progress("grids: scene " + c.spec);
      c.scene = make_scene(c.spec);
      c.rays = make_ray_set(ray_spec, c.scene);
      c.embree = measure("embree", c.scene, c.rays, min_s);
      row("embree", c, "embree", 0.0, c.embree);
    }

    std::string md = "## Uniform and nested grids\n\n";
    md += fmt::format(
        "The lecture's uniform grid (`grid`: resolution max(nx,ny,nz) = d·∛n, 3D-DDA of Amanatides and Woo, in-cell "
        "acceptance, per-ray mailbox) and nested grids (`nested-grid`, and `mode=two-level` after Kalojanov, Billeter and "
        "Slusallek 2011), against Embree (medium quality) on the same {} rays, single-threaded. Scenes: {}, {}, {}.\n\n",
        ray_spec, cases[0].spec, cases[1].spec, cases[2].spec);

    // (1) resolution sweep
    const std::vector<double> ds = {0.5, 1, 1.5, 2, 3, 4, 6, 8};
    md += "### Resolution: the density d\n\n| scene | best d (time) | ns/ray at best d | ns/ray at d=3 | d=3 / best | "
          "tests/ray at d=0.5, 3, 8 | grid/Embree at d=3 |\n|---|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
      double best_d = 0, best_ns = 1e300;
      std::map<double, Measured> by_d;
      for (double d : ds) {
        progress(fmt::format("grids: resolution {} d={}", c.label, d));
        const Measured m = measure(fmt::format("grid:d={}", d), c.scene, c.rays, min_s);
        row("resolution", c, "grid", d, m);
        by_d[d] = m;
        if (m.ns < best_ns) best_ns = m.ns, best_d = d;
      }
      md += fmt::format("| {} | {} | {:.0f} | {:.0f} | {:.2f} | {:.1f}, {:.1f}, {:.1f} | {:.1f} |\n", c.label, best_d, best_ns,
                        by_d[3].ns, by_d[3].ns / best_ns, by_d[0.5].tests, by_d[3].tests, by_d[8].tests,
                        by_d[3].ns / c.embree.ns);
    }
    md += "\n![time and tests per ray against d](grids_resolution.png)\n\n";

    // (2) placement
    md += "### Placement: bounding box against exact\n\n| scene | place | tests/ray | ns/ray | build s | MiB | refs/cell "
          "memory vs bbox |\n|---|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
      Measured bbox;
      for (const std::string place : {"bbox", "exact"}) {
        progress("grids: placement " + c.label + " " + place);
        const Measured m = measure("grid:place=" + place, c.scene, c.rays, min_s);
        row("placement", c, "grid:place=" + place, 3.0, m);
        if (place == "bbox") bbox = m;
        md += fmt::format("| {} | {} | {:.1f} | {:.0f} | {:.3f} | {:.1f} | {:.2f} |\n", c.label, place, m.tests, m.ns, m.build_s,
                          m.bytes / 1048576.0, double(m.bytes) / double(bbox.bytes));
      }
    }
    md += "\n";

    // (3) mailboxes
    md += "### Mailboxes\n\n| scene | tests/ray off | tests/ray on | tests saved | ns/ray off | ns/ray on | time saved "
          "|\n|---|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
      progress("grids: mailbox " + c.label);
      const Measured off = measure("grid:mailbox=off", c.scene, c.rays, min_s);
      const Measured on = measure("grid:mailbox=on", c.scene, c.rays, min_s);
      row("mailbox", c, "grid:mailbox=off", 3.0, off);
      row("mailbox", c, "grid:mailbox=on", 3.0, on);
      md += fmt::format("| {} | {:.1f} | {:.1f} | {:.0f}% | {:.0f} | {:.0f} | {:.0f}% |\n", c.label, off.tests, on.tests,
                        100.0 * (1.0 - on.tests / off.tests), off.ns, on.ns, 100.0 * (1.0 - on.ns / off.ns));
    }
    md += "\n";

    // (4) where grids work and where they fail
    const std::vector<std::string> accels = {"grid", "nested-grid", "nested-grid:mode=two-level"};
    md += "### Where grids work and where they fail\n\n| scene | accelerator | ns/ray | / Embree | tests/ray | cells/ray | "
          "build s | MiB |\n|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : cases) {
      md += fmt::format("| {} | embree | {:.0f} | 1.00 | – | – | {:.3f} | – |\n", c.label, c.embree.ns, c.embree.build_s);
      for (const auto& a : accels) {
        progress("grids: compare " + c.label + " " + a);
        const Measured m = measure(a, c.scene, c.rays, min_s);
        row("compare", c, a, 3.0, m);
        md += fmt::format("| {} | {} | {:.0f} | {:.2f} | {:.1f} | {:.1f} | {:.3f} | {:.1f} |\n", c.label, a, m.ns,
                          m.ns / c.embree.ns, m.tests, m.cells, m.build_s, m.bytes / 1048576.0);
      }
    }
    md += "\n![grids against Embree](grids_compare.png)\n\n";

    // (5) the performance goals: trace throughput on grass of a million blades (and on the
    // sphereflake and the stadium), and build throughput with place=bbox
    {
      Case big{"grass 1M", "grass:blades=1000000", nullptr, {}, {}};
      progress("grids: goals, scene " + big.spec);
      big.scene = make_scene(big.spec);
      big.rays = make_ray_set("primary:65536", big.scene);
      big.embree = measure("embree", big.scene, big.rays, min_s);
      row("embree", big, "embree", 0.0, big.embree);
      md += "### Performance goals\n\nTrace throughput, single thread, as a fraction of Embree's on the same rays "
            "(goal on grass of a million blades: ≥ 0.3):\n\n| scene | accelerator | ns/ray | Embree ns/ray | throughput / "
            "Embree's | tests/ray |\n|---|---|---|---|---|---|\n";
      std::vector<const Case*> goal_cases = {&big, &cases[1], &cases[2]};
      for (const Case* c : goal_cases)
        for (const std::string a : {"grid", "grid:place=exact"}) {
          progress("grids: goals, trace " + c->label + " " + a);
          const Measured m = measure(a, c->scene, c->rays, min_s);
          row("goal_trace", *c, a, 3.0, m);
          md += fmt::format("| {} | {} | {:.0f} | {:.0f} | {:.2f} | {:.1f} |\n", c->label, a, m.ns, c->embree.ns,
                            c->embree.ns / m.ns, m.tests);
        }
      md += "\nBuild throughput with `place=bbox`, single thread, best of three builds (goal: ≥ 10 M triangles/s). A "
            "build's work is its cell references, one per cell a bounding box overlaps: grass blades are tall and thin, "
            "so at d = 3 each spans ~70 cells. *Floor* is the time to allocate that many 32-bit references as the build "
            "does and write each once in order, and nothing else (best of three; arrays above 32 MiB are fresh pages, "
            "so the kernel's page faults and zeroing count): no build that stores its references can be faster on this "
            "machine.\n\n| scene | primitives | d | build s | "
            "M primitives/s | references per primitive | floor s | M primitives/s at the floor |\n"
            "|---|---|---|---|---|---|---|---|\n";
      std::vector<Case> build_cases = {big, cases[1], cases[2]};
      build_cases.push_back({"bunny 1.2M", "subdivided:of=cgal:bunny00,levels=2", make_scene("subdivided:of=cgal:bunny00,levels=2"), {}, {}});
      build_cases.push_back({"armadillo", "cgal:armadillo", make_scene("cgal:armadillo"), {}, {}});
      for (const Case& c : build_cases)
        for (const double d : {3.0, 1.0}) {
          progress(fmt::format("grids: goals, build {} d={}", c.label, d));
          const std::string spec = fmt::format("grid:place=bbox,d={}", d);
          double best = 1e300;
          std::unique_ptr<Aggregate> grid;
          for (int rep = 0; rep < 3; ++rep) {
            grid.reset();
            best = std::min(best, seconds_of([&] { grid = make_accelerator(spec, c.scene); }));
          }
          const auto* uniform = dynamic_cast<const UniformGrid*>(grid.get());
          const double refs = uniform ? static_cast<double>(uniform->cells().refs.size()) : 0.0;
          const double n = static_cast<double>(c.scene->primitive_count());
          Measured m;
          m.build_s = best;
          m.bytes = grid->stats().bytes;
          m.nodes = grid->stats().nodes;
          csv.row("goal_build", c.label, c.spec, c.scene->primitive_count(), spec, d, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                  m.build_s, m.bytes, m.nodes, 0.0);
          const double floor_s = first_touch_seconds(static_cast<std::size_t>(refs));
          csv.row("goal_build_floor", c.label, c.spec, c.scene->primitive_count(), spec, d, 0, 0.0, 0.0, 0.0, 0.0, 0.0,
                  0.0, floor_s, refs * sizeof(std::uint32_t), 0, 0.0);
          md += fmt::format("| {} | {} | {} | {:.3f} | {:.1f} | {:.1f} | {:.3f} | {:.1f} |\n", c.label,
                            c.scene->primitive_count(), d, best, n / best / 1e6, refs / n, floor_s, n / floor_s / 1e6);
        }
      md += "\n";
    }
    md += "Reading: the tables above are the answer, per scene; the resolution table gives the measured best d next to "
          "the lecture's d = 3. Primary rays of these cameras see mostly the large, evenly spread primitives (grass "
          "blades, the stadium's stands), so the crowded cells a nested grid refines are rarely visited; exact placement "
          "drops the references of primitives whose bounding box but not surface meets a cell; the mailbox always saves "
          "tests, and saves time only where a re-test costs more than the mailbox lookup.\n\n";
    md += fmt::format("Measured by `build/experiments/exp_grids --mode {}` (run by `./lab report`); data: grids.csv. {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/grids.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_grids: error: " << e.what() << "\n";
    return 2;
  }
}
