// This machine's noise floor, measured first in `./lab report` so that the report opens with it:
// one fixed reference case (`bvh` against `embree` on cgal:bunny00, 65,536 diffuse rays, single
// thread) timed over alternated replicate rounds (lib/cost/replicates.h). The spread of ns/ray and
// of the ratio over the rounds is what any other timing of the same run can be expected to move
// by between reruns. Writes noise_floor.json (read into results.json by make_report.py) and
// noise_floor.md (the fragment the report opens with).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "cost/output_file.h"
#include "cost/replicates.h"
#include "experiment_common.h"
#include "scene/scene_spec.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

constexpr const char* kScene = "cgal:bunny00";
constexpr const char* kRays = "diffuse:65536";
constexpr const char* kOurs = "bvh";
constexpr const char* kTheirs = "embree";

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv, "this machine's noise floor: one reference case over replicate rounds");
  try {
    // One pass of each per round; the rounds are cheap (~10 ms each), so many of them.
    const int rounds = opt.full() ? 40 : 20;
    progress(fmt::format("noise floor: {} against {} on {}, {}, {} rounds", kOurs, kTheirs, kScene, kRays, rounds));
    const auto scene = make_scene(kScene);
    const std::vector<Ray> rays = make_ray_set(kRays, scene);
    const auto ours = make_accelerator(kOurs, scene);
    const auto theirs = make_accelerator(kTheirs, scene);
    ReplicateOptions ro;
    ro.rounds = rounds;
    const ReplicateTiming t = time_replicates({ours.get(), theirs.get()}, rays, ro);
    const IntervalEstimate ns = t.ns_per_ray(0), embree_ns = t.ns_per_ray(1), ratio = t.ratio(1, 0);
    const double cv_ns = coefficient_of_variation(t.ns[0]), cv_embree_ns = coefficient_of_variation(t.ns[1]);
    const double cv_ratio = coefficient_of_variation(t.ratios(1, 0));
    const std::string spec = fmt::format("ours={} theirs={} scene={} rays={} threads=1 timer=thread_cpu "
                                         "rounds={} passes_per_round=1",
                                         canonical_spec(kOurs), canonical_spec(kTheirs), kScene, kRays, rounds);
    const nlohmann::json j = {
        {"spec", spec},  // defaults expanded: a changed default shows up as a changed spec
        {"ours", kOurs},
        {"theirs", kTheirs},
        {"scene", kScene},
        {"rays", kRays},
        {"replicates", t.rounds()},
        {"median_ns", ns.value},
        {"median_ns_ci95", {ns.lo, ns.hi}},
        {"embree_median_ns", embree_ns.value},
        {"embree_median_ns_ci95", {embree_ns.lo, embree_ns.hi}},
        {"ratio", ratio.value},
        {"ratio_definition", "Embree's ns/ray over ours, per round (> 1: ours is faster)"},
        {"ci95", {ratio.lo, ratio.hi}},
        {"interval", "percentile bootstrap of the median over rounds, 2000 resamples, fixed seed"},
        {"cv_ns", cv_ns},
        {"cv_embree_ns", cv_embree_ns},
        {"cv_ratio", cv_ratio},
        {"ns_per_round", t.ns[0]},
        {"embree_ns_per_round", t.ns[1]},
    };
    std::string md = section_anchor("noise-floor") + "## This machine's noise floor\n\n";
    md += fmt::format(
        "Measured at the start of this run: `{}` against `{}` on `{}` with `{}` rays, single thread (CPU time of "
        "the tracing thread), {} alternated rounds of one pass each (`build/experiments/exp_noise_floor --mode {}`). "
        "Intervals are 95% percentile-bootstrap intervals of the median over the rounds (2000 resamples, fixed "
        "seed); every timing of the report is replicated and bounded the same way. The coefficients of variation "
        "say how far one round strays: a timed figure of this report that differs from a rerun's by less than a "
        "few times them is noise.\n\n"
        "| figure | median | 95% interval | rounds | coefficient of variation |\n|---|---|---|---|---|\n"
        "| `{}` ns/ray | {:.1f} | [{:.1f}, {:.1f}] | {} | {:.1f}% |\n"
        "| `{}` ns/ray | {:.1f} | [{:.1f}, {:.1f}] | {} | {:.1f}% |\n"
        "| throughput `{}` / `{}` (Embree's time over ours) | {:.3f} | [{:.3f}, {:.3f}] | {} | {:.1f}% |\n\n"
        "Data: noise_floor.json. {}.\n\n",
        kOurs, kTheirs, kScene, kRays, t.rounds(), opt.mode, kOurs, ns.value, ns.lo, ns.hi, t.rounds(), 100 * cv_ns,
        kTheirs, embree_ns.value, embree_ns.lo, embree_ns.hi, t.rounds(), 100 * cv_embree_ns, kOurs, kTheirs,
        ratio.value, ratio.lo, ratio.hi, t.rounds(), 100 * cv_ratio, provenance());
    write_file_atomically(opt.out + "/noise_floor.json", j.dump(2) + "\n");
    write_file_atomically(opt.out + "/noise_floor.md", md);
    return 0;
  } catch (const InputError& e) {
    std::cerr << "exp_noise_floor: error: " << e.what() << "\n";
    return 2;
  }
}
