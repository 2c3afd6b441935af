// Agreement with the exact oracle on the CGAL demo meshes: brute force (watertight and
// Möller-Trumbore kernels), Embree and Embree's robust mode, on primary and diffuse rays and, for
// closed meshes, on rays aimed at edges and vertices. Counts are those of
// `raylab trace --check exact`. Writes oracle_agreement.csv and oracle_agreement.md.
#include <fmt/format.h>

#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "experiment_common.h"
#include "scene/cgal_meshes.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "agreement of brute force and Embree with the exact oracle");
  try {
    const std::vector<std::string> meshes = opt.full() ? cgal_mesh_names() : cgal_reference_meshes();
    // Rays per mesh and kind. Quick mode: 1024 camera and diffuse rays, where no method has
    // mismatched in any report (every row 0), and 2048 rays aimed at edges and vertices, where the
    // methods differ; brute force, |rays| × |triangles|, is most of the experiment's time.
    const int n_plain = opt.full() ? 16384 : 1024, n_features = opt.full() ? 16384 : 2048;
    const std::vector<std::string> accels = {"brute:kernel=watertight", "brute:kernel=mt", "embree", "embree-robust"};
    CsvWriter csv(opt.out + "/oracle_agreement.csv",
                  {"mesh", "triangles", "closed", "rays", "accel", "count", "mismatches", "false_hits", "missed_hits",
                   "wrong_t", "ties"});
    // totals[accel][ray kind] = {mismatches, rays}
    std::map<std::string, std::map<std::string, std::pair<std::size_t, std::size_t>>> totals;
    std::size_t mesh_count = 0, closed_count = 0;
    std::string skipped;
    for (const auto& name : meshes) {
      const std::string spec = "cgal:" + name;
      std::shared_ptr<const Scene> scene;
      try {
        scene = make_scene(spec);
      } catch (const InputError& e) {
        skipped += fmt::format("- `{}`: {}\n", spec, e.what());
        continue;
      }
      const bool closed = describe(*scene).closed;
      ++mesh_count;
      closed_count += closed;
      progress(fmt::format("oracle_agreement: {} ({} triangles{})", spec, scene->mesh.size(), closed ? ", closed" : ""));
      const auto oracle = make_accelerator("exact", scene);
      std::vector<std::string> kinds = {"primary", "diffuse"};
      if (closed) kinds.insert(kinds.end(), {"edges", "vertices"});
      std::map<std::string, std::unique_ptr<Aggregate>> built;
      for (const auto& a : accels) built[a] = make_accelerator(a, scene);
      const double diagonal = length(Vec3d(scene->bounds().diagonal()));
      for (const auto& kind : kinds) {
        const bool features = kind == "edges" || kind == "vertices";
        const std::string ray_spec = fmt::format("{}:{}", kind, features ? n_features : n_plain);
        const auto rays = make_ray_set(ray_spec, scene);
        const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{});
        for (const auto& a : accels) {
          const TraceResult got = trace_rays(*built[a], rays, TraceOptions{});
          const HitComparison c = compare_hits(rays, got.hits, ref.hits, diagonal);
          csv.row(name, scene->mesh.size(), closed ? 1 : 0, kind, a, rays.size(), c.mismatches, c.false_hits,
                  c.missed_hits, c.wrong_t, c.ties);
          auto& t = totals[a][kind];
          t.first += c.mismatches;
          t.second += rays.size();
        }
      }
    }
    std::string md = "## Agreement with the exact oracle on the CGAL demo meshes\n\n";
    md += fmt::format(
        "{} CGAL demo meshes ({} of them closed), {} camera and {} diffuse rays per mesh, {} edge- and {} "
        "vertex-aimed rays on each closed mesh{}. A mismatch is a false hit, a missed hit, or a t off by more than the stated bound "
        "(see `raylab trace --check`); hits on another triangle at the same t are ties, not mismatches.\n\n",
        mesh_count, closed_count, n_plain, n_plain, n_features, n_features,
        opt.full() ? "" : " (quick mode; `--mode full` traces 16384 of each kind on every CGAL demo mesh)");
    md += "| accelerator | primary | diffuse | edges | vertices |\n|---|---|---|---|---|\n";
    for (const auto& a : accels) {
      md += "| `" + a + "` |";
      for (const std::string kind : {"primary", "diffuse", "edges", "vertices"}) {
        const auto& t = totals[a][kind];
        md += t.second ? fmt::format(" {} of {} ({:.3f}%) |", t.first, t.second, 100.0 * t.first / t.second) : " – |";
      }
      md += "\n";
    }
    md += "\nPer-mesh counts: oracle_agreement.csv.";
    if (!skipped.empty()) md += " Meshes that could not be loaded:\n\n" + skipped;
    md += fmt::format("\n\nMeasured by `build/experiments/exp_oracle_agreement --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/oracle_agreement.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_oracle_agreement: error: " << e.what() << "\n";
    return 2;
  }
}
