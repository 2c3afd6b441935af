#pragma once
/// The cost-model commands of the `raylab` tool: `sweep` (the data set), `fit` (the model) and
/// `predict` (a model's prediction, optionally against a measurement). Each returns the exit
/// status; bad input throws InputError (one `raylab: error:` line, exit 2, in main).
#include <string>

namespace raylab {

struct SweepCommand {
  std::string plan, out, shard = "0/1";
  bool resume = false;
  int threads = 1;
  int passes = 5;
};
int run_sweep_command(const SweepCommand& o);

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
  bool measure = false, json = false, allow_extrapolation = false;
  int threads = 1;
  int passes = 5;
};
int run_predict_command(const PredictCommand& o);

}  // namespace raylab
