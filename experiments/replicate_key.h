#pragma once
/// A key number (experiment_common.h) from replicated measurements (lib/cost/replicates.h).
#include <string>
#include <utility>

#include "cost/replicates.h"
#include "experiment_common.h"

namespace raylab::experiments {

/// How every replicated key number's interval is obtained.
inline constexpr const char* kBootstrapIntervalText =
    "95% percentile bootstrap over the replicate rounds (2000 resamples, fixed seed)";

/// The key number `name` = `i`, produced by `spec`; `how` says what was resampled (default: the rounds).
inline KeyNumber replicated_key(std::string name, const IntervalEstimate& i, std::string spec,
                                std::string how = kBootstrapIntervalText) {
  KeyNumber k;
  k.name = std::move(name);
  k.value = i.value;
  k.lo = i.lo;
  k.hi = i.hi;
  k.replicates = i.replicates;
  k.spec = std::move(spec);
  k.interval = std::move(how);
  return k;
}

}  // namespace raylab::experiments
