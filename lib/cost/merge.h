#pragma once
/// `raylab merge`: the shards of a sweep (sweep.h, `--shard K/N`, run on one machine or as a Slurm
/// array job) into one data set. Every row of every shard file is checked against the plan's key
/// for its case number; the data set is written only when every case of the plan is there exactly
/// once, sorted by case, so that it equals one unsharded run row for row (timings aside).
///
/// Beside the data set OUT the merge writes OUT.sweep.json: the plan, the shard files and their
/// rows, the hosts and CPU models of the rows, and how the shards were run (`note`: Slurm job ids,
/// or how many local shards ran at a time, since concurrent shards disturb each other's timings).
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "cost/run_record.h"
#include "cost/sweep.h"
#include "geometry/input_error.h"

namespace raylab {

struct MergeOptions {
  /// The shards' runs CSVs. A file that does not exist is a shard that wrote no row (cancelled
  /// before it started): its cases are reported missing, not an error of its own.
  std::vector<std::string> shard_files;
  std::int64_t shard_count = 0;  ///< N of the shards' K/N, naming the shard of a missing case; 0: one file per shard
  std::string out;               ///< the merged runs CSV; an existing file is refused
  std::string note;              ///< how the shards were run, recorded in the merge record
};

struct ShardFileRows {
  std::string path;
  bool exists = false;
  std::int64_t rows = 0;
  bool torn_tail = false;  ///< the file ended in a half-written row (a shard killed while writing), ignored
};

struct MergeResult {
  std::vector<RunRecord> rows;                     ///< every row read, sorted by case (duplicates included)
  std::vector<ShardFileRows> files;                ///< in the order given
  std::int64_t case_count = 0;                     ///< the plan's
  std::int64_t shard_count = 0;
  std::vector<std::int64_t> missing_cases;         ///< cases of the plan in no file, ascending
  std::vector<std::int64_t> incomplete_shards;     ///< the shards (case mod N) of the missing cases, ascending
  std::map<std::int64_t, std::vector<std::string>> duplicates;  ///< case -> every `file:line` holding it, when more than one

  bool complete() const { return missing_cases.empty() && duplicates.empty(); }
};

/// Reads the shard files and checks every row against `plan` (InputError naming file and line for
/// a malformed row or a row that is not the plan's case). Missing and duplicated cases are
/// reported in the result, not thrown.
MergeResult collect_shards(const SweepPlan& plan, const std::vector<std::string>& shard_files,
                           std::int64_t shard_count = 0);

/// One line saying which cases are missing or duplicated, and in which shards or files.
std::string describe_incomplete(const MergeResult& result);

/// Thrown by merge_shards when cases are missing or duplicated; nothing was written.
class IncompleteMerge : public InputError {
 public:
  explicit IncompleteMerge(MergeResult r) : InputError(describe_incomplete(r)), result(std::move(r)) {}
  MergeResult result;
};

/// The merge record written beside a merged data set.
std::string merge_record_path(const std::string& out);

/// Collects the shards and, when every case is there once, writes `options.out` (header, then the
/// rows sorted by case) and its merge record, each atomically (temporary file, then rename); the
/// record is removed again if the data set cannot be written. Throws IncompleteMerge otherwise, and
/// InputError for bad input (an existing `out`, a bad shard file, a shard count below 1); either
/// way nothing is left under `out`.
MergeResult merge_shards(const SweepPlan& plan, const MergeOptions& options);

}  // namespace raylab
