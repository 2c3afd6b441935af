#pragma once
/// The cost model: ns per ray as a sum of named terms, each a feature of a run times a
/// non-negative constant (nanoseconds per event), fitted per structure family (fit.h).
///
/// Two levels (the lecture's Cost(node) = C_trav + P(L)·Cost(L) + P(R)·Cost(R), measured):
///  - `counters`: time from the measured counters of a traced pass (the machine constants):
///      ns/ray = c0 + c_node·nodes + c_leaf·leaves + c_test·tests [+ corrections];
///    c_node : c_test is the lecture's C_trav : C_isect, measured.
///  - `tree`: time from the structure alone (what a builder can use): the same form on the
///    surface-area expectations of tree_features.h, with correction terms (end-point overlap,
///    SIMD leaf granularity, memory, rays that start inside the scene or stop at any hit).
///
/// The candidate terms of a level are one list; a model is a subset of it that keeps the
/// level's required terms, so model selection (model_selection.h) is a loop over subsets.
#include <string>
#include <vector>

#include "cost/run_record.h"

namespace raylab {

enum class ModelLevel { counters, tree };

const char* level_name(ModelLevel level);

struct CostTerm {
  std::string name;
  std::string meaning;  ///< what the feature counts, for listings and model.json
  bool required = false;  ///< kept by model selection (the lecture's two constants)
  double (*feature)(const RunRecord&) = nullptr;
};

/// The candidate terms of a level, in listing order.
const std::vector<CostTerm>& cost_terms(ModelLevel level);

/// The term named `name` of `level`; throws InputError naming the valid ones.
const CostTerm& find_cost_term(ModelLevel level, const std::string& name);

/// The feature row of `terms` (names of `level`) for one run.
std::vector<double> feature_row(ModelLevel level, const std::vector<std::string>& terms, const RunRecord& run);

/// A fitted model of one level for one structure family.
struct FittedCostModel {
  ModelLevel level = ModelLevel::counters;
  std::vector<std::string> terms;
  std::vector<double> values;      ///< ns per unit of each term's feature
  std::vector<double> std_errors;  ///< NaN where unknown

  double predict(const RunRecord& run) const;
  /// The value of term `name`, 0 when the model does not have it.
  double value_of(const std::string& name) const;
  bool has(const std::string& name) const;
};

}  // namespace raylab
