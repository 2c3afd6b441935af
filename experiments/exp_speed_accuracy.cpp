// Speed against accuracy, the lab's headline chart: every method one point, throughput relative
// to Embree (single thread, the same rays, passes alternated, best kept) against its error rate
// against the exact oracle (accel/common/hit_comparison.h: false hits, missed hits, wrong first
// hits) on random lines, edge-aimed and vertex-aimed rays, one chart per scene family.
//
// Methods: every accelerator the factory knows with its default parameters and every listed
// variant (the brute-force kernels mt, watertight and exact; Embree and its robust mode; the BVH's
// robust=off; ...), and for every accelerator kind `NAME:kernel=certified` when the factory
// accepts it (a method that does not exist yet is skipped, so the chart covers it once it does).
// Writes speed_accuracy.csv and speed_accuracy.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "contact_columns.h"
#include "experiment_common.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

/// Every method of the chart, named as the tool names it: each kind's defaults and listed variants,
/// then `NAME:kernel=certified` for each kind whose factory accepts it on `scene`.
std::vector<std::string> methods(const std::shared_ptr<const Scene>& scene) {
  std::vector<std::string> specs;
  for (const auto& kind : accelerator_kinds()) {
    specs.push_back(kind.name);
    for (const auto& v : kind.oracle_variants) specs.push_back(kind.name + ":" + v);
  }
  for (const auto& kind : accelerator_kinds()) {
    const std::string certified = kind.name + ":kernel=certified";
    if (std::find(specs.begin(), specs.end(), certified) != specs.end()) continue;
    try {
      make_accelerator(certified, scene);
      specs.push_back(certified);
    } catch (const InputError&) {
      // the kind has no certified kernel (yet)
    }
  }
  return specs;
}

struct Family {
  std::string name, spec, why;
  bool closed = true;  ///< a closed mesh: edge- and vertex-aimed rays cross it
};

/// Best single-thread seconds (CPU time of the tracing thread) of `method` and of `embree` on
/// `rays` over the same number of alternated passes (at least 3, and until `min_seconds` of both).
std::pair<double, double> alternating_seconds(const Primitive& method, const Primitive& embree, const std::vector<Ray>& rays,
                                              double min_seconds) {
  double best = 1e300, best_embree = 1e300, spent = 0;
  for (int pass = 0; pass < 200 && (pass < 3 || spent < min_seconds); ++pass) {
    const double e = trace_rays(embree, rays, TraceOptions{1, false, false}).thread_cpu_seconds;
    const double m = trace_rays(method, rays, TraceOptions{1, false, false}).thread_cpu_seconds;
    best_embree = std::min(best_embree, e);
    best = std::min(best, m);
    spent += e + m;
  }
  return {best, best_embree};
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "speed against accuracy: every method against Embree and the exact oracle");
  try {
    const std::vector<Family> families = {
        {"closed mesh", "decimated:of=cgal:bunny00,faces=2000", "the Stanford bunny, decimated: closed, irregular"},
        {"tessellated sphere", "sphere:n=2000", "a UV sphere: closed, with two pole vertices of high valence"},
        {"open soup", "soup:n=2000", "random triangles: open, so edge and vertex rays graze", false},
        {"axis-aligned walls", "walls:n=50,angle=0", "boxes whose faces lie in split planes"}};
    const std::string count = opt.full() ? "8192" : "2048";
    const std::vector<std::string> ray_kinds = {"lines:" + count, "edges:" + count, "vertices:" + count};
    const double min_s = opt.full() ? 0.3 : 0.03;
    CsvWriter csv(opt.out + "/speed_accuracy.csv",
                  {"family", "scene", "method", "rays", "ray_count", "mismatches", "false_hits", "missed_hits", "wrong_t",
                   "ties", "error_rate", "seconds", "embree_seconds", "throughput_vs_embree",
                   "rays_crossing_well_conditioned", "mismatches_crossing_well_conditioned", "rays_touching",
                   "mismatches_touching", "rays_on_surface", "mismatches_on_surface", "rays_ill_conditioned",
                   "mismatches_ill_conditioned"});
    struct Point {
      double throughput = 0, errors = 0, rays = 0;
      std::map<std::string, HitComparison> by_kind;
      ContactColumns contact;  ///< over the ray kinds
    };
    std::map<std::string, std::map<std::string, Point>> points;  // family -> method -> point
    std::vector<std::string> all_methods;
    for (const auto& fam : families) {
      const auto scene = make_scene(fam.spec);
      const double diagonal = length(Vec3d(scene->bounds().diagonal()));
      std::vector<Ray> rays;
      std::map<std::string, std::pair<std::size_t, std::size_t>> ranges;  // kind -> [begin, end)
      for (const auto& k : ray_kinds) {
        const auto r = make_ray_set(k, scene);
        ranges[k] = {rays.size(), rays.size() + r.size()};
        rays.insert(rays.end(), r.begin(), r.end());
      }
      const auto oracle = make_accelerator("exact", scene);
      const TraceResult reference = trace_rays(*oracle, rays, TraceOptions{0, false, false});
      const std::vector<RayContact> classes = classify_contacts(scene, rays);
      const auto embree = make_accelerator("embree", scene);
      for (const auto& m : methods(scene)) {
        if (std::find(all_methods.begin(), all_methods.end(), m) == all_methods.end()) all_methods.push_back(m);
        progress("speed_accuracy: " + fam.spec + " " + m);
        const auto accel = make_accelerator(m, scene);
        const TraceResult got = trace_rays(*accel, rays, TraceOptions{1, false, false});
        const auto [seconds, embree_seconds] = alternating_seconds(*accel, *embree, rays, min_s);
        Point p;
        p.throughput = embree_seconds / seconds;
        for (const auto& k : ray_kinds) {
          const auto [b, e] = ranges[k];
          const std::vector<Ray> kr(rays.begin() + b, rays.begin() + e);
          const std::vector<Hit> kh(got.hits.begin() + b, got.hits.begin() + e);
          const std::vector<Hit> ref(reference.hits.begin() + b, reference.hits.begin() + e);
          const std::vector<RayContact> kc(classes.begin() + b, classes.begin() + e);
          const HitComparison c = compare_hits(kr, kh, ref, diagonal, &kc);
          p.by_kind[k] = c;
          p.errors += static_cast<double>(c.mismatches);
          p.rays += static_cast<double>(c.rays);
          const ContactColumns cc = ContactColumns::of(c);
          p.contact.add(cc);
          csv.row(fam.name, fam.spec, m, k, c.rays, c.mismatches, c.false_hits, c.missed_hits, c.wrong_t, c.ties,
                  c.mismatch_rate(), seconds, embree_seconds, p.throughput, cc.rays[0], cc.mismatches[0], cc.rays[1],
                  cc.mismatches[1], cc.rays[2], cc.mismatches[2], cc.rays[3], cc.mismatches[3]);
        }
        csv.row(fam.name, fam.spec, m, std::string("all"), p.rays, p.errors, 0, 0, 0, 0, p.errors / p.rays, seconds,
                embree_seconds, p.throughput, p.contact.rays[0], p.contact.mismatches[0], p.contact.rays[1],
                p.contact.mismatches[1], p.contact.rays[2], p.contact.mismatches[2], p.contact.rays[3],
                p.contact.mismatches[3]);
        points[fam.name][m] = p;
      }
    }

    std::string md = section_anchor("speed-accuracy");
    md += "## Speed against accuracy\n\n";
    md += fmt::format(
        "Every method is one point: throughput relative to Embree (`embree`, medium quality; single thread, timed in "
        "the tracing thread's CPU time; the same rays; passes alternated with Embree's, best of at least three kept) against its error rate, the fraction of "
        "rays whose closest hit disagrees with the exact oracle (`exact`): false hits, missed hits and wrong first hits "
        "(t off by more than the tolerance of `raylab trace --check`; a hit on another triangle at the same t is a tie, "
        "not an error). Rays: {} isotropic random lines (`lines:`), {} rays aimed exactly at edges (`edges:`) and {} at "
        "vertices (`vertices:`) per scene. Methods: every accelerator with its defaults and each variant the factory "
        "lists (`raylab accels`), and `NAME:kernel=certified` for every accelerator that accepts it. Command: "
        "`build/experiments/exp_speed_accuracy --mode {}`.\n\n",
        count, count, count, opt.mode);
    md += "| scene family | scene | why |\n|---|---|---|\n";
    for (const auto& f : families) md += fmt::format("| {} | `{}` | {} |\n", f.name, f.spec, f.why);
    md += "\n![speed against accuracy](speed_accuracy.png)\n\n";
    md += "Each cell: throughput relative to Embree, then errors on lines / edge-aimed / vertex-aimed rays (each of " +
          count + " rays); **0** where the method agrees with the oracle on every ray.\n\n| method |";
    for (const auto& f : families) md += " " + f.name + " |";
    md += "\n|---|";
    for (std::size_t i = 0; i < families.size(); ++i) md += "---|";
    md += "\n";
    std::map<std::string, double> total_errors, log_throughput;
    for (const auto& m : all_methods) {
      md += "| `" + m + "` |";
      int n = 0;
      for (const auto& f : families) {
        if (!points[f.name].count(m)) {
          md += " – |";
          continue;
        }
        const Point& p = points[f.name][m];
        std::string errs;
        for (const auto& k : ray_kinds) errs += (errs.empty() ? "" : " / ") + std::to_string(p.by_kind.at(k).mismatches);
        md += fmt::format(" {:.3g}×, {} |", p.throughput, p.errors == 0 ? std::string("**0**") : errs);
        total_errors[m] += p.errors;
        log_throughput[m] += std::log(p.throughput);
        ++n;
      }
      if (n) log_throughput[m] /= n;
      md += "\n";
    }
    // The fastest method overall, the fastest with no error on the closed families (where a
    // watertight float method can agree exactly), and the fastest with no error on any family.
    auto fastest_of = [&](const std::function<bool(const std::string&)>& admit) {
      std::string best;
      for (const auto& m : all_methods)
        if (log_throughput.count(m) && admit(m) && (best.empty() || log_throughput[m] > log_throughput[best])) best = m;
      return best;
    };
    auto closed_errors = [&](const std::string& m) {
      double e = 0;
      for (const auto& f : families)
        if (f.closed && points[f.name].count(m)) e += points[f.name][m].errors;
      return e;
    };
    const std::string fastest = fastest_of([](const std::string&) { return true; });
    const std::string fastest_closed = fastest_of([&](const std::string& m) { return closed_errors(m) == 0; });
    const std::string fastest_exact = fastest_of([&](const std::string& m) { return total_errors[m] == 0; });
    auto ratio_text = [&](const std::string& m) {
      return m.empty() ? std::string("–") : fmt::format("`{}` ({:.3g}× Embree)", m, std::exp(log_throughput[m]));
    };
    md += fmt::format(
        "\nOver the four families (geometric mean of the throughput ratios): the fastest method is {} with {} errors; "
        "the fastest with no error on the closed families is {}; the fastest with no error on any family, the open "
        "soup included, is {}. `embree` made {} errors ({} on the closed families) and `embree-robust` {} ({}); the "
        "exact oracle `exact` runs at {:.3g}× Embree.\n\n",
        ratio_text(fastest), total_errors[fastest], ratio_text(fastest_closed), ratio_text(fastest_exact),
        total_errors["embree"], closed_errors("embree"), total_errors["embree-robust"], closed_errors("embree-robust"),
        std::exp(log_throughput["exact"]));
    // Per class of first contact (the accuracy statements bound each, raylab accels).
    {
      ContactColumns all;
      for (const auto& f : families)
        if (points[f.name].count("embree")) all.add(points[f.name]["embree"].contact);
      md += "Errors per class of first contact, over the four families: the exact oracle classifies each ray "
            "(`raylab trace --classify`; `lib/accel/exact/contact_classes.h`) as **crossing** the surface (or missing "
            "it), **touching** it, or starting **on** it, and as **ill-conditioned** when its exact answer changes "
            "as the ray moves by a few ulps (every touching and on-surface ray, and rays that pass within the float "
            "error scale of a contour). Each cell: mismatches (rate). A watertight float method errs only on "
            "ill-conditioned rays; the exact and certified ones nowhere.\n\n";
      md += "| method " + all.header() + "\n|---|---|---|---|---|\n";
      for (const auto& m : all_methods) {
        ContactColumns k;
        for (const auto& f : families)
          if (points[f.name].count(m)) k.add(points[f.name][m].contact);
        md += "| `" + m + "` |" + k.cells() + "\n";
      }
      md += "\n";
    }
    md += fmt::format("Data: speed_accuracy.csv (per method, family and ray kind). Measured by "
                      "`build/experiments/exp_speed_accuracy --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/speed_accuracy.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_speed_accuracy: error: " << e.what() << "\n";
    return 2;
  }
}
