#pragma once
/// Accelerator specs a benchmark binary takes from the environment, checked before any benchmark
/// runs (the benchmarks themselves would end on an uncaught InputError).
#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
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

/// The ';'-separated items of $`variable`, each passed to `check` (which throws InputError for an
/// item it rejects), or `fallback` when the variable is unset or empty. A list of no items or a
/// rejected item ends the program with one `error:` line naming the variable, and exit status 2.
template <class Check>
std::vector<std::string> checked_list_from_env(const char* variable, std::vector<std::string> fallback,
                                               const std::string& item, Check&& check) {
  const std::optional<std::vector<std::string>> listed = list_from_env(variable);
  if (!listed) return fallback;
  try {
    if (listed->empty()) throw InputError("no " + item);
    for (const auto& spec : *listed) check(spec);
  } catch (const InputError& e) {
    std::cerr << "error: $" << variable << ": " << e.what() << "\n";
    std::exit(2);
  }
  return *listed;
}

/// The scene specs of $`variable` (checked_list_from_env), each made up front through `make`.
template <class MakeScene>
std::vector<std::string> scene_specs_from_env(const char* variable, std::vector<std::string> fallback,
                                              MakeScene&& make) {
  return checked_list_from_env(variable, std::move(fallback), "scene spec", make);
}

/// The accelerator specs of $`variable` (checked_list_from_env), each built once over a 20-triangle
/// sphere first.
inline std::vector<std::string> accelerator_specs_from_env(const char* variable, std::vector<std::string> fallback) {
  std::shared_ptr<const Scene> probe;
  // cost= models are read and checked, but the probe's size is not held to their fitted range.
  const BuildContext context = model_build_context(/*warn_outside_range=*/false);
  return checked_list_from_env(variable, std::move(fallback), "accelerator spec", [&](const std::string& spec) {
    if (!probe) probe = make_scene("sphere:n=20");
    make_accelerator(spec, probe, context);
  });
}

}  // namespace raylab
