// Speed against accuracy, the lab's headline chart: every method one point per scene family,
// throughput relative to Embree on ordinary rays (primary, diffuse, shadow; single thread, at least
// five rounds alternated with Embree; the ratio of the medians, with its 95% bootstrap interval over
// the rounds) against its error rate against the exact oracle (accel/common/hit_comparison.h:
// false hits, missed hits, wrong first hits) on adversarial rays: random lines, edge-, vertex-aimed, touching and grazing
// rays, and rays on the scene moved far from the origin and shrunk. Errors are also counted per
// class (crossing, touching, grazing, on-surface, far).
//
// Methods: every accelerator the factory knows with its default parameters (the certified kernel
// wherever a kernel is chosen) and every listed variant (the brute-force kernels watertight, mt and
// exact; `kernel=watertight` on every structure; Embree and its robust mode; the BVH's robust=off;
// ...).
// Writes speed_accuracy.csv and speed_accuracy.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "cost/model_file.h"
#include "cost/replicates.h"
#include "experiment_common.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

/// Every method of the chart, named as the tool names it: each kind's defaults and listed variants.
std::vector<std::string> methods() {
  std::vector<std::string> specs;
  for (const auto& kind : accelerator_kinds()) {
    specs.push_back(kind.name);
    for (const auto& v : kind.oracle_variants) specs.push_back(kind.name + ":" + v);
  }
  return specs;
}

struct Family {
  std::string name, spec, why;
  bool closed = true;  ///< a closed mesh: edge- and vertex-aimed rays cross it
};

/// The classes of the error columns. Near the origin, the exact oracle's class of first contact
/// (accel/exact/contact_classes.h): a well-conditioned crossing (misses included), touching,
/// starting on the surface, or grazing (every other ill-conditioned ray: within the float error
/// scale of a contour or of its start). Every ray of the far scenes (offsets >= 1e4, scales <=
/// 1e-4) is counted under `far`, whatever its contact. The classes partition the rays.
enum ErrorClass { kCrossing, kTouching, kGrazing, kOnSurface, kFar, kErrorClasses };
const char* const kErrorClassNames[kErrorClasses] = {"crossing", "touching", "grazing", "on_surface", "far"};

ErrorClass error_class(const RayContact& c) {
  if (c.contact == Contact::touching) return kTouching;
  if (c.contact == Contact::on_surface) return kOnSurface;
  return c.ill_conditioned ? kGrazing : kCrossing;
}

/// A scene far from the origin or tiny, and the rays traced on it.
struct FarScene {
  std::string label, transform;
};
const std::vector<FarScene> kFarScenes = {{"offset3e4", "rotate=1;2;3:40,translate=3e4:-2e4:1e4"},
                                          {"scale1e-5", "rotate=y:70,scale=1e-5"}};

/// The comparison of `got` with the oracle's `ref` by the rule `bound` states (compare_hits_exact for
/// methods stated exact, compare_hits otherwise), as exp_robustness and the oracle suite judge.
HitComparison compare_by_rule(const AccuracyBound& bound, const Scene& scene, const std::vector<Ray>& rays,
                              const std::vector<Hit>& got, const std::vector<Hit>& ref, double diagonal,
                              const std::vector<RayContact>* classes) {
  return bound.exact ? compare_hits_exact(scene, rays, got, ref, classes)
                     : compare_hits(rays, got, ref, diagonal, classes);
}

/// A short form of a method's stated accuracy bound (AccuracyBound; `raylab accels` states it in full).
std::string bound_text(const AccuracyBound& b) {
  if (b.exact) return "exact, every class";
  const auto rate = [](double r) { return r == 0 ? std::string("0") : fmt::format("{:g}%", 100 * r); };
  std::string s = b.crossing_features == 0 && b.crossing_other == 0
                      ? std::string("crossings: 0 errors")
                      : "crossings: <= " + rate(b.crossing_features) + " (feature rays), <= " + rate(b.crossing_other) +
                            " (other)";
  return s + (b.touching >= 1 && b.on_surface >= 1 && b.ill_conditioned >= 1 ? "; other classes: no claim" : "");
}

/// Single-thread timings of a method and of Embree on the ordinary ray sets, in alternated rounds.
struct RoundTimes {
  std::vector<double> method_s, embree_s;  ///< per round: CPU seconds of the tracing thread over every set
};

/// At least `min_rounds` rounds (and until `min_seconds` of both are spent), each tracing every set of
/// `sets` with Embree, then with the method: the alternation spreads a shared machine's slow spells
/// over both.
RoundTimes alternated_rounds(const Primitive& method, const Primitive& embree,
                             const std::vector<std::pair<std::vector<Ray>, bool>>& sets, int min_rounds,
                             double min_seconds) {
  RoundTimes t;
  double spent = 0;
  for (int round = 0; round < 200 && (round < min_rounds || spent < min_seconds); ++round) {
    double e = 0, m = 0;
    for (const auto& [rays, any_hit] : sets) {
      e += trace_rays(embree, rays, TraceOptions{1, false, any_hit}).thread_cpu_seconds;
      m += trace_rays(method, rays, TraceOptions{1, false, any_hit}).thread_cpu_seconds;
    }
    t.embree_s.push_back(e);
    t.method_s.push_back(m);
    spent += e + m;
  }
  return t;
}

/// The throughput ratio median(embree) / median(method) over the rounds (a round a shared machine
/// slowed does not move it), and its 95% percentile bootstrap interval (rounds resampled in pairs,
/// 2000 resamples, a fixed seed: Efron & Tibshirani, An Introduction to the Bootstrap, 1993, ch. 13).
struct Ratio {
  double value = 0, lo = 0, hi = 0;
};
Ratio bootstrap_ratio(const RoundTimes& t) {
  const std::size_t n = t.method_s.size();
  std::mt19937_64 rng(20261204);
  std::vector<double> ratios, e(n), m(n);
  constexpr int kResamples = 2000;
  ratios.reserve(kResamples);
  for (int b = 0; b < kResamples; ++b) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(rng() % n);
      e[i] = t.embree_s[k], m[i] = t.method_s[k];
    }
    ratios.push_back(median(e) / median(m));
  }
  std::sort(ratios.begin(), ratios.end());
  return {median(t.embree_s) / median(t.method_s), ratios[static_cast<std::size_t>(0.025 * kResamples)],
          ratios[static_cast<std::size_t>(0.975 * kResamples) - 1]};
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
    const std::string count = opt.full() ? "4096" : "1024";
    const std::string far_count = opt.full() ? "1024" : "256";
    const std::string ordinary_count = opt.full() ? "4096" : "1024";
    const std::vector<std::string> near_kinds = {"lines:" + count, "edges:" + count, "vertices:" + count,
                                                 "touching:" + count, "grazing:" + count};
    const std::vector<std::string> far_kinds = {"lines:" + far_count, "edges:" + far_count, "vertices:" + far_count};
    const std::vector<std::string> ordinary_kinds = {"primary:" + ordinary_count, "diffuse:" + ordinary_count,
                                                     "shadow:" + ordinary_count};
    constexpr int kMinRounds = 5;
    const double min_s = opt.full() ? 0.3 : 0.03;
    std::vector<std::string> header = {"family", "scene", "method", "rays", "ray_count", "mismatches", "false_hits",
                                       "missed_hits", "wrong_t", "ties", "error_rate", "rule", "within_bound"};
    for (const char* c : kErrorClassNames) header.push_back(std::string("rays_") + c), header.push_back(std::string("mismatches_") + c);
    for (const char* c : {"ordinary_rays", "rounds", "ns_per_ray", "embree_ns_per_ray", "throughput_vs_embree",
                          "throughput_ci95_lo", "throughput_ci95_hi", "bound", "ns_per_ray_lo", "ns_per_ray_hi",
                          "embree_ns_per_ray_lo", "embree_ns_per_ray_hi"})
      header.push_back(c);
    CsvWriter csv(opt.out + "/speed_accuracy.csv", header);

    // One traced set of adversarial rays: its comparison with the oracle, per error class.
    struct Tally {
      std::size_t rays = 0, mismatches = 0, false_hits = 0, missed = 0, wrong_t = 0, ties = 0;
      std::array<std::size_t, kErrorClasses> class_rays{}, class_mismatches{};
      bool within = true;
      void add(const Tally& o) {
        rays += o.rays, mismatches += o.mismatches, false_hits += o.false_hits, missed += o.missed, wrong_t += o.wrong_t,
            ties += o.ties, within = within && o.within;
        for (int c = 0; c < kErrorClasses; ++c) class_rays[c] += o.class_rays[c], class_mismatches[c] += o.class_mismatches[c];
      }
      double rate() const { return rays ? static_cast<double>(mismatches) / static_cast<double>(rays) : 0.0; }
    };
    struct Point {
      Tally all;
      Ratio throughput;
      std::size_t rounds = 0;
    };
    struct RaySet {
      std::string label;  ///< the ray spec, prefixed by the far scene's label
      std::shared_ptr<const Scene> scene;
      std::vector<Ray> rays;
      std::vector<Hit> reference;
      std::vector<RayContact> classes;
      bool feature = false, far = false;
      double diagonal = 0;
    };
    std::map<std::string, std::map<std::string, Point>> points;  // family -> method -> point
    std::vector<std::string> all_methods;
    std::map<std::string, std::size_t> adversarial_rays;  // family -> rays
    std::size_t ordinary_rays_per_family = 0;
    std::vector<std::string> skipped;  // ray sets a family's scene cannot make
    for (const auto& fam : families) {
      const auto scene = make_scene(fam.spec);
      std::vector<std::pair<std::shared_ptr<const Scene>, std::string>> scenes = {{scene, ""}};
      for (const auto& f : kFarScenes)
        scenes.push_back({make_scene("transformed:of=(" + fam.spec + ")," + f.transform), f.label + "/"});
      std::vector<RaySet> sets;
      for (const auto& [sc, prefix] : scenes) {
        const auto oracle = make_accelerator("exact", sc);
        for (const auto& k : prefix.empty() ? near_kinds : far_kinds) {
          RaySet r{prefix + k, sc, {}, {}, {}, is_feature_ray_spec(k), !prefix.empty(),
                   length(Vec3d(sc->bounds().diagonal()))};
          try {
            r.rays = make_ray_set(k, sc);
          } catch (const InputError& e) {
            // A scene without such features (walls' vertex fans are flat: nothing to touch).
            skipped.push_back(fmt::format("`{}` on {}: {}", k, fam.name, e.what()));
            continue;
          }
          r.reference = trace_rays(*oracle, r.rays, TraceOptions{0, false, false}).hits;
          r.classes = classify_contacts(sc, r.rays);
          sets.push_back(std::move(r));
        }
      }
      std::vector<std::pair<std::vector<Ray>, bool>> ordinary;
      ordinary_rays_per_family = 0;
      for (const auto& k : ordinary_kinds) {
        ordinary.push_back({make_ray_set(k, scene), is_any_hit_ray_spec(k)});
        ordinary_rays_per_family += ordinary.back().first.size();
      }
      for (const auto& r : sets) adversarial_rays[fam.name] += r.rays.size();
      const auto embree = make_accelerator("embree", scene);
      for (const auto& m : methods()) {
        if (std::find(all_methods.begin(), all_methods.end(), m) == all_methods.end()) all_methods.push_back(m);
        progress("speed_accuracy: " + fam.spec + " " + m);
        const AccuracyBound bound = accuracy_bound(m);
        Point p;
        std::map<const Scene*, std::unique_ptr<Aggregate>> built;
        std::vector<Tally> tallies;
        for (const auto& r : sets) {
          auto& accel = built[r.scene.get()];
          if (!accel) accel = make_accelerator(m, r.scene, model_build_context());
          const std::vector<Hit> got = trace_rays(*accel, r.rays, TraceOptions{0, false, false}).hits;  // not timed
          const HitComparison h = compare_by_rule(bound, *r.scene, r.rays, got, r.reference, r.diagonal, &r.classes);
          Tally t{h.rays, h.mismatches, h.false_hits, h.missed_hits, h.wrong_t, h.ties, {}, {},
                  within_bound(bound, h, r.feature)};
          // Per class: the comparison of each class's rays alone.
          std::array<std::vector<std::size_t>, kErrorClasses> members;
          for (std::size_t i = 0; i < r.rays.size(); ++i) members[r.far ? kFar : error_class(r.classes[i])].push_back(i);
          for (int c = 0; c < kErrorClasses; ++c) {
            if (members[c].empty()) continue;
            std::vector<Ray> cr;
            std::vector<Hit> ch, cref;
            for (const std::size_t i : members[c]) cr.push_back(r.rays[i]), ch.push_back(got[i]), cref.push_back(r.reference[i]);
            t.class_rays[c] = cr.size();
            t.class_mismatches[c] = compare_by_rule(bound, *r.scene, cr, ch, cref, r.diagonal, nullptr).mismatches;
          }
          p.all.add(t);
          tallies.push_back(t);
        }
        const RoundTimes times = alternated_rounds(*built[scene.get()], *embree, ordinary, kMinRounds, min_s);
        p.throughput = bootstrap_ratio(times);
        p.rounds = times.method_s.size();
        const double per_ray = 1e9 / static_cast<double>(ordinary_rays_per_family);
        const IntervalEstimate ms = bootstrap_median(times.method_s), es = bootstrap_median(times.embree_s);
        const auto write = [&](const std::string& label, const Tally& t) {
          csv.row(fam.name, fam.spec, m, label, t.rays, t.mismatches, t.false_hits, t.missed, t.wrong_t, t.ties, t.rate(),
                  std::string(bound.exact ? "exact" : "tolerance"), t.within ? 1 : 0, t.class_rays[kCrossing],
                  t.class_mismatches[kCrossing], t.class_rays[kTouching], t.class_mismatches[kTouching],
                  t.class_rays[kGrazing], t.class_mismatches[kGrazing], t.class_rays[kOnSurface],
                  t.class_mismatches[kOnSurface], t.class_rays[kFar], t.class_mismatches[kFar], ordinary_rays_per_family,
                  p.rounds, ms.value * per_ray, es.value * per_ray, p.throughput.value, p.throughput.lo,
                  p.throughput.hi, bound_text(bound), ms.lo * per_ray, ms.hi * per_ray, es.lo * per_ray,
                  es.hi * per_ray);
        };
        for (std::size_t i = 0; i < sets.size(); ++i) write(sets[i].label, tallies[i]);
        write("all", p.all);
        points[fam.name][m] = p;
      }
    }

    std::string md = section_anchor("speed-accuracy");
    md += "## Speed against accuracy\n\n";
    md += fmt::format(
        "Every method is one point per scene family. **Speed**: throughput relative to Embree (`embree`, medium quality) "
        "on ordinary rays only ({} primary, diffuse and shadow rays, the shadow rays as any-hit queries), single "
        "thread, timed in the tracing thread's CPU time, in at least {} rounds alternated with Embree's on the same "
        "rays; the ratio is the median of Embree's round times over the median of the method's, with its 95% "
        "bootstrap interval over the rounds (ns_per_ray and embree_ns_per_ray in the CSV are the medians, each with "
        "its own 95% bootstrap interval, *_lo and *_hi). "
        "**Accuracy**: the error rate on adversarial rays, the fraction whose closest hit disagrees with the exact "
        "oracle (`exact`): false hits, missed hits and wrong first hits, by the rule the method's accuracy bound is "
        "stated in (`raylab trace --check`'s tolerance for float methods; for methods stated exact, the same primitive "
        "or one at the same exact t). Adversarial rays per family: {} each of random lines (`lines:`), rays aimed "
        "exactly at edges (`edges:`) and vertices (`vertices:`), touching rays (`touching:`) and grazing rays "
        "(`grazing:`), and {} each of lines, edge- and vertex-aimed rays on the scene moved far from the origin "
        "(`transformed:of=(SCENE),{}`) and shrunk (`transformed:of=(SCENE),{}`). Methods: every "
        "accelerator with its defaults (the certified kernel, wherever a kernel is chosen) and each variant the "
        "factory lists (`raylab accels`; `kernel=watertight` among them for every structure). Command: "
        "`build/experiments/exp_speed_accuracy --mode {}`.\n\n",
        ordinary_kinds.front().substr(ordinary_kinds.front().find(':') + 1), kMinRounds, count, far_count,
        kFarScenes[0].transform, kFarScenes[1].transform, opt.mode);
    md += "| scene family | scene | why | adversarial rays |\n|---|---|---|---|\n";
    for (const auto& f : families)
      md += fmt::format("| {} | `{}` | {} | {} |\n", f.name, f.spec, f.why, adversarial_rays[f.name]);
    if (!skipped.empty()) {
      md += "\nRay sets a scene cannot make, left out:\n\n";
      for (const auto& k : skipped) md += "- " + k + "\n";
    }

    // The two answers the chart is read for: the fastest method with no error on any family, among
    // those stated exact and among the float ones, and the float method with the fewest errors.
    // The geometric mean over the families, and the geometric means of the families' interval ends:
    // the mean lies between them whenever every family's ratio lies in its own 95% interval.
    std::map<std::string, double> log_throughput, log_throughput_lo, log_throughput_hi;
    std::map<std::string, Tally> totals;
    for (const auto& m : all_methods) {
      int n = 0;
      for (const auto& f : families)
        if (points[f.name].count(m)) {
          const Ratio& r = points[f.name][m].throughput;
          log_throughput[m] += std::log(r.value);
          log_throughput_lo[m] += std::log(r.lo);
          log_throughput_hi[m] += std::log(r.hi);
          totals[m].add(points[f.name][m].all);
          ++n;
        }
      if (n) log_throughput[m] /= n, log_throughput_lo[m] /= n, log_throughput_hi[m] /= n;
    }
    const auto best_of = [&](const std::function<bool(const std::string&)>& admit,
                             const std::function<bool(const std::string&, const std::string&)>& better) {
      std::string best;
      for (const auto& m : all_methods)
        if (log_throughput.count(m) && admit(m) && (best.empty() || better(m, best))) best = m;
      return best;
    };
    const auto faster = [&](const std::string& a, const std::string& b) { return log_throughput[a] > log_throughput[b]; };
    const auto is_exact = [&](const std::string& m) { return accuracy_bound(m).exact; };
    const std::string fastest_exact =
        best_of([&](const std::string& m) { return is_exact(m) && totals[m].mismatches == 0; }, faster);
    const std::string most_accurate_float = best_of([&](const std::string& m) { return !is_exact(m); },
                                                    [&](const std::string& a, const std::string& b) {
                                                      return totals[a].mismatches != totals[b].mismatches
                                                                 ? totals[a].mismatches < totals[b].mismatches
                                                                 : faster(a, b);
                                                    });
    const std::string fastest = best_of([](const std::string&) { return true; }, faster);
    const auto named = [&](const std::string& m) {
      return m.empty() ? std::string("none")
                       : fmt::format("`{}` ({:.3g}× Embree [{:.3g}, {:.3g}], geometric mean over the families; {} "
                                     "errors in {} adversarial rays)",
                                     m, std::exp(log_throughput[m]), std::exp(log_throughput_lo[m]),
                                     std::exp(log_throughput_hi[m]), totals[m].mismatches, totals[m].rays);
    };
    md += "\n**At a glance.** Fastest exact method: " + named(fastest_exact) +
          ". Most accurate float method (fewest errors, then fastest): " + named(most_accurate_float) +
          ". Fastest method of all: " + named(fastest) +
          ". Each bracket holds the geometric means of the families' 95% interval ends: the mean lies in it whenever "
          "every family's ratio lies in its own interval.\n\n";
    md += "![speed against accuracy](speed_accuracy.png)\n\n";
    md += "*Figure: one panel per scene family. Right is faster (Embree = 1, dotted line), down is more accurate; "
          "the horizontal bars are the 95% intervals of the throughput ratio. Colour: the structure; marker: the "
          "kernel. Methods with no error at all sit in the grey band at the bottom (0 errors in the family's "
          "adversarial rays, their count in the table above). The line is the Pareto frontier (no other method is both faster and more accurate); "
          "the methods on it are labelled.*\n\n";

    const auto interval = [](const Ratio& r) { return fmt::format("{:.3g} [{:.3g}, {:.3g}]", r.value, r.lo, r.hi); };
    md += "Every method: throughput relative to Embree on ordinary rays with its 95% interval (per family), then its "
          "errors over the four families per class of adversarial ray: **crossing** (well-conditioned crossings and "
          "misses), **touching** (first contact touches the surface without crossing it), **grazing** (every other "
          "ill-conditioned ray: its exact answer changes when the ray moves by a few ulps; the oracle's criterion is "
          "`lib/accel/exact/contact_classes.h`), **on-surface** (starts on a surface), **far** (every ray on the "
          "scenes far from the origin and shrunk), each as mismatches / rays; and the accuracy bound the method states "
          "(`raylab accels`), with whether it held on every set.\n\n";
    md += "| method |";
    for (const auto& f : families) md += " " + f.name + " |";
    for (const char* c : {"crossing", "touching", "grazing", "on-surface", "far"}) md += std::string(" ") + c + " |";
    md += " stated bound | held |\n|---|";
    for (std::size_t i = 0; i < families.size() + kErrorClasses + 2; ++i) md += "---|";
    md += "\n";
    for (const auto& m : all_methods) {
      md += "| `" + m + "` |";
      for (const auto& f : families)
        md += points[f.name].count(m) ? " " + interval(points[f.name][m].throughput) + " |" : std::string(" – |");
      const Tally& t = totals[m];
      for (int c = 0; c < kErrorClasses; ++c)
        md += t.class_rays[c] == 0 ? std::string(" – |")
                                   : fmt::format(" {}{}{} / {} |", t.class_mismatches[c] ? "" : "**",
                                                 t.class_mismatches[c], t.class_mismatches[c] ? "" : "**", t.class_rays[c]);
      md += " " + bound_text(accuracy_bound(m)) + " | " + (t.within ? "yes" : "**no**") + " |\n";
    }
    md += fmt::format("\nData: speed_accuracy.csv (per method, family and ray set; the `all` rows sum a family's sets, "
                      "and the class columns partition each row's rays). Measured by "
                      "`build/experiments/exp_speed_accuracy --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/speed_accuracy.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_speed_accuracy: error: " << e.what() << "\n";
    return 2;
  }
}
