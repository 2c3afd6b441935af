// The lecture's opening claim: brute force costs |Image| x |Objects|, acceleration about
// |Image| x log|Objects|. The same rays are traced with `brute` and `embree` (single thread)
// while the number of triangles grows, on decimated/subdivided CGAL meshes and on random soups;
// the per-ray times are fitted to a + b·N (brute) and a + b·log2 N (embree), and both to a power
// law c·N^α. Writes image_log_objects.csv and image_log_objects.md.
#include <fmt/format.h>

#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "experiment_common.h"
#include "cost/fit.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "|Image| x |Objects| against |Image| x log|Objects|");
  try {
    struct Family {
      std::string name;
      std::vector<std::string> scenes;
    };
    std::vector<Family> families = {
        {"cgal:bunny00 (decimated/subdivided)",
         {"decimated:of=cgal:bunny00,faces=1000", "decimated:of=cgal:bunny00,faces=4000",
          "decimated:of=cgal:bunny00,faces=16000", "cgal:bunny00", "subdivided:of=cgal:bunny00,levels=1"}},
        {"soup", {"soup:n=1000", "soup:n=4000", "soup:n=16000", "soup:n=64000", "soup:n=256000"}},
    };
    if (opt.full()) {
      families[0].scenes.push_back("subdivided:of=cgal:bunny00,levels=2");
      families[0].scenes.push_back("subdivided:of=cgal:bunny00,levels=3");
      families[1].scenes.push_back("soup:n=1024000");
      families[1].scenes.push_back("soup:n=4096000");
    }
    const std::string ray_spec = "primary:1024";
    CsvWriter csv(opt.out + "/image_log_objects.csv",
                  {"family", "scene", "triangles", "accel", "rays", "ns_per_ray", "build_s", "hit_rate",
                   "prim_tests_per_ray"});
    std::string md;
    md += "## |Image| x |Objects| against |Image| x log|Objects|\n\n";
    md += "The lecture: brute force costs |Image| x |Objects|; acceleration about |Image| x log|Objects|. ";
    md += fmt::format("The same {} rays per scene are traced with `brute` (watertight kernel) and `embree` ", ray_spec);
    md += "(medium quality), single-threaded, as the triangle count grows.\n\n";
    md += "Fits with Ceres (lib/cost/fit.h: relative residuals, Huber loss at 10%), ± one standard error.\n\n";
    md += "| family | model | fit (ns per ray) | R² | power law α (ns ∝ N^α) |\n|---|---|---|---|---|\n";
    for (const auto& fam : families) {
      std::map<std::string, std::vector<double>> ns, tris;
      for (const auto& spec : fam.scenes) {
        progress("image_log_objects: " + spec);
        const auto scene = make_scene(spec);
        const auto rays = make_ray_set(ray_spec, scene);
        for (const std::string accel_spec : {"brute", "embree"}) {
          std::unique_ptr<Aggregate> accel;
          const double build_s = seconds_of([&] { accel = make_accelerator(accel_spec, scene); });
          const TraceResult counted = trace_rays(*accel, rays, TraceOptions{1, true, false});
          const double t = ns_per_ray(*accel, rays, false, accel_spec == "brute" ? 0.0 : 0.2);
          const double n = static_cast<double>(scene->mesh.size());
          ns[accel_spec].push_back(t);
          tris[accel_spec].push_back(n);
          csv.row(fam.name, spec, scene->mesh.size(), accel_spec, rays.size(), t, build_s,
                  static_cast<double>(counted.hit_count) / rays.size(),
                  static_cast<double>(counted.counters.prim_tests) / rays.size());
        }
      }
      const FitResult brute_lin = fit_basis(tris["brute"], ns["brute"], [](double x) { return x; });
      const FitResult brute_pow = fit_power_law(tris["brute"], ns["brute"]);
      const FitResult em_log = fit_basis(tris["embree"], ns["embree"], [](double x) { return std::log2(x); });
      const FitResult em_pow = fit_power_law(tris["embree"], ns["embree"]);
      md += fmt::format("| {} | brute: a + b·N | ({}) + ({})·N | {:.4f} | {} |\n", fam.name,
                        format_with_error(brute_lin.values[0], brute_lin.std_errors[0]),
                        format_with_error(brute_lin.values[1], brute_lin.std_errors[1]), brute_lin.r2,
                        format_with_error(brute_pow.values[1], brute_pow.std_errors[1]));
      md += fmt::format("| {} | embree: a + b·log2 N | ({}) + ({})·log2 N | {:.4f} | {} |\n", fam.name,
                        format_with_error(em_log.values[0], em_log.std_errors[0]),
                        format_with_error(em_log.values[1], em_log.std_errors[1]), em_log.r2,
                        format_with_error(em_pow.values[1], em_pow.std_errors[1]));
    }
    md += "\n![per-ray time against triangle count](image_log_objects.png)\n\n";
    md += "Reading: brute force's exponent α near 1 confirms |Objects|; Embree's small α and a good fit to a + b·log2 N "
          "are the lecture's log|Objects|. Per-ray times of brute force are b ns per triangle (its per-test cost).\n\n";
    md += fmt::format("Measured by `build/experiments/exp_image_log_objects --mode {}` (run by `./lab report`); "
                      "data: image_log_objects.csv. {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/image_log_objects.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_image_log_objects: error: " << e.what() << "\n";
    return 2;
  }
}
