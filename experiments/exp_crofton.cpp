// Crofton's theorem, as the lecture uses it: the average projected area of a convex body is S/4
// (convex shapes only), and a line that meets a convex body C meets a convex body O inside it
// with probability S_O/S_C.
//  1. Convex bodies: CGAL convex hulls of the demo meshes and random convex polytopes (round,
//     cubic, needle-like and flat); the projected area in each of many uniform random directions
//     is the area of the planar hull of the projected vertices (geometry/convex_hull.h).
//  2. Non-convex meshes: the true average silhouette area, measured with isotropic random lines
//     (Ā = π r² · P(a line through the ball of radius r meets the mesh)), against S/4.
//  3. Convex within convex: the fraction of isotropic lines meeting the outer body that also
//     meet the inner one, against S_O/S_C.
// Writes crofton.csv, crofton.md and crofton.verdicts.csv.
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <random>

#include "accel/common/accel_factory.h"
#include "experiment_common.h"
#include "geometry/convex_hull.h"
#include "rays/isotropic_lines.h"
#include "scene/cgal_meshes.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

struct Body {
  std::string name, kind;  ///< kind: hull of a demo mesh | random polytope
  TriangleMesh hull;
};

std::vector<Vec3f> vertices_of(const TriangleMesh& m) { return m.vertices; }

/// The mean projected area over `directions` uniform random directions, and its standard error.
std::pair<double, double> mean_projected_area(const TriangleMesh& hull, int directions, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  const auto points = vertices_of(hull);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < directions; ++i) {
    const double a = projected_area(points, Vec3d(g(rng), g(rng), g(rng)));
    sum += a, sum2 += a * a;
  }
  const double n = directions, mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, (sum2 / n - mean * mean) / (n - 1)))};
}

/// Points of a random convex polytope: `count` points uniform on the unit sphere (round), in the
/// unit cube (cube), or Gaussian with axes scaled by `scale`.
std::vector<Vec3f> random_points(const std::string& shape, int count, const Vec3d& scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3f> p;
  for (int i = 0; i < count; ++i) {
    Vec3d x = shape == "cube" ? Vec3d(u(rng), u(rng), u(rng)) : Vec3d(g(rng), g(rng), g(rng));
    if (shape == "round") x = normalize(x);
    p.push_back(Vec3f(Vec3d(x.x * scale.x, x.y * scale.y, x.z * scale.z)));
  }
  return p;
}

std::shared_ptr<Scene> mesh_scene(const std::string& name, const TriangleMesh& mesh) {
  auto s = std::make_shared<Scene>();
  s->spec = name;
  s->mesh = mesh;
  return s;
}

/// The fraction of `lines` that hit `scene` (closest-hit queries with the default BVH, certified), and
/// its binomial standard error.
std::pair<double, double> hit_fraction(const std::shared_ptr<const Scene>& scene, const std::vector<Ray>& lines) {
  const auto accel = make_accelerator("bvh", scene);
  const double p = static_cast<double>(trace_rays(*accel, lines, TraceOptions{0, false, false}).hit_count) /
                   static_cast<double>(lines.size());
  return {p, std::sqrt(p * (1 - p) / static_cast<double>(lines.size()))};
}

/// Isotropic lines through the ball around `bounds` (its centre, 1.01 times half its diagonal).
std::vector<Ray> lines_around(const Bounds3f& bounds, std::size_t n, std::uint64_t seed, double& radius) {
  const Bounds3d b(Vec3d(bounds.lo), Vec3d(bounds.hi));
  radius = 0.505 * length(b.diagonal());
  return isotropic_lines(b.center(), radius, n, seed);
}

TriangleMesh box_hull(const Bounds3f& b) {
  std::vector<Vec3f> corners;
  for (int i = 0; i < 8; ++i) corners.emplace_back(i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z);
  return convex_hull(corners);
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "Crofton's theorem: mean projected area S/4 and hit probability S_o/S_c");
  try {
    if (!opt.claim.empty() && !opt.runs_claim({"3", "3b", "3c"}))
      throw InputError("--claim " + opt.claim + ": exp_crofton decides claims 3, 3b and 3c only (all from one run)");
    const int directions = opt.full() ? 20000 : 2000;
    const std::size_t line_count = opt.full() ? 2000000 : 200000;
    CsvWriter csv(opt.out + "/crofton.csv", {"part", "body", "kind", "triangles", "surface_area", "predicted",
                                             "measured", "std_error", "ratio", "ratio_std_error"});
    // Demo meshes: closed ones (their hulls for part 1, themselves for part 2), up to 200k triangles.
    std::vector<std::pair<std::string, std::shared_ptr<const Scene>>> meshes;
    for (const auto& name : cgal_reference_meshes()) {
      const auto s = make_scene("cgal:" + name);
      if (s->mesh.size() <= 200000 && describe(*s).closed) meshes.emplace_back(name, s);
      if (meshes.size() == (opt.full() ? 12u : 6u)) break;
    }
    std::vector<Body> bodies;
    for (const auto& [name, s] : meshes) bodies.push_back({"hull of cgal:" + name, "hull of a demo mesh", convex_hull(s->mesh.vertices)});
    const struct {
      const char* name;
      const char* shape;
      int count;
      Vec3d scale;
    } polytopes[] = {{"tetrahedron-like: 4 points on the sphere", "round", 4, Vec3d(1.0)},
                     {"12 points on the sphere", "round", 12, Vec3d(1.0)},
                     {"1000 points on the sphere", "round", 1000, Vec3d(1.0)},
                     {"200 points in a cube", "cube", 200, Vec3d(1.0)},
                     {"needle: Gaussian 1 : 0.02 : 0.02", "gauss", 300, Vec3d(1.0, 0.02, 0.02)},
                     {"flat: Gaussian 1 : 1 : 0.001", "gauss", 300, Vec3d(1.0, 1.0, 0.001)},
                     {"far from the origin: 100 points on a sphere at 1e4", "round", 100, Vec3d(1.0)}};
    std::uint64_t seed = 1;
    for (const auto& p : polytopes) {
      auto points = random_points(p.shape, p.count, p.scale, seed++);
      if (std::string(p.name).find("far") == 0)
        for (auto& q : points) q = q + Vec3f(1e4f, 0.0f, 0.0f);
      bodies.push_back({p.name, "random polytope", convex_hull(points)});
    }

    // 1. Convex bodies.
    std::string md = section_anchor("claim-3");
    md += "## Crofton's theorem: mean projected area S/4 and hit probability S_o/S_c\n\n";
    md += "**Claim** (lecture, *Average projected area*): the average projected area of a convex shape of surface "
          "area S is S/4 (\"convex shapes only\"), and a ray that hits a convex shape S_c hits a convex shape S_o "
          "inside it with probability S_o/S_c. **Source**: Cauchy's surface area formula and Crofton's formula of "
          "integral geometry (L. A. Santaló, *Integral Geometry and Geometric Probability*, Addison-Wesley, 1976, "
          "ch. 12–14); see [docs/theory.md](../theory.md#claim-3).\n\n";
    md += fmt::format(
        "**Experiment**: (1) CGAL convex hulls (`CGAL::convex_hull_3`) of {} closed demo meshes and {} random convex "
        "polytopes; the projected area in each of {} uniform random directions is the area of the planar convex hull "
        "(`CGAL::convex_hull_2`) of the projected hull vertices, exact up to double rounding. (2) The same demo "
        "meshes, not convex: their true mean silhouette area, measured as π r²·P(hit) with {} isotropic random lines "
        "through the ball of radius r around each mesh (traced with `bvh`, the default: certified kernel, exact first hits). (3) Pairs of convex bodies, one "
        "inside the other: the fraction of {} isotropic lines meeting the outer that also meet the inner. Every ± is "
        "one standard error of the sampling. Command: `build/experiments/exp_crofton --mode {}`.\n\n",
        meshes.size(), std::size(polytopes), directions, line_count, line_count, opt.mode);
    const std::string spec = fmt::format("exp_crofton:mode={},directions={},lines={}", opt.mode, directions, line_count);
    const std::string command = "build/experiments/exp_crofton --mode " + opt.mode;
    const Threshold t3{"Cauchy's formula is exact, so c in Ā = c·S/4 (fitted over every body) must lie within 1 ± 0.01: "
                       "confirmed where c's 95% interval lies inside (0.99, 1.01), refuted where it lies outside",
                       "within", 1.0, 0.01};
    const Threshold t3b{"a non-convex silhouette hides part of the surface, so the largest ratio mean silhouette / (S/4) "
                        "over the non-convex meshes must lie below 1: confirmed where its 95% interval lies below 1",
                        "below", 1.0};
    const Threshold t3c{"Crofton's formula is exact, so c = P(inner | outer)/(S_o/S_c) (the pairs' ratios pooled by "
                        "their sampling errors) must lie within 1 ± 0.05 (the pairs' line samples leave a few per cent of sampling error): confirmed "
                        "where c's 95% interval lies inside (0.95, 1.05), refuted where it lies outside",
                        "within", 1.0, 0.05};
    md += "**Thresholds, stated before measuring.** Claim 3: " + t3.text + ". Claim 3b: " + t3b.text + ". Claim 3c: " +
          t3c.text + ". Intervals of fitted constants are value ± t(0.975, points − 1)·s.e.; of a sampled ratio, "
          "± 1.96·s.e.\n\nReproduce: `" + command + "` (all three claims come from one run).\n\n";
    md += "### 1. Convex bodies: mean projected area against S/4\n\n| body | kind | faces | S | S/4 | mean projected area | "
          "ratio |\n|---|---|---|---|---|---|---|\n";
    std::vector<std::vector<double>> conv_x;
    std::vector<double> conv_y;
    double worst_dev = 0;
    for (const auto& b : bodies) {
      progress("crofton: " + b.name);
      const double s = surface_area(b.hull);
      const auto [mean, se] = mean_projected_area(b.hull, directions, seed++);
      const double ratio = mean / (s / 4);
      csv.row("convex", b.name, b.kind, b.hull.size(), s, s / 4, mean, se, ratio, se / (s / 4));
      md += fmt::format("| {} | {} | {} | {:.6g} | {:.6g} | {} | {} |\n", b.name, b.kind, b.hull.size(), s, s / 4,
                        format_with_error(mean, se), format_with_error(ratio, se / (s / 4)));
      conv_x.push_back({s / 4});
      conv_y.push_back(mean);
      worst_dev = std::max(worst_dev, std::abs(ratio - 1) / (se / (s / 4)));
    }
    FitOptions plain;
    plain.loss_scale = 0;
    const FitResult conv = fit_linear_terms(conv_x, conv_y, plain);
    md += fmt::format("\nFit of mean projected area = c · S/4 over the {} bodies (Ceres, relative residuals): **c = {}**; "
                      "the largest deviation of one body is {:.1f} standard errors.\n\n",
                      conv.points, format_with_error(conv.values[0], conv.std_errors[0]), worst_dev);

    // 2. Non-convex meshes.
    md += "### 2. Non-convex meshes: mean silhouette area against S/4\n\n| mesh | triangles | S | S/4 | mean silhouette "
          "area (lines) | ratio | its hull: lines | its hull: projections |\n|---|---|---|---|---|---|---|---|\n";
    double lo_ratio = 1e300, hi_ratio = 0, hi_ratio_se = 0;
    std::vector<std::vector<double>> hull_x;
    std::vector<double> hull_y;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      const auto& [name, s] = meshes[i];
      progress("crofton: silhouette of " + name);
      double r = 0;
      const auto lines = lines_around(s->bounds(), line_count, 100 + i, r);
      const double disk = std::numbers::pi * r * r;
      const auto [p, pse] = hit_fraction(s, lines);
      const double area = surface_area(s->mesh), mean = disk * p, se = disk * pse;
      const auto [hp, hpse] = hit_fraction(mesh_scene(name + " hull", bodies[i].hull), lines);
      const double hull_exact = conv_y[i];
      csv.row("nonconvex", name, "demo mesh", s->mesh.size(), area, area / 4, mean, se, mean / (area / 4), se / (area / 4));
      csv.row("hull_by_lines", "hull of cgal:" + name, "hull of a demo mesh", bodies[i].hull.size(), surface_area(bodies[i].hull),
              hull_exact, disk * hp, disk * hpse, disk * hp / hull_exact, disk * hpse / hull_exact);
      md += fmt::format("| cgal:{} | {} | {:.6g} | {:.6g} | {} | {} | {} | {:.6g} |\n", name, s->mesh.size(), area, area / 4,
                        format_with_error(mean, se), format_with_error(mean / (area / 4), se / (area / 4)),
                        format_with_error(disk * hp, disk * hpse), hull_exact);
      lo_ratio = std::min(lo_ratio, mean / (area / 4));
      if (mean / (area / 4) > hi_ratio) hi_ratio = mean / (area / 4), hi_ratio_se = se / (area / 4);
      hull_x.push_back({hull_exact});
      hull_y.push_back(disk * hp);
    }
    const FitResult hull_lines = fit_linear_terms(hull_x, hull_y, plain);
    md += fmt::format(
        "\nThe line estimate is checked on each mesh's hull, whose mean projected area part 1 computed exactly: "
        "lines / projections = {} (fit over the {} hulls). A non-convex surface's silhouette hides the parts of it "
        "that other parts cover, so it falls short of S/4: here by {:.0f}% to {:.0f}%. (Crofton's formula itself "
        "holds for any surface when a line counts once per crossing; it is the silhouette, one count per line, that "
        "needs convexity.)\n\n",
        format_with_error(hull_lines.values[0], hull_lines.std_errors[0]), hull_lines.points, 100 * (1 - hi_ratio),
        100 * (1 - lo_ratio));

    // 3. Convex within convex.
    md += "### 3. Convex within convex: P(line meets inner | it meets outer) against S_o/S_c\n\n| inner | outer | S_o/S_c | "
          "lines meeting outer | measured | ratio |\n|---|---|---|---|---|---|\n";
    struct Pair {
      std::string inner_name, outer_name;
      TriangleMesh inner, outer;
    };
    std::vector<Pair> pairs;
    pairs.push_back({"hull of cgal:" + meshes[0].first, "its bounding box", bodies[0].hull, box_hull(meshes[0].second->bounds())});
    pairs.push_back({"sphere:n=2000", "its bounding box", make_scene("sphere:n=2000")->mesh,
                     box_hull(make_scene("sphere:n=2000")->bounds())});
    pairs.push_back({"12 points on the sphere, scaled 0.3", "1000 points on the sphere", [&] {
                       auto p = random_points("round", 12, Vec3d(0.3), 2);
                       return convex_hull(p);
                     }(),
                     bodies[meshes.size() + 2].hull});
    pairs.push_back({"needle: Gaussian 1 : 0.02 : 0.02", "the box [-5, 5]^3", bodies[meshes.size() + 4].hull,
                     box_hull(Bounds3f(Vec3f(-5.0f), Vec3f(5.0f)))});
    pairs.push_back({"flat: Gaussian 1 : 1 : 0.001", "the box [-5, 5]^3", bodies[meshes.size() + 5].hull,
                     box_hull(Bounds3f(Vec3f(-5.0f), Vec3f(5.0f)))});
    std::vector<std::vector<double>> pair_x;
    std::vector<double> pair_y, pair_ratio, pair_ratio_se;
    double worst_pair = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const auto& pr = pairs[i];
      progress("crofton: " + pr.inner_name + " in " + pr.outer_name);
      const auto outer = mesh_scene(pr.outer_name, pr.outer);
      const auto inner = mesh_scene(pr.inner_name, pr.inner);
      double r = 0;
      const auto lines = lines_around(outer->bounds(), line_count, 200 + i, r);
      const auto outer_accel = make_accelerator("bvh", outer);
      const auto inner_accel = make_accelerator("bvh", inner);
      const TraceResult o = trace_rays(*outer_accel, lines, TraceOptions{0, false, false});
      const TraceResult in = trace_rays(*inner_accel, lines, TraceOptions{0, false, false});
      std::size_t both = 0, inner_only = 0;
      for (std::size_t k = 0; k < lines.size(); ++k) {
        both += o.hits[k].valid() && in.hits[k].valid();
        inner_only += !o.hits[k].valid() && in.hits[k].valid();
      }
      const double predicted = surface_area(pr.inner) / surface_area(pr.outer);
      const double n = static_cast<double>(o.hit_count), p = static_cast<double>(both) / n, se = std::sqrt(p * (1 - p) / n);
      csv.row("nested", pr.inner_name + " in " + pr.outer_name, "pair", pr.inner.size(), surface_area(pr.inner), predicted,
              p, se, p / predicted, se / predicted);
      md += fmt::format("| {} | {} | {:.5f} | {:.0f} | {} | {} |\n", pr.inner_name, pr.outer_name, predicted, n,
                        format_with_error(p, se), format_with_error(p / predicted, se / predicted));
      if (inner_only > 0) md += fmt::format("| | ({} lines met the inner body but not the outer: it is not inside) | | | | |\n", inner_only);
      pair_x.push_back({predicted});
      pair_y.push_back(p);
      pair_ratio.push_back(p / predicted);
      pair_ratio_se.push_back(se / predicted);
      worst_pair = std::max(worst_pair, std::abs(p - predicted) / se);
    }
    const FitResult nested = fit_linear_terms(pair_x, pair_y, plain);
    md += fmt::format("\nFit of measured = c · S_o/S_c over the {} pairs: **c = {}**; the largest deviation of one pair "
                      "is {:.1f} standard errors.\n\n",
                      nested.points, format_with_error(nested.values[0], nested.std_errors[0]), worst_pair);
    // The pairs' ratios have known, very different sampling errors (binomial over the lines): their
    // inverse-variance weighted mean, its s.e. scaled by the Birge ratio √(χ²/(n − 1)) where the
    // ratios scatter more than their errors say.
    double w_sum = 0, wr_sum = 0;
    for (std::size_t i = 0; i < pair_ratio.size(); ++i) {
      const double w = 1 / (pair_ratio_se[i] * pair_ratio_se[i]);
      w_sum += w;
      wr_sum += w * pair_ratio[i];
    }
    const double pooled = wr_sum / w_sum;
    double chi2 = 0;
    for (std::size_t i = 0; i < pair_ratio.size(); ++i) chi2 += std::pow((pair_ratio[i] - pooled) / pair_ratio_se[i], 2);
    const double birge = std::max(1.0, std::sqrt(chi2 / static_cast<double>(pair_ratio.size() - 1)));
    const double pooled_se = birge / std::sqrt(w_sum);
    md += fmt::format("Inverse-variance weighted mean of the pairs' ratios (each weighted by its sampling error; s.e. "
                      "scaled by the Birge ratio √(χ²/(n − 1)) = {:.2f}): **c = {}**, the key number of claim 3c.\n\n",
                      birge, format_with_error(pooled, pooled_se));

    const KeyNumber k3 = fitted_key("c in Ā = c·S/4", conv, 0, spec);
    const KeyNumber k3b = normal_key("largest mean silhouette / (S/4) of a non-convex mesh", hi_ratio, hi_ratio_se,
                                     static_cast<long>(line_count), spec);
    KeyNumber k3c = fitted_key("c: inverse-variance weighted mean of P(inner | outer) / (S_o/S_c)", pooled, pooled_se,
                               pair_ratio.size(), 1, spec);
    k3c.interval += ", Birge-scaled";
    std::vector<Verdict> verdicts = {
        {"3", "mean projected area of a convex body = S/4", decide_verdict(k3, t3),
         fmt::format("Ā = c·S/4, c = {} over {} hulls and polytopes", format_with_error(conv.values[0], conv.std_errors[0]),
                     conv.points),
         "claim-3", k3, t3, command},
        {"3b", "S/4 needs convexity: non-convex silhouettes fall short", decide_verdict(k3b, t3b),
         fmt::format("mean silhouette / (S/4) = {:.2f} … {:.2f} on {} closed demo meshes", lo_ratio, hi_ratio, meshes.size()),
         "claim-3", k3b, t3b, command},
        {"3c", "P(hit inner | hit outer) = S_o/S_c", decide_verdict(k3c, t3c),
         fmt::format("measured = c·S_o/S_c, c = {} (weighted mean) over {} nested pairs", format_with_error(pooled, pooled_se),
                     pair_ratio.size()),
         "claim-3", k3c, t3c, command}};
    md += verdict_paragraph(
        verdicts[0], fmt::format("Round, cubic, needle-like, flat and far-from-origin polytopes and the hulls of real "
                                 "meshes: c − 1 = {:+.5f}, the largest deviation of one body {:.1f} of its standard "
                                 "errors.",
                                 conv.values[0] - 1.0, worst_dev));
    md += verdict_paragraph(
        verdicts[1], fmt::format("The lecture states S/4 for convex shapes only; a non-convex silhouette hides the parts "
                                 "of the surface it covers, so its mean falls {} S/4 (ratio {:.2f} … {:.2f}). A cost "
                                 "model that charges a mesh by S/4 of its surface overestimates how often rays meet it.",
                                 hi_ratio < 1 ? "short of" : "not short of", lo_ratio, hi_ratio));
    md += verdict_paragraph(
        verdicts[2], fmt::format("The conditional probability follows the ratio of surface areas over {} pairs of "
                                 "different shapes, the largest deviation {:.1f} standard errors of its pair.",
                                 nested.points, worst_pair));
    md += "![Crofton's theorem](crofton.png)\n\n*Figure: left, mean projected (or silhouette) area over S/4 for every "
          "body and mesh, error bars 2 s.e.: the convex bodies sit on 1, the non-convex meshes' silhouettes fall "
          "short of it; right, P(inner | outer) against S_o/S_c for the nested pairs, on the diagonal where claim 3c "
          "holds.*\n\n";
    md += fmt::format("Data: crofton.csv. Measured by `build/experiments/exp_crofton --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/crofton.md") << md;
    write_verdicts(opt.out, "crofton", verdicts);
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_crofton: error: " << e.what() << "\n";
    return 2;
  }
}
