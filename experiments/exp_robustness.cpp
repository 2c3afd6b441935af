// Robustness (issues 6 and 15): where methods fail. Runs every
// accelerator the factory knows (its default, the certified kernel wherever a kernel is chosen,
// and its listed variants: the watertight, Möller-Trumbore and exact kernels through brute,
// kernel=watertight on every structure, Embree and
// Embree's robust mode) against the exact oracle on the adversarial cases of
// tests/test_adversarial_cases.h (the same cases the adversarial test suite holds each method
// to), plus shared edges, vertices, touching and grazing rays of every closed CGAL demo mesh, and
// a closed mesh far from the origin, tiny and huge (`transformed`). The oracle classifies every
// ray (crossing, touching, on-surface, ill-conditioned; accel/exact/contact_classes.h), and
// mismatches are counted per class, by the exact rule for methods stated exact.
// What certainty costs is measured by exp_certainty.
// Also: the cost of non-finite rays and memory per triangle next to Embree's.
// Writes robustness.csv, robustness_classes.csv,
// robustness_nonfinite.csv, robustness_memory.csv and robustness.md.
#include <fmt/format.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <map>
#include <optional>

#include "../tests/test_adversarial_cases.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/exact/contact_classes.h"
#include "contact_columns.h"
#include "cost/model_file.h"
#include "cost/replicates.h"
#include "experiment_common.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

std::vector<std::string> all_accel_specs() { return adversarial::accel_specs_under_test(); }

/// Quick mode: the closed CGAL demo meshes up to this many triangles.
constexpr std::size_t kQuickMaxTriangles = 10000;

/// The closed mesh of the `transformed` cases (far from the origin, tiny, huge).
std::string kTransformedMesh(bool full) { return full ? "cgal:elephant" : "decimated:of=cgal:elephant,faces=2000"; }

/// Alternated rounds of the non-finite rays' timing: each round traces the valid, the invalid and
/// the mixed rays in turn, one pass each, timed by the tracing thread's CPU time.
constexpr int kNonFiniteRounds = 5;

/// Builds per structure behind the memory table's build seconds.
constexpr int kMemoryBuildRounds = 5;

struct Count {
  std::size_t rays = 0, false_hits = 0, missed = 0, wrong_t = 0, ties = 0, allowed = 0, occlusion_mismatches = 0;
  std::array<std::size_t, kRayBuckets> bucket_rays{}, bucket_mismatches{};
  ContactColumns contact;
  std::size_t mismatches() const { return false_hits + missed + wrong_t; }
  void add(const Count& o) {
    rays += o.rays, false_hits += o.false_hits, missed += o.missed, wrong_t += o.wrong_t, ties += o.ties,
        allowed += o.allowed, occlusion_mismatches += o.occlusion_mismatches;
    for (int b = 0; b < kRayBuckets; ++b) bucket_rays[b] += o.bucket_rays[b], bucket_mismatches[b] += o.bucket_mismatches[b];
    contact.add(o.contact);
  }
};

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "adversarial cases, contact classes, non-finite rays, memory per triangle");
  try {
    const auto specs = all_accel_specs();
    std::vector<adversarial::Case> cases = adversarial::synthetic_cases(opt.full() ? 4 : 1);
    // Every closed CGAL demo mesh (quick mode: those up to 10k triangles, 71 of the 85; the larger
    // ones cost most of the mode's time: brute force with the exact kernel and the exact oracle
    // grow with |rays| x |triangles|; full mode and the oracle suite run them).
    const std::size_t max_triangles = opt.full() ? 0 : kQuickMaxTriangles;
    const auto closed = adversarial::closed_cgal_meshes(max_triangles);
    progress(fmt::format("robustness: {} closed CGAL demo meshes", closed.size()));
    std::vector<std::optional<adversarial::Case>> mesh_cases(closed.size());  // made in parallel, kept in order
    tbb::parallel_for(std::size_t{0}, closed.size(), [&](std::size_t i) {
      mesh_cases[i] = adversarial::shared_edges_case(closed[i], make_scene("cgal:" + closed[i]), opt.full() ? 1024 : 256, true);
    });
    for (auto& c : mesh_cases) cases.push_back(std::move(*c));
    // The far, tiny and huge mesh: the elephant, decimated to 2000 triangles in quick mode. At its
    // 5558 triangles moved to an offset of 1e6, the grids with exact placement (and grid:d=8) take
    // 10-30 s per build here, against under a second at the origin: most of a quick run's time.
    for (auto& c : adversarial::transformed_cases(kTransformedMesh(opt.full()), opt.full() ? 1024 : 256))
      cases.push_back(std::move(c));

    CsvWriter csv(opt.out + "/robustness.csv",
                  {"case", "triangles", "ray_class", "accel", "rays", "mismatches", "false_hits", "missed_hits", "wrong_t",
                   "ties", "occlusion_mismatches", "allowed", "within_bound", "rule", "rays_crossing",
                   "mismatches_crossing", "rays_touching", "mismatches_touching", "rays_on_surface",
                   "mismatches_on_surface", "rays_ill_conditioned", "mismatches_ill_conditioned"});
    // rows: case group -> accel -> counts. CGAL meshes are summed into one row.
    std::map<std::string, std::map<std::string, Count>> table;
    std::vector<std::string> groups;
    std::map<std::string, std::string> group_detail;
    std::vector<std::string> violations;
    // Each case against every spec, cases in parallel (nothing here is timed); the rows are
    // written afterwards in case order, so the output does not depend on the thread count.
    struct SpecOutcome {
      Count count;
      bool exact = false;  ///< the spec's bound is the exact rule
      bool ok = false;
      std::string why;
    };
    std::vector<std::vector<SpecOutcome>> outcomes(cases.size());
    std::atomic<std::size_t> started{0};
    tbb::parallel_for(std::size_t{0}, cases.size(), [&](std::size_t ci) {
      const auto& c = cases[ci];
      progress(fmt::format("robustness: [{}/{}] {} ({} triangles, {} rays)", ++started, cases.size(), c.name,
                           c.scene->mesh.size(), c.rays.size()));
      const auto oracle = make_accelerator("exact", c.scene);
      const TraceResult ref = trace_rays(*oracle, c.rays, TraceOptions{0, false, false});
      const TraceResult ref_occ = trace_rays(*oracle, c.rays, TraceOptions{0, false, true});
      const std::vector<RayContact> classes = classify_contacts(c.scene, c.rays);
      const double diagonal = length(Vec3d(c.scene->bounds().diagonal()));
      for (const auto& spec : specs) {
        const auto accel = make_accelerator(spec, c.scene, model_build_context());
        const TraceResult got = trace_rays(*accel, c.rays, TraceOptions{0, false, false});
        const TraceResult got_occ = trace_rays(*accel, c.rays, TraceOptions{0, false, true});
        const AccuracyBound bound = accuracy_bound(spec);
        const HitComparison h = bound.exact ? compare_hits_exact(*c.scene, c.rays, got.hits, ref.hits, &classes)
                                            : compare_hits(c.rays, got.hits, ref.hits, diagonal, &classes);
        const HitComparison o = compare_occlusion(got_occ.blocked, ref_occ.blocked, &classes);
        std::size_t allowed = 0;
        for (int b = 0; b < kRayBuckets; ++b)
          allowed += allowed_mismatches(bound, static_cast<RayBucket>(b), c.feature_rays(), h.bucket_rays[b]);
        SpecOutcome out;
        out.exact = bound.exact;
        out.count = Count{h.rays, h.false_hits, h.missed_hits, h.wrong_t, h.ties, allowed, o.mismatches, h.bucket_rays,
                          h.bucket_mismatches, ContactColumns::of(h)};
        out.ok = within_bound(bound, h, c.feature_rays(), &out.why) && within_bound(bound, o, c.feature_rays(), &out.why);
        outcomes[ci].push_back(std::move(out));
      }
    });
    for (std::size_t ci = 0; ci < cases.size(); ++ci) {
      const auto& c = cases[ci];
      const std::string group = c.name.rfind("shared_edges/", 0) == 0 && c.name != "shared_edges/fan256"
                                    ? "shared_edges/cgal (" + std::to_string(closed.size()) + " meshes)"
                                    : c.name;
      if (!group_detail.count(group)) {
        groups.push_back(group);
        group_detail[group] = c.detail;
      }
      for (std::size_t si = 0; si < specs.size(); ++si) {
        const std::string& spec = specs[si];
        const SpecOutcome& out = outcomes[ci][si];
        const Count& k = out.count;
        if (!out.ok) violations.push_back(fmt::format("`{}` on `{}`: {}", spec, c.name, out.why));
        // The class columns are the per-class table's (contact_columns.h): touching and on-surface rays
        // by their contact class (the accuracy buckets file both under ill-conditioned).
        const ContactColumns& cc = k.contact;
        csv.row(c.name, c.scene->mesh.size(), std::string(adversarial::ray_class_name(c.ray_class)), spec, k.rays,
                k.mismatches(), k.false_hits, k.missed, k.wrong_t, k.ties, k.occlusion_mismatches, k.allowed,
                out.ok ? 1 : 0, std::string(out.exact ? "exact" : "tolerance"), cc.rays[0],
                cc.mismatches[0], cc.rays[1], cc.mismatches[1], cc.rays[2], cc.mismatches[2], cc.rays[3],
                cc.mismatches[3]);
        table[group][spec].add(k);
      }
    }

    std::string md = "## Robustness: where methods fail\n\n";
    md += "Every accelerator against the exact oracle on the adversarial cases of the test suite "
          "(`tests/test_adversarial_cases.h`, held to each method's stated accuracy bound by "
          "`tests/test_adversarial.cpp`), on edge-, vertex-aimed, touching and grazing rays of every closed CGAL demo "
          "mesh" + std::string(opt.full() ? "" : fmt::format(" up to {} triangles (quick mode; full mode runs all)", kQuickMaxTriangles)) + ", and on a closed mesh (`" + kTransformedMesh(opt.full()) + "`" + std::string(opt.full() ? "" : "; full mode: `cgal:elephant`") + ") moved far from the origin, shrunk and grown (`transformed:`). Each cell: "
          "closest-hit mismatches as false hits / missed hits / wrong first hits. Float methods are judged by the "
          "tolerance of `raylab trace --check` (t within 1e-4 of the scene's scale; a hit on another triangle there is a "
          "tie); methods stated exact (`exact`, `brute:kernel=exact`, and every accelerator's default, the certified kernel) by the exact rule: the "
          "same primitive, or one whose exact t equals the oracle's.\n\n";
    md += "| case | rays |";
    for (const auto& s : specs) md += " `" + s + "` |";
    md += "\n|---|---|";
    for (std::size_t i = 0; i < specs.size(); ++i) md += "---|";
    md += "\n";
    std::map<std::string, Count> totals;
    for (const auto& g : groups) {
      md += "| " + g + " | " + std::to_string(table[g][specs.front()].rays) + " |";
      for (const auto& s : specs) {
        const Count& k = table[g][s];
        totals[s].add(k);
        md += k.mismatches() == 0 ? " 0 |" : fmt::format(" {}/{}/{} |", k.false_hits, k.missed, k.wrong_t);
      }
      md += "\n";
    }
    md += "| **all** | " + std::to_string(totals[specs.front()].rays) + " |";
    for (const auto& s : specs) md += fmt::format(" **{}** ({:.2f}%) |", totals[s].mismatches(),
                                                  100.0 * totals[s].mismatches() / std::max<std::size_t>(1, totals[s].rays));
    md += "\n\n![mismatches per method and case](robustness.png)\n\n*Figure: one row per method; the share of "
          "rays that mismatch the exact oracle, per case (left) and per contact class over every case (right, the "
          "numbers of the per-class table below). White is agreement on every ray: the exact and certified methods' "
          "rows; the watertight float methods' errors gather in the touching and ill-conditioned columns, where no float "
          "kernel makes a claim, while Embree's and the Möller-Trumbore paths' (`kernel=mt`, `robust=off`) also fall "
          "on well-conditioned crossings.*\n\nCases:\n\n";
    for (const auto& g : groups) md += "- **" + g + "**: " + group_detail[g] + "\n";
    md += violations.empty() ? "\nEvery method stayed within its stated accuracy bound on every case.\n"
                             : "\nOutside the stated bound:\n\n- " + [&] {
                                 std::string s;
                                 for (const auto& v : violations) s += (s.empty() ? "" : "\n- ") + v;
                                 return s;
                               }() + "\n";

    // Per class of first contact, over every case: one robustness_classes.csv row per method and
    // class, and the table's cells from the same rows.
    {
      CsvWriter cls(opt.out + "/robustness_classes.csv",
                    {"accel", "rule", "class", "rays", "mismatches", "allowed_rate_features", "allowed_rate_other"});
      // The columns of ContactColumns, and the accuracy bucket whose bound applies to each.
      const std::array<std::pair<const char*, RayBucket>, 4> classes = {
          {{"crossing", RayBucket::crossing}, {"touching", RayBucket::touching}, {"on_surface", RayBucket::on_surface},
           {"ill_conditioned", RayBucket::ill_conditioned}}};
      std::map<std::string, ContactColumns> rows;
      for (const auto& s : specs) {
        const Count& k = totals[s];
        const AccuracyBound bound = accuracy_bound(s);
        for (std::size_t i = 0; i < classes.size(); ++i) {
          cls.row(s, std::string(bound.exact ? "exact" : "tolerance"), std::string(classes[i].first), k.contact.rays[i],
                  k.contact.mismatches[i], bound.max_mismatch_rate(classes[i].second, true),
                  bound.max_mismatch_rate(classes[i].second, false));
          rows[s].rays[i] = k.contact.rays[i];
          rows[s].mismatches[i] = k.contact.mismatches[i];
        }
      }
      md += "\n### Mismatches per class\n\nThe exact oracle classifies each ray's first contact (`raylab trace "
            "--classify`): a **crossing** passes from one side of the surface to the other (at a shared edge or inside a "
            "vertex's tangent cone included; rays without contact count here too), a **touching** contact meets the "
            "surface and stays on one side (a silhouette vertex or edge, a boundary edge, a ray in a face's plane, a "
            "tangent sphere), an **on-surface** ray starts on a surface; **ill-conditioned** rays are those whose exact "
            "answer changes when the ray moves by a few ulps: every touching and on-surface ray, and rays within the "
            "float error scale of a contour or of their start (the criterion is stated in "
            "`lib/accel/exact/contact_classes.h`), so the last column includes the two before it, and the crossing "
            "column counts well-conditioned crossings only. Each cell: mismatches of all the cases above, with the rays "
            "of the class in the header. The accuracy statements (`raylab accels`) bound each class; "
            "robustness_classes.csv has this table's rows, with each bound, and robustness.csv the same columns per "
            "case.\n\n";
      md += "| accelerator | rule " + rows[specs.front()].header() + "\n|---|---|---|---|---|---|\n";
      for (const auto& s : specs)
        md += fmt::format("| `{}` | {} |", s, accuracy_bound(s).exact ? "exact" : "tolerance") + rows[s].cells() + "\n";
    }

    // Non-finite rays: a defined "no hit", at no more than the cost of a valid ray.
    {
      const auto scene = make_scene(opt.full() ? "sphere:n=100000" : "sphere:n=20000");
      const auto valid = make_ray_set(opt.full() ? "lines:200000" : "lines:50000", scene);
      std::vector<Ray> invalid = valid, mixed = valid;
      const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
      for (std::size_t i = 0; i < invalid.size(); ++i) {
        Ray& r = invalid[i];
        switch (i % 4) {
          case 0: r.org.x = nan; break;
          case 1: r.dir.y = inf; break;
          case 2: r.tmax = nan; break;
          default: r.dir = Vec3f(0.0f); break;
        }
        if (i % 2) mixed[i] = r;
      }
      CsvWriter nf(opt.out + "/robustness_nonfinite.csv",
                   {"accel", "rays", "ns_valid", "ns_invalid", "ns_mixed", "ratio_invalid", "ratio_mixed", "invalid_hits",
                    "ns_valid_lo", "ns_valid_hi", "ratio_invalid_lo", "ratio_invalid_hi", "ratio_mixed_lo",
                    "ratio_mixed_hi", "rounds", "ns_invalid_lo", "ns_invalid_hi", "ns_mixed_lo", "ns_mixed_hi"});
      const int rounds = opt.full() ? 2 * kNonFiniteRounds : kNonFiniteRounds;
      md += fmt::format("\n### Non-finite rays\n\n{} random lines on `{}`; then the same rays with a NaN origin, an "
                        "infinite direction, a NaN tmax or a zero direction (invalid), and half of them invalid "
                        "(mixed). Single-thread ns per ray (the tracing thread's CPU time), medians over {} alternated "
                        "rounds that trace the valid, invalid and mixed rays in turn; ratios are taken per round, with "
                        "95% bootstrap intervals in brackets. The claim is no slowdown beyond 2.5×.\n\n",
                        valid.size(), scene->spec, rounds);
      md += "| accelerator | valid ns/ray [95%] | invalid ns/ray [95%] | mixed ns/ray [95%] | invalid / valid [95%] | "
            "mixed / valid [95%] "
            "| rounds | hits on invalid rays |\n|---|---|---|---|---|---|---|---|\n";
      for (const auto& spec : specs) {
        if (spec.rfind("brute", 0) == 0) continue;  // |rays| x |triangles|: too slow to time here
        const auto accel = make_accelerator(spec, scene, model_build_context());
        const auto trace = [&accel](const std::vector<Ray>* rays) {
          return [&accel, rays] {
            return trace_rays(*accel, *rays, TraceOptions{1, false, false}).thread_cpu_seconds /
                   static_cast<double>(rays->size()) * 1e9;
          };
        };
        const auto ns = alternate_rounds({trace(&valid), trace(&invalid), trace(&mixed)}, rounds);
        std::vector<double> invalid_ratio, mixed_ratio;
        for (int r = 0; r < rounds; ++r) {
          invalid_ratio.push_back(ns[1][r] / ns[0][r]);
          mixed_ratio.push_back(ns[2][r] / ns[0][r]);
        }
        const IntervalEstimate a = bootstrap_median(ns[0]), bi = bootstrap_median(invalid_ratio),
                               mi = bootstrap_median(mixed_ratio);
        const IntervalEstimate b = bootstrap_median(ns[1]), m = bootstrap_median(ns[2]);
        const std::size_t hits = trace_rays(*accel, invalid, TraceOptions{1, false, false}).hit_count;
        nf.row(spec, valid.size(), a.value, b.value, m.value, bi.value, mi.value, hits, a.lo, a.hi, bi.lo, bi.hi, mi.lo,
               mi.hi, rounds, b.lo, b.hi, m.lo, m.hi);
        md += fmt::format("| `{}` | {} | {} | {} | {} | {} | {} | {} |\n", spec, format_interval(a, 3),
                          format_interval(b, 3), format_interval(m, 3), format_interval(bi), format_interval(mi),
                          rounds, hits);
      }
    }

    // Memory per triangle, next to Embree's.
    {
      // Quick mode: the bunny decimated to 16000 triangles (every structure is built once here; at
      // its 75k triangles the BSP trees and exact-placement grids take seconds each).
      std::shared_ptr<const Scene> scene;
      try {
        scene = make_scene(opt.full() ? "cgal:bunny00" : "decimated:of=cgal:bunny00,faces=16000");
      } catch (const InputError&) {
        scene = make_scene("sphere:n=70000");
      }
      CsvWriter mem(opt.out + "/robustness_memory.csv", {"accel", "triangles", "bytes", "bytes_per_triangle", "build_s",
                                                          "build_s_lo", "build_s_hi", "rounds"});
      md += fmt::format("\n### Memory per triangle\n\nAcceleration structure only (not the scene's vertices and "
                        "indices), on `{}` ({} triangles); Embree's is counted by its memory monitor callback. "
                        "0 means the method keeps no structure of its own. Build seconds (wall clock, every thread): "
                        "the median of {} builds with its 95% bootstrap interval.\n\n| accelerator | bytes | bytes per "
                        "triangle | build s [95%] | rounds |\n|---|---|---|---|---|\n",
                        scene->spec, scene->mesh.size(), kMemoryBuildRounds);
      for (const auto& spec : specs) {
        std::vector<double> build_s;
        std::size_t bytes = 0;
        for (int r = 0; r < kMemoryBuildRounds; ++r) {
          std::unique_ptr<Aggregate> accel;
          build_s.push_back(seconds_of([&] { accel = make_accelerator(spec, scene, model_build_context()); }));
          bytes = accel->stats().bytes;
        }
        const IntervalEstimate build = bootstrap_median(build_s);
        const double per = static_cast<double>(bytes) / static_cast<double>(scene->mesh.size());
        mem.row(spec, scene->mesh.size(), bytes, per, build.value, build.lo, build.hi, kMemoryBuildRounds);
        md += fmt::format("| `{}` | {} | {:.1f} | {} | {} |\n", spec, bytes, per, format_interval(build, 3),
                          kMemoryBuildRounds);
      }
    }
    md += fmt::format("\nPer-case counts: robustness.csv (also any-hit mismatches, per class); robustness_classes.csv; "
                      "robustness_nonfinite.csv; robustness_memory.csv. "
                      "Measured by `build/experiments/exp_robustness --mode {}` (run by `./lab report`). {}.\n",
                      opt.mode, provenance());
    std::ofstream(opt.out + "/robustness.md") << md;
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_robustness: error: " << e.what() << "\n";
    return 2;
  }
}
