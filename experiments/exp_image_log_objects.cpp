// The lecture's opening claim: brute force costs |Image| x |Objects|, acceleration about
// |Image| x log|Objects|. Every structure traces the same rays (single thread) while the number
// of primitives grows, on random soups, the Stanford bunny (decimated and subdivided) and the
// sphereflake (spheres); operations per ray (node and leaf visits plus primitive tests) and time
// per ray are fitted to a + b·log2 N and to c·N^α. Then the four families where the claim fails
// (procedural.h: dust, needles, fan, row), each with its fitted exponent. The same runs give the
// section on the computational geometry of ray shooting (claim 5): memory against query cost as
// n grows, with fitted exponents, next to the bounds of Pellegrini (1993), Mohaban and Sharir
// (1997) and Aronov, de Berg and Gray (2008).
// Writes image_log_objects.csv, image_log_objects_fits.csv, image_log_objects.md,
// ray_shooting_bounds.md and their verdicts.
#include <fmt/format.h>

#include <cmath>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "cost/replicates.h"
#include "experiment_common.h"
#include "scene/procedural.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

struct Family {
  std::string name;   ///< soup | bunny | sphereflake | dust | needles | fan | row
  std::string what;   ///< one phrase for the tables
  std::vector<std::string> scenes;
  std::vector<std::string> accels;
  std::string rays;   ///< a ray spec; empty: the near-miss rays of the row scene
  bool failure = false;
};

/// The largest primitive count at which `accel` runs on `family` in this mode: brute force to 2^16
/// (2^20 in full mode), as the issue asks; the BSP and the octree on triangles, whose builds (exact
/// clipping) take minutes beyond, to 2^14 and 2^18 (2^16 and 2^20); the octree over the
/// sphereflake's spheres (no clipping: 0.35 s at depth 6, 597,871 spheres) to every depth, so that
/// its exponent has as many sizes as the other structures'. A uniform grid places a primitive in every cell its
/// box overlaps, and every needle's or fan triangle's box overlaps a fixed fraction of the grid:
/// its references grow as N², so it stops at 2^10 on the needles and 2^12 on the fan.
double size_cap(const std::string& accel, const std::string& family, bool full) {
  const std::string name = accel.substr(0, accel.find(':'));
  if (name == "brute") return full ? 1 << 20 : 1 << 16;
  if (name == "bsp") return full ? 1 << 16 : 1 << 14;
  if (name == "octree" && family != "sphereflake") return full ? 1 << 20 : 1 << 18;
  if (name == "grid" && family == "needles") return full ? 1 << 11 : 1 << 10;
  if (name == "grid" && family == "fan") return full ? 1 << 13 : 1 << 12;
  return 1e300;
}

std::vector<Family> families(bool full) {
  const std::vector<std::string> all = {"grid", "nested-grid", "kdtree", "octree", "bsp", "bvh", "embree", "brute"};
  std::vector<Family> f;
  {
    Family soup{"soup", "random triangles, soup:n=N", {}, all, "primary:1024"};
    // Every power of two up to 2^14 (cheap), so that the BSP tree and the octree, which stop early,
    // have enough points for a decisive interval; every second one beyond.
    for (int k = 10; k <= (full ? 24 : 20); k += k < 14 ? 1 : 2) soup.scenes.push_back(fmt::format("soup:n={}", 1 << k));
    f.push_back(soup);
  }
  {
    Family bunny{"bunny", "the Stanford bunny, decimated and Loop-subdivided",
                 {"decimated:of=cgal:bunny00,faces=1024", "decimated:of=cgal:bunny00,faces=4096",
                  "decimated:of=cgal:bunny00,faces=16384", "cgal:bunny00", "subdivided:of=cgal:bunny00,levels=1",
                  "subdivided:of=cgal:bunny00,levels=2"},
                 {"kdtree", "bvh", "embree", "brute"}, "primary:1024"};
    if (full) bunny.scenes.push_back("subdivided:of=cgal:bunny00,levels=3");
    f.push_back(bunny);
  }
  {
    Family flake{"sphereflake", "spheres, sphereflake:depth=D", {}, {"grid", "kdtree", "octree", "bvh", "embree", "brute"},
                 "primary:1024"};
    for (int d = 2; d <= (full ? 7 : 6); ++d) flake.scenes.push_back(fmt::format("sphereflake:depth={}", d));
    f.push_back(flake);
  }
  const std::vector<std::string> failing = {"grid", "kdtree", "bvh", "embree"};
  const int top = full ? 18 : 14;
  auto sweep = [&](const std::string& name, const std::string& what, const std::string& rays) {
    Family fam{name, what, {}, failing, rays, true};
    for (int k = 8; k <= top; ++k) fam.scenes.push_back(fmt::format("{}:n={}", name, 1 << k));
    f.push_back(fam);
  };
  sweep("dust", "rays that escape: tiny triangles, almost every ray hits nothing", "primary:1024");
  sweep("needles", "parallel needles whose boxes all overlap", "primary:1024");
  sweep("fan", "a vertex of valence N", "primary:1024");
  sweep("row", "a near-miss row along the ray", "");
  return f;
}

struct Run {
  double n = 0;
  TraceCost cost;
  std::size_t bytes = 0;
  std::vector<double> ns_rounds;  ///< ns/ray per replicate round; cost.ns is their median
  IntervalEstimate ns;            ///< that median with its 95% bootstrap interval
};

/// Alternated rounds of every timing: at each N, each round traces every structure and Embree in
/// turn, each for at least min_s / kTimeRounds of thread CPU time (at least one pass), keeping its
/// fastest pass.
constexpr int kTimeRounds = 5;

std::vector<Ray> rays_for(const Family& fam, const std::shared_ptr<const Scene>& scene) {
  if (!fam.rays.empty()) return make_ray_set(fam.rays, scene);
  NearMissRowConfig c;
  c.triangles = static_cast<std::int64_t>(scene->primitive_count());
  return near_miss_row_rays(c, 1024, 1);
}

std::vector<double> column(const std::vector<Run>& runs, double (*get)(const Run&)) {
  std::vector<double> v;
  for (const auto& r : runs) v.push_back(get(r));
  return v;
}

double log2_of(double x) { return std::log2(x); }

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "|Image| x |Objects| against |Image| x log|Objects|, and where it fails");
  try {
    if (!opt.claim.empty() && !opt.runs_claim({"1", "1b", "1c", "1d", "1e", "5"}))
      throw InputError("--claim " + opt.claim + ": exp_image_log_objects decides claims 1, 1b–1e and 5 only (all from one run)");
    const double min_s = opt.full() ? 0.2 : 0.05;
    CsvWriter csv(opt.out + "/image_log_objects.csv",
                  {"family", "scene", "primitives", "accel", "rays", "nodes_per_ray", "leaves_per_ray", "tests_per_ray",
                   "ops_per_ray", "ns_per_ray", "ns_per_ray_lo", "ns_per_ray_hi", "rounds", "embree_ns_per_ray", "bytes",
                   "hit_rate", "embree_ns_per_ray_lo", "embree_ns_per_ray_hi"});
    FitsCsv fits(opt.out + "/image_log_objects_fits.csv");
    // family -> accel -> runs, in growing N
    std::map<std::string, std::map<std::string, std::vector<Run>>> runs;
    const auto fams = families(opt.full());
    for (const auto& fam : fams) {
      for (const auto& spec : fam.scenes) {
        const auto scene = make_scene(spec);
        const double n = scene->total_primitive_count();
        const auto rays = rays_for(fam, scene);
        IntervalEstimate embree_ns;  // value 0: Embree not timed at this N
        embree_ns.value = 0;
        // Every structure built at this N, kept for the alternated rounds.
        std::vector<std::string> timed;
        std::vector<std::unique_ptr<Aggregate>> kept;
        for (const auto& a : fam.accels) {
          if (n > size_cap(a, fam.name, opt.full())) continue;
          progress(fmt::format("image_log_objects: {} (N = {:.0f}) {}", spec, n, a));
          Run r;
          r.n = n;
          std::unique_ptr<Aggregate> accel = make_accelerator(a, scene);
          r.cost = trace_cost(*accel, rays, false, 0.0);  // the counters; the time comes from the rounds
          r.bytes = accel->stats().bytes;
          runs[fam.name][a].push_back(r);
          timed.push_back(a);
          kept.push_back(std::move(accel));
        }
        if (!kept.empty()) {
          progress(fmt::format("image_log_objects: {} (N = {:.0f}), {} structures in {} alternated rounds", spec, n,
                               kept.size(), kTimeRounds));
          std::vector<const Primitive*> contenders;
          for (const auto& k : kept) contenders.push_back(k.get());
          ReplicateOptions o;
          o.rounds = kTimeRounds;
          o.min_round_seconds = min_s / kTimeRounds;
          const ReplicateTiming t = time_replicates(contenders, rays, o);
          for (std::size_t i = 0; i < timed.size(); ++i) {
            Run& r = runs[fam.name][timed[i]].back();
            r.ns_rounds = t.ns[i];
            r.ns = t.ns_per_ray(i);
            r.cost.ns = r.ns.value;
            if (timed[i] == "embree") embree_ns = r.ns;
          }
        }
        for (const auto& a : fam.accels) {
          auto& v = runs[fam.name][a];
          if (v.empty() || v.back().n != n) continue;
          const Run& r = v.back();
          csv.row(fam.name, spec, n, a, rays.size(), r.cost.nodes, r.cost.leaves, r.cost.tests, r.cost.ops(), r.cost.ns,
                  r.ns.lo, r.ns.hi, r.ns.replicates, embree_ns.value, r.bytes, r.cost.hit_rate, embree_ns.lo,
                  embree_ns.hi);
        }
      }
    }

    // Fits per family and structure: operations and time, against log2 N and N^α.
    struct Fits {
      FitResult ops_log, ops_pow, ns_log, ns_pow, bytes_pow;
      bool counted = false;
      double n_min = 0, n_max = 0, ops_max = 0, bytes_per_prim = 0;
    };
    std::map<std::string, std::map<std::string, Fits>> fitted;
    for (const auto& fam : fams)
      for (const auto& a : fam.accels) {
        const auto& v = runs[fam.name][a];
        if (v.size() < 3) continue;
        const auto n = column(v, [](const Run& r) { return r.n; });
        const auto ns = column(v, [](const Run& r) { return r.cost.ns; });
        const auto ops = column(v, [](const Run& r) { return r.cost.ops(); });
        const auto bytes = column(v, [](const Run& r) { return static_cast<double>(r.bytes); });
        Fits f;
        f.n_min = n.front();
        f.n_max = n.back();
        f.ns_log = fit_basis(n, ns, log2_of);
        f.ns_pow = fit_power_law(n, ns);
        fits.row(fam.name + "|" + a, "ns_per_ray", "log", f.ns_log, n);
        fits.row(fam.name + "|" + a, "ns_per_ray", "power", f.ns_pow, n);
        f.counted = ops.back() > 0;
        if (f.counted) {
          f.ops_log = fit_basis(n, ops, log2_of);
          f.ops_pow = fit_power_law(n, ops);
          f.ops_max = ops.back();
          fits.row(fam.name + "|" + a, "ops_per_ray", "log", f.ops_log, n);
          fits.row(fam.name + "|" + a, "ops_per_ray", "power", f.ops_pow, n);
        }
        if (bytes.back() > 0 && bytes.front() > 0) {
          f.bytes_pow = fit_power_law(n, bytes);
          f.bytes_per_prim = bytes.back() / n.back();
          fits.row(fam.name + "|" + a, "bytes", "power", f.bytes_pow, n);
        }
        fitted[fam.name][a] = f;
      }

    // ----- claim 1 -----
    std::string md = section_anchor("claim-1");
    md += "## |Image| x |Objects| against |Image| x log|Objects|\n\n";
    md += "**Claim** (lecture, *Ray Tracing 2*): brute force costs |Image| × |Objects|; acceleration costs about "
          "|Image| × log |Objects|. **Source**: the lecture; the expected-cost argument behind it is MacDonald and "
          "Booth, \"Heuristics for ray tracing using space subdivision\", *The Visual Computer* 6(3):153–166, 1990 "
          "(see [docs/theory.md](../theory.md#claim-1)).\n\n";
    md += fmt::format(
        "**Experiment**: every structure traces the same camera rays (`primary:1024`, single thread) on scenes of "
        "N = 2^10 … 2^{} primitives; brute force up to 2^{}, the BSP tree up to 2^{} and the octree up to 2^{} "
        "(their builds take minutes beyond). *ops/ray* are the operations the traversal counters see: node and leaf "
        "visits plus primitive tests. *ns/ray* is the median over {} alternated rounds at each N (each round traces "
        "every structure and Embree in turn, the fastest pass over {:.2g} s of the tracing thread's CPU time, at least "
        "one pass); a time over Embree's is taken per round, with its 95% bootstrap interval. Every fit is Ceres' "
        "(lib/cost/fit.h: relative residuals, Huber loss at 10%), ± one standard error; *log fits better* compares "
        "the Akaike criteria of a + b·log2 N and c·N^α (both two parameters). Command: `build/experiments/exp_image_log_objects --mode {}`.\n\n",
        opt.full() ? 24 : 20, opt.full() ? 20 : 16, opt.full() ? 16 : 14, opt.full() ? 20 : 18, kTimeRounds,
        min_s / kTimeRounds, opt.mode);
    const std::string command = "build/experiments/exp_image_log_objects --mode " + opt.mode;
    const double kLogAlpha = 0.25;
    const Threshold t_log{fmt::format(
        "operations per ray grow as log N, not as a power, where the fitted exponent α of ops/ray ∝ N^α has its 95% "
        "interval below {0} (confirmed), and as a power where it lies above {0} (refuted); inconclusive where it "
        "straddles {0}. A logarithm a + b·log2 N fitted as a power over N = 2^8 … 2^20 gives α ≈ 0.1–0.2 for the "
        "intercepts the benign scenes show; the weakest power the failure mechanisms predict is N^(1/3) (escaping rays "
        "cross ∝ ∛N cells); {0} lies between. The same rule decides every family, benign (claim 1) and built to fail "
        "(1b–1e, each by its structure with the largest α)",
        kLogAlpha), "below", kLogAlpha};
    const Threshold t_brute{"brute force's tests per ray grow as N: α's 95% interval within 1 ± 0.1", "within", 1.0, 0.1};
    const Threshold t1{"holds (confirmed) where brute force's tests grow as N (α within 1 ± 0.1) and every hierarchy "
                       "(kd-tree, octree, BSP, BVH) on soups, meshes and spheres grows as log N by the rule of 1b–1e "
                       "(α's interval below 0.25); holds only under stated conditions where these hold and a family "
                       "of 1b–1e is refuted; refuted where brute force or a benign hierarchy fails the rule; "
                       "inconclusive at this noise where any of these straddles its threshold. The uniform grids are "
                       "judged under claim 6 (they fail on uneven densities by design). Key number: the benign "
                       "hierarchy whose α interval reaches highest",
                       "conditional", kLogAlpha};
    md += "**Thresholds, stated before measuring.** Claim 1: " + t1.text + ". Claims 1b–1e: " + t_log.text +
          ". Intervals of fitted exponents are value ± t(0.975, points − 2)·s.e. (Student's t: few sizes per "
          "series).\n\nReproduce: `" + command + "` (claims 1, 1b–1e and 5 come from one run).\n\n";
    md += "### Where the claim holds\n\n";
    md += fmt::format(
        "Brute force against Embree, time per ray (the section's first table): at each N, the {} alternated rounds "
        "described above (brute force and Embree among every structure); the fits (Ceres, relative "
        "residuals, Huber loss at 10%) are to the medians over the rounds, and every interval is a 95% percentile "
        "bootstrap over the rounds (each N's rounds resampled, the medians refitted, {} resamples, fixed seed), the "
        "spread a rerun of the timings would show.\n\n"
        "| family | model | fit (ns per ray) [95%] | R² | power law: ns ∝ N^α [95%] | rounds per N |\n"
        "|---|---|---|---|---|---|\n",
        kTimeRounds, kBootstrapResamples);
    IntervalEstimate brute_soup_time_alpha;  // brute force's ns/ray ∝ N^α on the soup, over the rounds
    for (const auto& fam : fams) {
      if (fam.failure) continue;
      for (const std::string a : {"brute", "embree"}) {
        const auto& v = runs[fam.name][a];
        if (v.size() < 3) continue;
        const auto n = column(v, [](const Run& r) { return r.n; });
        std::vector<std::vector<double>> reps;
        for (const Run& r : v) reps.push_back(r.ns_rounds);
        const bool brute = a == "brute";
        const auto basis = [brute](double x) { return brute ? x : std::log2(x); };
        const auto fit_both = [&](const std::vector<double>& ns) {
          const FitResult f = fit_basis(n, ns, basis), p = fit_power_law(n, ns);
          return std::vector<double>{f.values[0], f.values[1], p.values[1]};
        };
        std::vector<double> medians;
        for (const auto& r : reps) medians.push_back(median(r));
        const FitResult f = fit_basis(n, medians, basis);
        if (brute) fits.row(fam.name + "|" + a, "ns_per_ray", "linear", f, n);
        const BootstrapFit b = bootstrap_fit(reps, fit_both);
        if (brute && fam.name == "soup") brute_soup_time_alpha = b.parameters[2];
        md += fmt::format("| {} | {}: a + b·{} | ({}) + ({})·{} | {:.4f} | α = {} | {} |\n", fam.name, a,
                          brute ? "N" : "log2 N", format_interval(b.parameters[0]), format_interval(b.parameters[1]),
                          brute ? "N" : "log2 N", f.r2, format_interval(b.parameters[2]), b.parameters[0].replicates);
      }
    }
    md += "\nEvery structure, operations and time per ray:\n\n";
    md += "| family | structure | N | ops/ray: a + b·log2 N | ops/ray ∝ N^α | ns/ray ∝ N^α | log fits better (ops) | "
          "ops/ray at largest N | ns/ray vs Embree at largest N [95%] |\n|---|---|---|---|---|---|---|---|---|\n";
    // Time per ray over Embree's at a run's N, round by round (both traced in that N's rounds).
    const auto over_embree = [&](const std::string& family, const Run& run) -> std::string {
      for (const Run& e : runs[family]["embree"])
        if (e.n == run.n && !e.ns_rounds.empty() && e.ns_rounds.size() == run.ns_rounds.size())
          return format_interval(bootstrap_median(per_round_ratios(run.ns_rounds, e.ns_rounds)));
      return "–";
    };
    std::vector<double> tree_alphas;  // ops exponents of the hierarchies on the benign families
    std::vector<std::string> benign_verdicts;  // decide_verdict of each hierarchy on each benign family
    KeyNumber k1;
    FitResult brute_soup_ops;
    for (const auto& fam : fams) {
      if (fam.failure) continue;
      for (const auto& a : fam.accels) {
        if (!fitted[fam.name].count(a)) continue;
        const Fits& f = fitted[fam.name][a];
        const Run& last = runs[fam.name][a].back();
        const std::string ops_log = f.counted ? fmt::format("({}) + ({})·log2 N", format_with_error(f.ops_log.values[0], f.ops_log.std_errors[0]),
                                                            format_with_error(f.ops_log.values[1], f.ops_log.std_errors[1]))
                                              : "–";
        md += fmt::format("| {} | `{}` | {:.0f} … {:.0f} | {} | {} | {} | {} | {} | {} |\n", fam.name, a, f.n_min, f.n_max,
                          ops_log, f.counted ? exponent_text(f.ops_pow) : "–", exponent_text(f.ns_pow),
                          f.counted ? (f.ops_log.aic < f.ops_pow.aic ? "yes" : "no") : "–",
                          f.counted ? fmt::format("{:.1f}", f.ops_max) : "–", over_embree(fam.name, last));
        if (a == "brute" && fam.name == "soup") brute_soup_ops = f.ops_pow;
        if (a != "brute" && a != "embree" && f.counted) tree_alphas.push_back(f.ops_pow.values[1]);
        if ((a == "kdtree" || a == "octree" || a == "bsp" || a == "bvh") && f.counted) {
          const KeyNumber k = fitted_key("α of ops/ray ∝ N^α, " + fam.name, f.ops_pow, 1,
                                         canonical_spec(a) + " on " + fam.scenes.front() + " … " + fam.scenes.back() +
                                             ", rays " + fam.rays);
          benign_verdicts.push_back(decide_verdict(k, t_log));
          if (!(k.hi <= k1.hi)) k1 = k;
        }
      }
    }
    std::sort(tree_alphas.begin(), tree_alphas.end());
    const double median_alpha = tree_alphas.empty() ? 0.0 : tree_alphas[tree_alphas.size() / 2];
    const double max_alpha = tree_alphas.empty() ? 0.0 : tree_alphas.back();
    md += "\n";

    md += "### Where the claim fails\n\n";
    md += "Four scene families built to break it (`raylab scenes` lists them; lib/scene/procedural.h explains each). "
          "Rays: `primary:1024`, except on the row, where 1024 rays run along its axis and pass within the gap of "
          "every triangle (near_miss_row_rays). The uniform grid stops at 2^10 needles and 2^12 fan triangles: "
          "every such primitive's box overlaps a fixed fraction of the grid's cells, so its references, memory and "
          "build time grow as N² (at 2^14 fan triangles: 35 s and 650 MB).\n\n";
    md += "| family | what | structure | ops/ray ∝ N^α | ns/ray ∝ N^α | ops/ray at N = 2^8 and at largest N | hit rate |\n"
          "|---|---|---|---|---|---|---|\n";
    std::vector<Verdict> verdicts;
    std::map<std::string, std::pair<std::string, FitResult>> worst;  // family -> the structure with the largest exponent
    for (const auto& fam : fams) {
      if (!fam.failure) continue;
      for (const auto& a : fam.accels) {
        if (!fitted[fam.name].count(a)) continue;
        const Fits& f = fitted[fam.name][a];
        const auto& v = runs[fam.name][a];
        md += fmt::format("| {} | {} | `{}` | {} | {} | {} | {:.1f}% |\n", fam.name, fam.what, a,
                          f.counted ? exponent_text(f.ops_pow) : "–", exponent_text(f.ns_pow),
                          f.counted ? fmt::format("{:.1f} → {:.1f}", v.front().cost.ops(), v.back().cost.ops()) : "–",
                          100 * v.back().cost.hit_rate);
        if (f.counted && (!worst.count(fam.name) || f.ops_pow.values[1] > worst[fam.name].second.values[1]))
          worst[fam.name] = {a, f.ops_pow};
      }
    }
    md += "\n";

    const std::map<std::string, std::string> failure_titles = {
        {"dust", "log N for rays that escape (dust)"},
        {"needles", "log N among overlapping needles"},
        {"fan", "log N at a vertex of valence N (fan)"},
        {"row", "log N along a near-miss row"}};
    const std::map<std::string, std::string> ids = {{"dust", "1b"}, {"needles", "1c"}, {"fan", "1d"}, {"row", "1e"}};
    std::vector<Verdict> failure_verdicts;
    int refuting = 0;
    bool failure_inconclusive = false;
    for (const auto& fam : fams) {
      if (!fam.failure || !worst.count(fam.name)) continue;
      const auto& [accel, pow] = worst[fam.name];
      const KeyNumber k = fitted_key("α of ops/ray ∝ N^α, " + fam.name, pow, 1,
                                     canonical_spec(accel) + " on " + fam.scenes.front() + " … " + fam.scenes.back() +
                                         ", rays " + (fam.rays.empty() ? "near_miss_row_rays:1024" : fam.rays));
      // The claim is "log N": the rule confirms it below the threshold and refutes it above.
      const std::string v = decide_verdict(k, t_log);
      refuting += v == kRefuted;
      failure_inconclusive |= v == kInconclusive;
      failure_verdicts.push_back({ids.at(fam.name), failure_titles.at(fam.name), v,
                                  fmt::format("ops/ray ∝ N^α, {} (`{}`)", exponent_text(pow), accel), "claim-1", k,
                                  t_log, command});
    }
    // The claim proper (t1): brute force linear, every benign hierarchy logarithmic; conditional
    // where a failure family is refuted.
    const KeyNumber k_brute = fitted_key("α of brute force's tests/ray ∝ N^α, soup", brute_soup_ops, 1, "brute");
    const std::string brute_verdict = decide_verdict(k_brute, t_brute);
    const bool brute_linear = brute_verdict == kConfirmed;
    const bool trees_sublinear = !tree_alphas.empty() && max_alpha < 0.5;
    std::vector<std::string> cases = benign_verdicts;
    cases.push_back(brute_verdict);
    std::string v1 = decide_all(cases);
    if (v1 == kConfirmed && refuting) v1 = kConditional;
    else if (v1 == kConfirmed && failure_inconclusive) v1 = kInconclusive;
    const Verdict main_verdict{
        "1", "|Image| × log|Objects|", v1,
        fmt::format("ops/ray ∝ N^α with median α = {:.2f} (largest {:.2f}) over the hierarchies and grids on soups, "
                    "meshes and spheres; brute force: tests {}, time {}",
                    median_alpha, max_alpha, exponent_text(brute_soup_ops),
                    "α = " + format_interval(brute_soup_time_alpha) + " over " +
                        std::to_string(brute_soup_time_alpha.replicates) + " rounds"),
        "claim-1", k1, t1, command};
    verdicts.push_back(main_verdict);
    verdicts.insert(verdicts.end(), failure_verdicts.begin(), failure_verdicts.end());
    // Time against tests, decided by the intervals: the time exponent's bootstrap interval over the
    // rounds against the tests' fitted interval (k_brute; the tests are counted, not timed).
    const double tests_alpha = brute_soup_ops.values[1];
    const std::string time_against_tests =
        !brute_soup_time_alpha.defined() ? "its rounds gave no interval"
        : brute_soup_time_alpha.lo > k_brute.hi
            ? "faster than its tests, by the intervals: the triangles outgrow the caches"
        : brute_soup_time_alpha.hi < k_brute.lo ? "slower than its tests, by the intervals"
                                                : "as fast as its tests: the intervals overlap";
    md += verdict_paragraph(
        main_verdict,
        fmt::format("Brute force's tests per ray grow {} (α = {:.2f}), its time with α = {:.2f} ({}). The hierarchies' "
                    "operations grow {} on soups of evenly spread triangles, on real meshes and on the sphereflake "
                    "(largest α = {:.2f}). {} of the four families below refute{} the claim.",
                    brute_linear ? "linearly in N, as claimed" : "not linearly in N", tests_alpha,
                    brute_soup_time_alpha.value, time_against_tests,
                    trees_sublinear ? "far slower than N" : "not much slower than N", max_alpha,
                    refuting == 0 ? std::string("None") : std::to_string(refuting), refuting == 1 ? "s" : ""));
    md += "| claim | on | verdict | the largest exponent |\n|---|---|---|---|\n";
    for (std::size_t i = 1; i < verdicts.size(); ++i)
      md += fmt::format("| {} | {} | **{}** | {} |\n", verdicts[i].claim, verdicts[i].title, verdicts[i].verdict, verdicts[i].key);
    md += "\nA family *refutes* the claim when the 95% interval of its largest fitted exponent lies above 0.25 (the "
          "threshold stated at the top of the section). Escaping rays cross every cell along their chord, ∝ N^(1/3) of a grid of ∛N cells per axis; the "
          "needles' boxes all overlap, so a box hierarchy meets most of them; every box around the fan's apex holds "
          "a constant fraction of its triangles; the row puts every triangle within reach of the ray. Only cuts of "
          "the primitives themselves (the kd-tree's split clipping) can separate such geometry from a ray, and only "
          "where the cost model finds it worthwhile.\n\n";
    const std::map<std::string, std::string> mechanisms = {
        {"1b", "Escaping rays cross every cell along their chord: ∝ N^(1/3) cells of a grid of ∛N cells per axis, and "
               "as many leaves of a balanced tree."},
        {"1c", "The needles' boxes all overlap, so a box hierarchy meets most of them."},
        {"1d", "Every box around the fan's apex holds a constant fraction of its triangles."},
        {"1e", "The row puts every triangle within reach of the ray."}};
    for (std::size_t i = 1; i < verdicts.size(); ++i)
      md += verdict_paragraph(verdicts[i], mechanisms.count(verdicts[i].claim) ? mechanisms.at(verdicts[i].claim) : "");
    md += "![operations and time per ray against N](image_log_objects.png)\n\n*Figure: operations (top) and time "
          "(bottom) per ray against N on the benign families, log axes: the hierarchies' curves flatten like log N "
          "(claim 1), brute force's rise as N.*\n\n![the failing families](image_log_objects_failures.png)\n\n"
          "*Figure: operations per ray against N on the four families built to fail (claims 1b–1e), with the fitted "
          "powers c·N^α: straight lines on log axes are powers, not logarithms.*\n\n";
    md += fmt::format("Data: image_log_objects.csv (ns_per_ray: the median of the rounds, with its 95% bootstrap "
                      "interval ns_per_ray_lo..hi and the round count; embree_ns_per_ray and its interval "
                      "embree_ns_per_ray_lo..hi repeat the embree row's), fits: image_log_objects_fits.csv. "
                      "Measured by "
                      "`build/experiments/exp_image_log_objects --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/image_log_objects.md") << md;
    write_verdicts(opt.out, "image_log_objects", verdicts);

    // ----- claim 5 -----
    std::string b = section_anchor("claim-5");
    b += "## The computational geometry of ray shooting: query time against memory\n\n";
    b += "**Claim** (lecture, *Theory*): ray shooting among n triangles can be answered in O(log n) time with "
         "O(n^(5+ε)) space (Pellegrini), and among spheres in O(log² n) time with O(n^(5+ε)) space (attributed to "
         "Guibas and Pellegrini). **Sources**: M. Pellegrini, \"Ray shooting on triangles in 3-space\", "
         "*Algorithmica* 9(5):471–494, 1993. The sphere bound and its attribution could not be traced to any "
         "publication; what the literature states for spheres is S. Mohaban and M. Sharir, \"Ray shooting amidst "
         "spheres in three dimensions and related problems\", *SIAM J. Computing* 26(3):654–674, 1997: O(n^(3+ε)) "
         "space and preprocessing, O(n^ε) query. For fat convex polyhedra, B. Aronov, M. de Berg and C. Gray, \"Ray "
         "shooting and intersection searching amidst fat convex polyhedra in 3-space\", *Computational Geometry* "
         "41(1–2):68–76, 2008: O(n^(2+ε)) storage, O(log² n) query; for axis-parallel (c-oriented) polyhedra, "
         "M. de Berg, *Ray Shooting, Depth Orders and Hidden Surface Removal*, LNCS 703, Springer, 1993. See "
         "[docs/theory.md](../theory.md#claim-5).\n\n";
    b += "**Experiment**: the runs of the previous section, read as memory (the structure's bytes, Embree's by its "
         "memory monitor) against query cost (operations and ns per ray) as n grows; on triangles (soups, the bunny), "
         "spheres (`sphereflake`, as spheres) and the worst cases (needles, fan, near-miss row). Both are fitted to "
         "c·n^β. Command: `build/experiments/exp_image_log_objects --mode " + opt.mode + "`.\n\n";
    const Threshold t5{"the lab's structures use near-linear memory; they would make the n^(5+ε) space unnecessary in "
                       "practice (refuted) only if their query cost stayed logarithmic on the worst-case families too, "
                       "by claim 1's rule (the largest α's 95% interval below 0.25); where it lies above 0.25, the "
                       "guarantee is what the space buys (holds only under stated conditions); inconclusive at this "
                       "noise where it straddles 0.25",
                       "conditional", kLogAlpha};
    b += "**Threshold, stated before measuring.** " + t5.text + ".\n\nReproduce: `" + command + "`.\n\n";
    b += "| family | structure | n | memory ∝ n^β | bytes per primitive at largest n | query ops/ray ∝ n^α | query ns/ray ∝ n^α |\n"
         "|---|---|---|---|---|---|---|\n";
    std::vector<double> betas;
    double worst_alpha = 0, worst_beta = 0;
    std::string worst_case, worst_beta_case;
    KeyNumber k5;
    for (const auto& fam : fams) {
      if (fam.name == "dust") continue;  // dust is the escape case of claim 1; not a query-cost worst case
      for (const auto& a : fam.accels) {
        if (a == "brute" || !fitted[fam.name].count(a)) continue;
        const Fits& f = fitted[fam.name][a];
        if (f.bytes_pow.points == 0) continue;
        b += fmt::format("| {} | `{}` | {:.0f} … {:.0f} | β = {} | {:.0f} | {} | {} |\n", fam.name, a, f.n_min, f.n_max,
                         format_with_error(f.bytes_pow.values[1], f.bytes_pow.std_errors[1]), f.bytes_per_prim,
                         f.counted ? exponent_text(f.ops_pow) : "–", exponent_text(f.ns_pow));
        if (!fam.failure) betas.push_back(f.bytes_pow.values[1]);
        if (fam.failure && f.bytes_pow.values[1] > worst_beta)
          worst_beta = f.bytes_pow.values[1],
          worst_beta_case = fmt::format("{} on {}: β = {}", a, fam.name,
                                        format_with_error(f.bytes_pow.values[1], f.bytes_pow.std_errors[1]));
        if (fam.failure && f.counted && f.ops_pow.values[1] > worst_alpha) {
          worst_alpha = f.ops_pow.values[1];
          worst_case = fmt::format("{} on {}: {}", a, fam.name, exponent_text(f.ops_pow));
          k5 = fitted_key("largest α of query ops/ray ∝ n^α on a worst case (" + fam.name + ")", f.ops_pow, 1,
                          canonical_spec(a) + " on " + fam.scenes.front() + " … " + fam.scenes.back());
        }
      }
    }
    std::sort(betas.begin(), betas.end());
    b += "\n| bound | space | query | for |\n|---|---|---|---|\n"
         "| Pellegrini 1993 (the lecture's figure) | O(n^(5+ε)) | O(log n) | triangles |\n"
         "| the lecture's sphere bound (no source found) | O(n^(5+ε)) | O(log² n) | spheres |\n"
         "| Mohaban and Sharir 1997 | O(n^(3+ε)) | O(n^ε) | spheres |\n"
         "| Aronov, de Berg and Gray 2008 | O(n^(2+ε)) | O(log² n) | fat convex polyhedra |\n"
         "| brute force | O(n) | O(n) | anything |\n\n";
    // Practice refutes the need for n^(5+ε) space only if its near-linear structures kept the query
    // cost logarithmic on the worst cases too; where those grow as a power, the guarantee is what
    // the space buys.
    const std::string worst_log = decide_verdict(k5, t_log);
    const Verdict v5{"5", "O(log n) query needs n^(5+ε) space (Pellegrini)",
                     worst_log == kRefuted ? kConditional : worst_log == kConfirmed ? kRefuted : kInconclusive,
                     fmt::format("the lab's structures use memory ∝ n^β, β = {:.2f} … {:.2f} on benign scenes, and "
                                 "query cost logarithmic there; on the worst cases the query cost grows as a power "
                                 "(largest: {}) and so may the memory ({})",
                                 betas.empty() ? 0.0 : betas.front(), betas.empty() ? 0.0 : betas.back(), worst_case,
                                 worst_beta_case),
                     "claim-5", k5, t5, command};
    b += verdict_paragraph(
        v5, fmt::format("The bounds are worst-case guarantees; the lab's structures give none. They buy memory ∝ n^β "
                        "with β = {:.2f} … {:.2f} on benign scenes (n^5 bytes would be 10^15 at n = 1000) and "
                        "near-logarithmic queries there, and they give up every guarantee: on the worst-case families "
                        "the query cost grows as a power of n, up to α = {:.2f}, where Pellegrini's structure would "
                        "still answer in O(log n). Whether a guaranteed structure with near-linear space exists is "
                        "open; the known trade-offs (Agarwal and Matoušek 1993) interpolate between the two ends.",
                        betas.empty() ? 0.0 : betas.front(), betas.empty() ? 0.0 : betas.back(), worst_alpha));
    b += "![query cost against memory](ray_shooting_bounds.png)\n\n*Figure: query operations per ray against the "
         "structure's memory as n grows, one line per structure and family, beside the bounds drawn with unit "
         "constants: the lab's structures stay near linear memory; on the worst cases their query cost climbs.*\n\n";
    b += fmt::format("Data: image_log_objects.csv (the bytes column), fits: image_log_objects_fits.csv (quantity "
                     "`bytes`). Measured by `build/experiments/exp_image_log_objects --mode {}`. {}.\n",
                     opt.mode, provenance());
    std::ofstream(opt.out + "/ray_shooting_bounds.md") << b;
    write_verdicts(opt.out, "ray_shooting_bounds", {v5});
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_image_log_objects: error: " << e.what() << "\n";
    return 2;
  }
}
