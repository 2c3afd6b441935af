#pragma once
/// `raylab sweep`: the cost model's data set. A plan is a JSON file
///
///   {"description": "...",
///    "scenes": [SPEC | {"scene": SPEC, "accels": [SPEC, ...] | K}, ...],
///    "accels": [SPEC, ...],
///    "rays": [SPEC, ...],
///    "accels_per_scene": K,                          (optional; default: every accel)
///    "sample_seed": S,                               (optional; default 1)
///    "replicates": {"fraction": F, "repeats": R},    (optional; default: none)
///    "seconds_per_case": T}                          (optional; default: SweepOptions::timing's, 0.1 s)
///
/// of the lab's spec strings. Every key but scenes, accels and rays is optional, so a plan of
/// plain lists (the first format) reads as before, with the same case numbers.
///
/// Which accelerators run on a scene: a scene object's "accels" list (each one of the plan's
/// accels), or a sample of K of the plan's accels (K from the scene object's "accels": K, else
/// the plan's "accels_per_scene"), else all of them. The sample is stratified by structure family
/// and deterministic: within a family, accels are ranked by the FNV-1a 64 hash of
/// "S|scene|accel"; families are ranked by their best accel; the sample takes the first of each
/// family in that order, then the second of each, ... until it has K. A scene's accels run in the
/// plan's order.
///
/// Cases: the primary cases are scenes × (their accels) × rays, numbered from 0 in that order
/// (rays fastest; with every accel on every scene, case = (s·|accels| + a)·|rays| + r). Then the
/// replicates: a deterministic set of ⌈F·P⌉ of the P primary cases, evenly spaced over them
/// (case ⌊(j + ½)·P/n⌋, j < n), plus the first case of any structure family or scene family the
/// spacing missed, is measured R more times. Replicate k (1..R) of the i-th replicated case is case
/// P + (k−1)·n' + i (n' replicated cases): it has its own number and the same (scene, accel,
/// rays), so it runs after every primary case, on a structure built again, and under a shard count
/// N it usually runs in another shard's process than its first measurement.
///
/// `quick` and `full` name the plans shipped in data/plans/; any other name is a path. A shard K/N
/// runs the cases whose number is K mod N, so shards can run on separate machines and their rows,
/// sorted by case, equal one whole run.
///
/// Every case becomes one RunRecord (run_record.h): the structure is built once per (scene,
/// accel) and per replicate, its features computed (tree_features.h), then for each ray set it is
/// timed against Embree (timing.h) and traced once more with counters. Rows are appended and
/// flushed as they finish, so an interrupted sweep resumes (`resume`) without losing a finished
/// row.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cost/run_record.h"
#include "cost/timing.h"
#include "cost/tree_features.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

struct SweepCase {
  std::int64_t number = 0;
  std::string scene, accel, rays;
  std::int64_t replicate = 0;     ///< 0: the first measurement; k: its k-th repeat
  std::int64_t first_case = -1;   ///< a replicate's primary case number (-1 for primary cases)
};

struct SweepPlan {
  std::string source;  ///< the plan's name or path, for messages
  std::vector<std::string> scenes, accels, rays;
  /// Per scene, the indices into `accels` it runs, ascending; a scene without an entry (the list
  /// is shorter, or the entry is empty) runs every accel.
  std::vector<std::vector<std::size_t>> scene_accels;
  /// The primary case numbers measured again, ascending, each `replicate_repeats` times.
  std::vector<std::int64_t> replicated;
  std::int64_t replicate_repeats = 1;
  /// When set, each case's passes run until ours have taken this long in total, at least
  /// TimingOptions::min_passes of them (TimingOptions::min_seconds; unset: the sweep's options').
  std::optional<double> seconds_per_case;

  /// The accels of scene `s`, as indices into `accels`.
  std::vector<std::size_t> accels_of(std::size_t s) const;
  std::int64_t primary_case_count() const;
  std::int64_t case_count() const;
  /// Throws std::out_of_range outside [0, case_count()).
  SweepCase case_at(std::int64_t number) const;
  /// "N cases = S scenes x A accels x R rays", with "a..b of A accels" when scenes run samples
  /// and " + M replicates" when the plan has them.
  std::string describe() const;
};

/// The deterministic, family-stratified sample of `count` of `accels` for `scene` (see above).
std::vector<std::size_t> sample_accels(const std::vector<std::string>& accels, const std::string& scene,
                                       std::size_t count, std::uint64_t seed);

/// The primary cases a plan with replicate fraction `fraction` measures again (see above), for
/// the plan's scenes, accels and rays as set.
std::vector<std::int64_t> replicated_cases(const SweepPlan& plan, double fraction);

/// Loads and validates a plan: `quick`, `full`, or a path. Throws InputError naming the file and
/// the key (or JSON line and column) for a missing file, malformed JSON, an unknown key (also in a
/// scene object or in "replicates"), an empty or non-string list, a repeated spec, a spec the lab
/// does not know (accelerators must have tree features: no Embree, no exact oracle), a scene's
/// accel that is not one of the plan's, or a count or fraction out of range.
SweepPlan load_plan(const std::string& name_or_path);

/// The path `load_plan` reads for `name_or_path`.
std::string plan_path(const std::string& name_or_path);

/// Throws InputError (prefixed by `where`) unless `row` is a case of `plan` with the plan's key
/// (scene, accel, rays) and replicate index for its case number: how a resumed sweep and a merge
/// know a row is theirs.
void check_row_in_plan(const SweepPlan& plan, const RunRecord& row, const std::string& where);

struct ShardSpec {
  std::int64_t index = 0, count = 1;
  bool contains(std::int64_t case_number) const { return case_number % count == index; }
};

/// Parses "K/N" with 0 <= K < N; throws InputError otherwise.
ShardSpec parse_shard(const std::string& text);

/// A structure built for measurement: the accelerator, its build time and its features.
struct BuiltStructure {
  std::unique_ptr<Aggregate> accel;
  double build_s = 0;      ///< the fastest of build_passes builds
  double build_s_max = 0;  ///< the slowest ([build_s, build_s_max]: the builds' range)
  int build_passes = 1;
  TreeFeatures features;
};

/// The builds a sweep times per structure: up to kSweepBuildPasses, fewer once they total
/// kSweepBuildSeconds, but never fewer than two. A process's first build of a large scene writes
/// memory it has never touched, and its page faults vary from process to process: in
/// docs/results/cost_runs.csv at 1d92509, which timed such scenes once, the `build_s` of replicate
/// 1 differed from replicate 0's by 25% (mean of the 4 pairs built once) against 9% (57 pairs built
/// three times).
inline constexpr int kSweepBuildPasses = 3;
inline constexpr double kSweepBuildSeconds = 0.5;

/// Builds `accel_spec` on `scene` in an arena of `threads` threads, up to `max_passes` times
/// (fewer once the builds total `max_seconds`, but at least two when `max_passes` allows; each
/// build freed before the next, so no two are held at once), keeps the last and reads its features.
BuiltStructure build_structure(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene, int threads,
                               int max_passes = 1, double max_seconds = 0);

/// Measures one case: times `built` against `embree` on `rays` (time_alternating), counts a
/// separate pass, and fills every column of the row. `sweep` and `predict --measure` both time
/// through here.
RunRecord measure_case(const SweepCase& c, const Scene& scene, const BuiltStructure& built, const Aggregate& embree,
                       const std::vector<Ray>& rays, const TimingOptions& timing);

struct SweepOptions {
  std::string out;     ///< the runs CSV
  ShardSpec shard;
  bool resume = false;  ///< continue `out`, skipping its cases; without it an existing `out` is an error
  int threads = 1;
  TimingOptions timing;
  /// One line per finished case: its number, times, the elapsed time and an estimate of the rest.
  std::function<void(const std::string&)> progress;
};

struct SweepSummary {
  std::int64_t measured = 0;  ///< cases run now
  std::int64_t skipped = 0;   ///< cases found in `out` already (resume)
};

/// Runs the plan's cases of one shard into `options.out`. Throws InputError for bad options (an
/// existing `out` without resume, a resumed file that does not belong to this plan); a file this
/// call created is removed again when no row could be written.
SweepSummary run_sweep(const SweepPlan& plan, const SweepOptions& options);

}  // namespace raylab
