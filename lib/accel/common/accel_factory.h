#pragma once
/// The one factory: an accelerator from a spec `NAME[:key=value,...]` (geometry/spec_string.h),
/// e.g. `embree:quality=high` or `brute:kernel=mt`. Unknown names and unknown or malformed
/// parameters throw InputError listing the valid ones. Every accelerator registered here is run
/// by the oracle test suite (tests/test_oracle.cpp) on every scene and ray kind it lists.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geometry/spec_string.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// How closely an accelerator agrees with the exact oracle, in the sense of compare_hits
/// (hit_comparison.h): at most `max_mismatch_rate` of the rays mismatch. Exact or watertight
/// methods state 0; inexact ones (Embree's default mode, Möller-Trumbore) state their bound
/// for rays aimed at edges and vertices, where they fail, and for all other rays.
struct AccuracyBound {
  double max_mismatch_rate_features = 0.0;  ///< `edges:` and `vertices:` rays
  double max_mismatch_rate_other = 0.0;     ///< every other ray kind
  std::string statement;                    ///< one sentence for listings and the report
};

struct AccelKind {
  std::string name;
  std::string summary;
  std::vector<ParamDoc> params;
  /// Builds the accelerator on `scene`, reading its parameters from `reader` (the factory calls
  /// reader.finish(params) afterwards).
  std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>, SpecReader&)> build;
  /// The accuracy the oracle suite holds this accelerator to, given its parameters.
  std::function<AccuracyBound(SpecReader&)> accuracy;
  /// Parameter settings the oracle suite runs besides the defaults, e.g. {"kernel=mt"}.
  std::vector<std::string> oracle_variants = {};
};

/// Every accelerator the lab knows, in listing order.
const std::vector<AccelKind>& accelerator_kinds();

/// Looks up `name`; throws InputError listing the valid names.
const AccelKind& find_accelerator_kind(const std::string& name);

/// Builds the accelerator described by `spec` on `scene`; throws InputError for bad specs.
std::unique_ptr<Aggregate> make_accelerator(const std::string& spec, std::shared_ptr<const Scene> scene);

/// The accuracy bound for `spec`.
AccuracyBound accuracy_bound(const std::string& spec);

}  // namespace raylab
