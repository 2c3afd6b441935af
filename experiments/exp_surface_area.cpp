// The lecture's cost model rests on "hit probabilities proportional to surface area": under
// isotropic random lines (the Cauchy-Crofton measure, `lines:` rays) the fraction of lines that
// meet a convex cell inside the root is SA(cell)/SA(root), so the expected interior-node visits of
// a traversal without early exit are Σ SA(n)/SA(root), its leaf visits Σ SA(l)/SA(root) over
// non-empty leaves and its primitive tests Σ N(l)·SA(l)/SA(root) (lib/cost/tree_features.h).
//  1. Geometric: for every line, the cells it meets (walk_structure_cells, no early exit), against
//     the predictions, for the kd-tree, the octree, the BSP tree and the BVH (binary and 8-wide).
//  2. Traversal: the counters of real traversals (which stop at the first hit) for lines, camera,
//     diffuse and shadow rays, as ratios to the same predictions.
// Writes surface_area.csv, surface_area.md and surface_area.verdicts.csv.
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numbers>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "cost/structure_cells.h"
#include "cost/tree_features.h"
#include "experiment_common.h"
#include "rays/isotropic_lines.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

/// Mean and standard error of the mean.
struct Sample {
  double sum = 0, sum2 = 0;
  std::size_t n = 0;
  void add(double x) { sum += x, sum2 += x * x, ++n; }
  double mean() const { return n ? sum / static_cast<double>(n) : 0.0; }
  double se() const {
    if (n < 2) return 0.0;
    const double m = mean();
    return std::sqrt(std::max(0.0, (sum2 / static_cast<double>(n) - m * m) / static_cast<double>(n - 1)));
  }
};

/// Per line meeting the root cell: interior cells, non-empty leaves and the primitives of those
/// leaves that the whole line meets.
struct LineCounts {
  Sample inner, leaves, tests;
  std::size_t lines = 0, meeting_root = 0;
};

LineCounts count_cells_met(const Aggregate& accel, const std::vector<Ray>& lines) {
  LineCounts c;
  c.lines = lines.size();
  for (const Ray& r : lines) {
    const Vec3d o(r.org), d(r.dir);
    double inner = 0, leaves = 0, tests = 0;
    bool root = false, first = true;
    walk_structure_cells(accel, [&](const StructureCell& cell) {
      const bool met = cell.meets_line(o, d);
      if (first) root = met, first = false;
      if (!met) return false;
      if (!cell.leaf) ++inner;
      else if (cell.primitives > 0) ++leaves, tests += static_cast<double>(cell.primitives);
      return true;
    });
    if (!root) continue;
    ++c.meeting_root;
    c.inner.add(inner);
    c.leaves.add(leaves);
    c.tests.add(tests);
  }
  return c;
}

/// Whether a ray (as traced, from tmin to tmax) meets the box.
bool ray_meets_box(const Ray& r, const Bounds3f& box) {
  float t0, t1;
  return intersect_box(box, r, safe_inverse(r.dir), r.tmin, r.tmax, t0, t1);
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "hit probabilities proportional to surface area");
  try {
    if (!opt.claim.empty() && !opt.runs_claim({"2", "2b"}))
      throw InputError("--claim " + opt.claim + ": exp_surface_area decides claims 2 and 2b only (both from one run)");
    const std::vector<std::string> scenes = {"decimated:of=cgal:bunny00,faces=8000",
                                             "stadium:object=(sphere:n=800),ratio=50", "soup:n=8000"};
    const std::vector<std::string> accels = {"kdtree", "octree", "bsp", "bvh:width=2", "bvh"};
    const std::size_t line_count = opt.full() ? 200000 : 20000;
    const std::string n = opt.full() ? "65536" : "16384";
    const std::vector<std::string> ray_kinds = {"lines:" + n, "primary:" + n, "diffuse:" + n, "shadow:" + n};
    CsvWriter csv(opt.out + "/surface_area.csv",
                  {"part", "scene", "accel", "rays", "quantity", "predicted", "measured", "std_error", "z", "ratio"});
    std::string md = section_anchor("claim-2");
    md += "## Hit probabilities proportional to surface area\n\n";
    md += "**Claim** (lecture, *Cost*): \"the probability of hitting a node is proportional to its surface area\", "
          "so a split's cost weighs each child by SA(child)/SA(parent). **Source**: the Cauchy–Crofton formula of "
          "integral geometry (L. A. Santaló, *Integral Geometry and Geometric Probability*, Addison-Wesley, 1976, "
          "ch. 12–14): for convex K ⊂ L, a line drawn from the motion-invariant measure that meets L meets K with "
          "probability area(K)/area(L); applied to ray tracing by J. D. MacDonald and K. S. Booth, \"Heuristics for "
          "ray tracing using space subdivision\", *The Visual Computer* 6(3):153–166, 1990 (see "
          "[docs/theory.md](../theory.md#claim-2)).\n\n";
    md += fmt::format(
        "**Experiment 1** (the claim itself): {} isotropic random lines (`lines:` rays) through each scene; for each "
        "line, the cells of the structure it meets, walked without early exit (lib/cost/structure_cells.h: boxes, and "
        "the BSP's convex cells). Predicted, per line that meets the root: interior visits Σ SA(n)/SA(root), leaf "
        "visits Σ SA(l)/SA(root) over non-empty leaves, primitive tests Σ N(l)·SA(l)/SA(root) (tree_features.h). "
        "*z* is (measured − predicted)/standard error of the measured mean. **Experiment 2** (real rays): the "
        "traversal counters of `raylab trace` for {} rays of each kind, per ray that meets the root box, over the "
        "same predictions. Command: `build/experiments/exp_surface_area --mode {}`.\n\n",
        line_count, n, opt.mode);
    std::string spec = fmt::format("exp_surface_area:mode={},lines={},rays={}", opt.mode, line_count, n);
    for (const auto& a : accels) spec += " " + canonical_spec(a);
    const std::string command = "build/experiments/exp_surface_area --mode " + opt.mode;
    const Threshold t2{"for lines from the invariant measure the prediction is exact, so each quantity's c in measured = "
                       "c·predicted (interior visits, leaf visits, primitive tests; box cells of the kd-tree, octree "
                       "and BVHs) must lie within 1 ± 0.02: confirmed where every c's 95% interval lies inside (0.98, "
                       "1.02), refuted where any lies wholly outside; the key number is the c whose interval reaches "
                       "farthest from 1",
                       "within", 1.0, 0.02};
    const Threshold t2b{"real rays (camera, diffuse, shadow, and lines that stop at the first hit) follow the "
                        "expectation itself where c of interior visits lies within 1 ± 0.02 for every ray kind "
                        "(confirmed); they follow it only up to a constant per ray kind (holds only under stated "
                        "conditions) where some c's interval lies outside and every kind's fit keeps R² ≥ 0.9; refuted "
                        "where a kind outside has R² < 0.9 (not even proportional)",
                        "conditional", 1.0, 0.02};
    md += "**Thresholds, stated before measuring.** Claim 2: " + t2.text + ". Claim 2b: " + t2b.text +
          ". Intervals of fitted constants are value ± t(0.975, points − 1)·s.e.\n\nReproduce: `" + command +
          "` (both claims come from one run).\n\n";

    // quantity -> (predicted, measured) rows: box cells (kd-tree, octree, BVH); the BSP's convex cells
    std::map<std::string, std::vector<std::vector<double>>> fit_x, bsp_x;
    std::map<std::string, std::vector<double>> fit_y, bsp_y;
    double max_z = 0;
    std::uint64_t line_seed = 0;
    std::string max_z_case;
    std::string table1 = "| scene | structure | quantity | predicted | measured (± s.e.) | z |\n|---|---|---|---|---|---|\n";
    std::string table2 = "| scene | structure | rays | interior visits / predicted | leaf visits / predicted | tests / predicted |\n"
                         "|---|---|---|---|---|---|\n";
    // ray kind -> (predicted, measured) pairs of interior visits, for the per-kind fit
    std::map<std::string, std::pair<std::vector<std::vector<double>>, std::vector<double>>> by_kind;
    for (const auto& s : scenes) {
      const auto scene = make_scene(s);
      const Bounds3d b(Vec3d(scene->bounds().lo), Vec3d(scene->bounds().hi));
      std::map<std::string, std::vector<Ray>> rays;
      for (const auto& k : ray_kinds) rays[k] = make_ray_set(k, scene);
      for (const auto& a : accels) {
        progress("surface_area: " + s + " " + a);
        const auto accel = make_accelerator(a, scene);
        const TreeFeatures f = tree_features(*accel, *scene);
        // A line sample of its own per structure, so that the rows of the fit below are independent.
        const auto lines = isotropic_lines(b.center(), 0.505 * length(b.diagonal()), line_count, ++line_seed);
        const LineCounts c = count_cells_met(*accel, lines);
        const std::vector<std::tuple<std::string, double, const Sample*>> quantities = {
            {"interior visits", f.expected_inner, &c.inner},
            {"leaf visits", f.expected_leaves, &c.leaves},
            {"primitive tests", f.expected_tests, &c.tests}};
        for (const auto& [q, predicted, sample] : quantities) {
          const double z = sample->se() > 0 ? (sample->mean() - predicted) / sample->se() : 0.0;
          csv.row("lines_geometric", s, a, fmt::format("lines:{}", line_count), q, predicted, sample->mean(), sample->se(),
                  z, sample->mean() / predicted);
          table1 += fmt::format("| {} | `{}` | {} | {:.3f} | {} | {:+.2f} |\n", s, a, q, predicted,
                                format_with_error(sample->mean(), sample->se()), z);
          const bool bsp = a == "bsp";
          (bsp ? bsp_x : fit_x)[q].push_back({predicted});
          (bsp ? bsp_y : fit_y)[q].push_back(sample->mean());
          if (!bsp && std::abs(z) > std::abs(max_z)) max_z = z, max_z_case = fmt::format("`{}` on {}, {}", a, s, q);
        }
        // Experiment 2: real traversals.
        const Bounds3f root = scene->bounds();
        for (const auto& k : ray_kinds) {
          const bool any = is_any_hit_ray_spec(k);
          std::vector<Ray> meeting;
          for (const Ray& r : rays[k])
            if (ray_meets_box(r, root)) meeting.push_back(r);
          if (meeting.empty()) continue;
          const TraceResult counted = trace_rays(*accel, meeting, TraceOptions{1, true, any});
          const double m = static_cast<double>(meeting.size());
          const double inner = static_cast<double>(counted.counters.nodes) / m;
          const double leaves = static_cast<double>(counted.counters.leaves) / m;
          const double tests = static_cast<double>(counted.counters.prim_tests) / m;
          for (const auto& [q, predicted, measured] :
               {std::tuple{"interior visits", f.expected_inner, inner}, std::tuple{"leaf visits", f.expected_leaves, leaves},
                std::tuple{"primitive tests", f.expected_tests, tests}})
            csv.row("traversal", s, a, k, q, predicted, measured, 0.0, 0.0, measured / predicted);
          table2 += fmt::format("| {} | `{}` | {} | {:.2f} | {:.2f} | {:.2f} |\n", s, a, k, inner / f.expected_inner,
                                leaves / f.expected_leaves, tests / f.expected_tests);
          const std::string kind = k.substr(0, k.find(':'));
          by_kind[kind].first.push_back({f.expected_inner});
          by_kind[kind].second.push_back(inner);
        }
      }
    }
    // Agreement: measured = c · predicted, one fit per quantity. The three quantities of one
    // structure come from the same lines, so only rows of one quantity are independent samples
    // (each structure has a line sample of its own).
    FitOptions plain;
    plain.loss_scale = 0;  // every point counts; the claim must hold for all of them
    const std::vector<std::string> quantity_names = {"interior visits", "leaf visits", "primitive tests"};
    std::map<std::string, FitResult> agreement, bsp_agreement;
    md += "### 1. Lines against the surface-area prediction\n\n" + table1;
    md += "\nFits of measured = c · predicted (Ceres, relative residuals, no robust loss), one per quantity over the "
          "scenes and structures (rows of one quantity are independent: each structure has its own lines); the BSP "
          "tree apart, its cells being convex polyhedra computed in floating point:\n\n"
          "| quantity | box cells (kd-tree, octree, BVHs): c | (c − 1)/s.e. | BSP cells: c |\n|---|---|---|---|\n";
    double worst_c_dev = 0;
    std::string box_cs, bsp_cs;
    for (const auto& q : quantity_names) {
      agreement[q] = fit_linear_terms(fit_x[q], fit_y[q], plain);
      bsp_agreement[q] = fit_linear_terms(bsp_x[q], bsp_y[q], plain);
      const FitResult& f = agreement[q];
      const double dev = std::abs(f.values[0] - 1.0) / std::max(f.std_errors[0], 1e-12);
      worst_c_dev = std::max(worst_c_dev, dev);
      md += fmt::format("| {} | {} | {:.1f} | {} |\n", q, format_with_error(f.values[0], f.std_errors[0]), dev,
                        format_with_error(bsp_agreement[q].values[0], bsp_agreement[q].std_errors[0]));
      box_cs += fmt::format("{}{} {}", box_cs.empty() ? "" : ", ", q, format_with_error(f.values[0], f.std_errors[0]));
      bsp_cs += fmt::format("{}{}", bsp_cs.empty() ? "" : ", ",
                            format_with_error(bsp_agreement[q].values[0], bsp_agreement[q].std_errors[0]));
    }
    md += fmt::format("\nThe largest |z| of one row of the box structures is {:.2f} ({}).\n\n", std::abs(max_z), max_z_case);
    md += "### 2. Real rays: how far they depart from it\n\n";
    md += "Traversals stop at the first hit, and camera, diffuse and shadow rays start at the eye or on a surface "
          "inside the scene, so they visit fewer cells than a whole line; ratios below 1 measure by how much.\n\n";
    md += table2;
    md += "\nLeaf visits above 1 mean a traversal entered more leaves than a whole line meets: the octree counts "
          "every leaf it enters, empty ones included, while the prediction counts non-empty leaves only.\n";
    md += "\nFit of measured interior visits = c · predicted, per ray kind (over scenes and structures):\n\n"
          "| rays | c | R² |\n|---|---|---|\n";
    std::map<std::string, FitResult> kind_fits;
    for (const std::string kind : {"lines", "primary", "diffuse", "shadow"}) {
      if (!by_kind.count(kind)) continue;
      const FitResult f = fit_linear_terms(by_kind[kind].first, by_kind[kind].second);
      kind_fits[kind] = f;
      md += fmt::format("| {} | {} | {:.3f} |\n", kind, format_with_error(f.values[0], f.std_errors[0]), f.r2);
    }
    // Claim 2: every quantity's c within 1 ± δ; the key is the c whose interval reaches farthest from 1.
    std::vector<std::string> quantity_verdicts;
    KeyNumber k2;
    double k2_reach = -1;
    for (const auto& q : quantity_names) {
      const KeyNumber k = fitted_key("c of " + q + " (box cells, lines)", agreement[q], 0, spec);
      quantity_verdicts.push_back(decide_verdict(k, t2));
      const double reach = std::max(std::abs(k.lo - 1.0), std::abs(k.hi - 1.0));
      if (!(reach <= k2_reach)) k2 = k, k2_reach = reach;
    }
    const bool agrees = decide_all(quantity_verdicts) == kConfirmed;
    std::vector<Verdict> verdicts;
    verdicts.push_back({"2", "P(line meets node) = SA(node)/SA(root)", decide_all(quantity_verdicts),
                        fmt::format("cells met by lines = c·Σ SA/SA(root) over kd-trees, octrees and BVHs: c = {} "
                                    "(largest |z| of a row {:.1f}); BSP cells c = {}",
                                    box_cs, std::abs(max_z), bsp_cs),
                        "claim-2", k2, t2, command});
    std::string departures;
    for (const auto& [kind, f] : kind_fits)
      departures += fmt::format("{}{} c = {}", departures.empty() ? "" : "; ", kind, format_with_error(f.values[0], f.std_errors[0]));
    // Claim 2b: per ray kind, c of interior visits within 1 ± δ; outside it, proportional if R² ≥ 0.9.
    std::vector<std::string> kind_verdicts;
    KeyNumber k2b;
    double k2b_dev = -1;
    bool proportional = true;
    for (const auto& [kind, f] : kind_fits) {
      const KeyNumber k = fitted_key("c of interior visits, " + kind + " rays", f, 0, spec);
      const std::string v = decide_verdict(k, Threshold{"", "within", t2b.value, t2b.tolerance});
      kind_verdicts.push_back(v);
      if (v == kRefuted) proportional &= f.r2 >= 0.9;
      if (std::abs(k.value - 1.0) > k2b_dev) k2b = k, k2b_dev = std::abs(k.value - 1.0);
    }
    std::string v2b = decide_all(kind_verdicts);
    if (v2b == kRefuted && proportional) v2b = kConditional;
    verdicts.push_back({"2b", "SA expectations for real rays", v2b, "interior visits = c·Σ SA(n)/SA(root): " + departures,
                        "claim-2", k2b, t2b, command});
    double bsp_worst = 0;
    for (const auto& [q, f] : bsp_agreement)
      bsp_worst = std::max(bsp_worst, std::abs(f.values[0] - 1.0) / std::max(f.std_errors[0], 1e-12));
    md += "\n" + verdict_paragraph(
                      verdicts[0],
                      fmt::format("For lines from the invariant measure the surface-area expectations of box cells {} "
                                  "(the largest |c − 1| is {:.1f} standard errors; the largest |z| of one row {:.1f}). "
                                  "The BSP's convex cells depart from them by up to {:.1f} standard errors; the BSP's "
                                  "prediction sums the areas of its cells as computed (faces clipped in double "
                                  "precision, lib/accel/bsp/bsp_cell.h), so a departure there measures those cells, "
                                  "not the theorem.",
                                  agrees ? "hold within the sampling error of the line count" : "depart from the line counts",
                                  worst_c_dev, std::abs(max_z), bsp_worst));
    double c_lo = 1e300, c_hi = 0;
    for (const auto& [kind, f] : kind_fits) c_lo = std::min(c_lo, f.values[0]), c_hi = std::max(c_hi, f.values[0]);
    md += verdict_paragraph(
        verdicts[1],
        fmt::format("Real traversals, which stop at the first hit, visit c = {:.2f} … {:.2f} of the predicted interior "
                    "nodes depending on the ray kind, not the prediction: the SAH ranks trees correctly only as far as "
                    "that fraction is the same for the trees being compared (lib/cost fits one constant per ray class "
                    "for this reason).",
                    c_lo, c_hi));
    md += "![measured against predicted](surface_area.png)\n\n*Figure: left, the cells each line meets against the "
          "surface-area prediction for every structure and scene (on the diagonal where claim 2 holds; error bars 2 "
          "s.e.); right, real traversals' interior visits over the prediction per ray kind (claim 2b: below 1 by the "
          "fraction c).*\n\n";
    md += fmt::format("Data: surface_area.csv. Measured by `build/experiments/exp_surface_area --mode {}` (run by "
                      "`./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/surface_area.md") << md;
    write_verdicts(opt.out, "surface_area", verdicts);
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_surface_area: error: " << e.what() << "\n";
    return 2;
  }
}
