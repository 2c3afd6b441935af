#pragma once
/// Accelerator specs a benchmark binary takes from the environment, checked before any benchmark
/// runs (the benchmarks themselves would end on an uncaught InputError).
#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "accel/common/accel_factory.h"
#include "accel/common/timing_cpu.h"
#include "cost/model_file.h"
#include "geometry/input_error.h"
#include "scene/scene_spec.h"

namespace raylab {

/// $RAYLAB_TIMING_CPU (accel/common/timing_cpu.h), checked when a benchmark binary that includes
/// this header starts: a bad value ends it with one `error:` line and exit status 2.
inline const bool timing_cpu_checked = [] {
  try {
    (void)timing_cpu();
  } catch (const InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    std::exit(2);
  }
  return true;
}();

/// The ';'-separated items of $`variable` (empty items dropped); nullopt when it is unset or empty.
inline std::optional<std::vector<std::string>> list_from_env(const char* variable) {
  const char* env = std::getenv(variable);
  if (env == nullptr || *env == '\0') return std::nullopt;
  std::vector<std::string> items;
  const std::string text(env);
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find(';', start), text.size());
    if (end > start) items.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return items;
}

/// The ';'-separated scene specs in $`variable`, each made up front through `make` (a spec
/// make_scene rejects ends the program with one `error:` line naming the variable, and exit
/// status 2), or `fallback` when it is unset or empty.
template <class MakeScene>
std::vector<std::string> scene_specs_from_env(const char* variable, std::vector<std::string> fallback,
                                              MakeScene&& make) {
  const std::optional<std::vector<std::string>> listed = list_from_env(variable);
  if (!listed) return fallback;
  try {
    if (listed->empty()) throw InputError("no scene spec");
    for (const auto& spec : *listed) make(spec);
  } catch (const InputError& e) {
    std::cerr << "error: $" << variable << ": " << e.what() << "\n";
    std::exit(2);
  }
  return *listed;
}

/// The ';'-separated accelerator specs in $`variable`, or `fallback` when it is unset or empty.
/// Each is built once over a 20-triangle sphere first: a spec the factory rejects ends the program
/// with one `error:` line naming the variable, and exit status 2.
inline std::vector<std::string> accelerator_specs_from_env(const char* variable, std::vector<std::string> fallback) {
  const std::optional<std::vector<std::string>> listed = list_from_env(variable);
  if (!listed) return fallback;
  const std::vector<std::string>& specs = *listed;
  try {
    if (specs.empty()) throw InputError("no accelerator spec");
    const auto probe = make_scene("sphere:n=20");
    // cost= models are read and checked, but the probe's size is not held to their fitted range.
    const BuildContext context = model_build_context(/*warn_outside_range=*/false);
    for (const auto& spec : specs) make_accelerator(spec, probe, context);
  } catch (const InputError& e) {
    std::cerr << "error: $" << variable << ": " << e.what() << "\n";
    std::exit(2);
  }
  return specs;
}

}  // namespace raylab
