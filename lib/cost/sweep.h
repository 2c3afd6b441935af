#pragma once
/// `raylab sweep`: the cost model's data set. A plan is a JSON file
///
///   {"scenes": [SPEC, ...], "accels": [SPEC, ...], "rays": [SPEC, ...], "description": "..."}
///
/// of the lab's spec strings; its cases are the product scenes × accels × rays, numbered in that
/// order from 0 (case = (s·|accels| + a)·|rays| + r). `quick` and `full` name the plans shipped in
/// data/plans/; any other name is a path. A shard K/N runs the cases whose number is K mod N, so
/// shards can run on separate machines and their rows, sorted by case, equal one whole run.
///
/// Every case becomes one RunRecord (run_record.h): the structure is built once per (scene,
/// accel), its features computed (tree_features.h), then for each ray set it is timed against
/// Embree (timing.h) and traced once more with counters. Rows are appended and flushed as
/// they finish, so an interrupted sweep resumes (`resume`) without losing a finished row.
#include <cstdint>
#include <functional>
#include <memory>
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
};

struct SweepPlan {
  std::string source;  ///< the plan's name or path, for messages
  std::vector<std::string> scenes, accels, rays;

  std::int64_t case_count() const;
  SweepCase case_at(std::int64_t number) const;
};

/// Loads and validates a plan: `quick`, `full`, or a path. Throws InputError naming the file and
/// the key (or JSON line and column) for a missing file, malformed JSON, an unknown key, an empty
/// or non-string list, a repeated spec, or a spec the lab does not know (accelerators must have
/// tree features: no Embree, no exact oracle).
SweepPlan load_plan(const std::string& name_or_path);

/// The path `load_plan` reads for `name_or_path`.
std::string plan_path(const std::string& name_or_path);

/// Throws InputError (prefixed by `where`) unless `row` is a case of `plan` with the plan's key
/// (scene, accel, rays) for its case number: how a resumed sweep and a merge know a row is theirs.
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
  double build_s = 0;
  TreeFeatures features;
};

/// Builds `accel_spec` on `scene` in an arena of `threads` threads and reads its features.
BuiltStructure build_structure(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene, int threads);

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
  std::function<void(const std::string&)> progress;  ///< one line per finished case
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
