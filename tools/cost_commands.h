#pragma once
/// The cost-model commands of the `raylab` tool: `sweep` (the data set), `merge` (a sharded
/// sweep's files into one data set), `fit` (the model) and `predict` (a model's prediction,
/// optionally against a measurement). Each returns the exit status; bad input throws InputError
/// (one `raylab: error:` line, exit 2, in main).
#include <cstdint>
#include <string>
#include <vector>

namespace raylab {

struct SweepCommand {
  std::string plan, out, shard = "0/1";
  bool resume = false;
  bool check = false;  ///< validate the plan and print its case count; run nothing
  int threads = 1;
  int passes = 5;
};
int run_sweep_command(const SweepCommand& o);

struct MergeCommand {
  std::string plan, out, note;
  std::vector<std::string> shard_files;
  std::int64_t shards = 0;  ///< N of the shards' K/N; 0: one file per shard
};
/// Exit 0 when merged. When cases are missing it prints `incomplete_shards=K1,K2` on stdout (for
/// the scripts that resubmit those shards) before throwing the one-line error.
int run_merge_command(const MergeCommand& o);

struct FitCommand {
  std::string runs, out;
  double loss_scale = 0.1;
  std::string target = "embree-normalized";
  bool allow_mixed_hardware = false;
  bool json = false;
};
int run_fit_command(const FitCommand& o);

struct PredictCommand {
  std::string model = "default", scene, accel, rays = "primary:16384";
  bool measure = false, json = false;
  bool strict = false;               ///< refuse a run more than kStrictRangeFactor outside the fitted range
  bool allow_extrapolation = false;  ///< accepted for old scripts; predicting outside the range is the default
  int threads = 1;
  int passes = 5;
};
int run_predict_command(const PredictCommand& o);

}  // namespace raylab
