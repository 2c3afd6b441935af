#include "cost/cost_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/input_error.h"

#include <string>

namespace raylab {
namespace {

double incoherent(const RunRecord& r) { return ray_kind_incoherent(r.ray_kind) ? 1.0 : 0.0; }
double any_hit(const RunRecord& r) { return r.any_hit() ? 1.0 : 0.0; }
/// How many times the structure outgrows the per-core cache, on a log scale: 0 while it fits.
double cache_doublings(const RunRecord& r) {
  if (r.l2_bytes <= 0 || r.bytes <= r.l2_bytes) return 0.0;
  return std::log2(static_cast<double>(r.bytes) / static_cast<double>(r.l2_bytes));
}

const std::vector<CostTerm> kCounterTerms = {
    {"c0", "1 per ray: ray setup and the root box", false, [](const RunRecord&) { return 1.0; }},
    {"node", "interior nodes (grid cells) visited per ray", true, [](const RunRecord& r) { return r.nodes_per_ray; }},
    {"leaf", "leaves (non-empty cells) visited per ray", false, [](const RunRecord& r) { return r.leaves_per_ray; }},
    {"test", "primitive tests per ray", true, [](const RunRecord& r) { return r.tests_per_ray; }},
    {"hit", "tests that found a closer hit, per ray", false, [](const RunRecord& r) { return r.hits_per_ray; }},
    {"mailbox", "tests a mailbox skipped, per ray", false, [](const RunRecord& r) { return r.mailbox_skips_per_ray; }},
    {"node_incoherent", "interior nodes per ray of incoherent ray kinds (all but primary)", false,
     [](const RunRecord& r) { return r.nodes_per_ray * incoherent(r); }},
    {"node_memory", "interior nodes per ray times log2(structure bytes / L2 bytes) when it exceeds L2", false,
     [](const RunRecord& r) { return r.nodes_per_ray * cache_doublings(r); }},
    {"occluded", "1 per any-hit (occluded) query", false, any_hit},
};

/// The tree level's ray classes: how rays meet a structure differs most between them (measured
/// visits over the surface-area expectation, quick plan: about 0.25 for camera rays, 0.5-1 for
/// bounces, 0.3-0.9 for any-hit rays), so each has its own constants.
double ray_class_is(const RunRecord& r, const char* c) { return std::string(ray_class_of(r.ray_kind)) == c ? 1.0 : 0.0; }

#define RAYLAB_TREE_CLASS_TERMS(C, WHO)                                                                       \
  {"inner_" C, "Σ SA(interior)/SA(root), for " WHO, true,                                                   \
   [](const RunRecord& r) { return r.e_inner * ray_class_is(r, C); }},                                      \
      {"leaf_" C, "Σ SA(leaf)/SA(root) over non-empty leaves, for " WHO, false,                             \
       [](const RunRecord& r) { return r.e_leaves * ray_class_is(r, C); }},                                 \
      {"test_" C, "Σ N(leaf)·SA(leaf)/SA(root), for " WHO, true,                                            \
       [](const RunRecord& r) { return r.e_tests * ray_class_is(r, C); }}

const std::vector<CostTerm> kTreeTerms = {
    {"c0", "1 per ray", false, [](const RunRecord&) { return 1.0; }},
    RAYLAB_TREE_CLASS_TERMS("camera", "camera rays (primary; edges, vertices, file)"),
    RAYLAB_TREE_CLASS_TERMS("bounce", "rays from surfaces, closest hit (diffuse)"),
    RAYLAB_TREE_CLASS_TERMS("occlusion", "rays from surfaces, any hit (shadow, ao)"),
    RAYLAB_TREE_CLASS_TERMS("lines", "isotropic lines (lines)"),
    {"test_groups", "Σ ⌈N(leaf)/4⌉·SA(leaf)/SA(root): tests in SIMD groups of 4 (packets of wide BVHs)", false,
     [](const RunRecord& r) { return r.e_test_groups; }},
    {"epo", "end-point overlap at 1:1 weights (Aila, Karras and Laine 2013)", false,
     [](const RunRecord& r) { return r.epo; }},
    {"inner_memory", "Σ SA(interior)/SA(root) times log2(structure bytes / L2 bytes) when it exceeds L2", false,
     [](const RunRecord& r) { return r.e_inner * cache_doublings(r); }},
};

#undef RAYLAB_TREE_CLASS_TERMS

}  // namespace

const char* level_name(ModelLevel level) { return level == ModelLevel::counters ? "counters" : "tree"; }

const std::vector<CostTerm>& cost_terms(ModelLevel level) {
  return level == ModelLevel::counters ? kCounterTerms : kTreeTerms;
}

const CostTerm& find_cost_term(ModelLevel level, const std::string& name) {
  std::string valid;
  for (const CostTerm& t : cost_terms(level)) {
    if (t.name == name) return t;
    valid += (valid.empty() ? "" : ", ") + t.name;
  }
  throw InputError(std::string("unknown ") + level_name(level) + " term '" + name + "' (valid: " + valid + ")");
}

std::vector<double> feature_row(ModelLevel level, const std::vector<std::string>& terms, const RunRecord& run) {
  std::vector<double> row;
  row.reserve(terms.size());
  for (const std::string& name : terms) row.push_back(find_cost_term(level, name).feature(run));
  return row;
}

double FittedCostModel::predict(const RunRecord& run) const {
  double ns = 0;
  for (std::size_t j = 0; j < terms.size(); ++j) ns += values[j] * find_cost_term(level, terms[j]).feature(run);
  return ns;
}

double FittedCostModel::parameter_log_variance(const RunRecord& run) const {
  const double ns = predict(run);
  if (!(ns > 0)) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t k = terms.size();
  if (covariance.size() != k * k) return 0.0;
  const std::vector<double> x = feature_row(level, terms, run);
  double variance = 0;
  for (std::size_t i = 0; i < k; ++i)
    for (std::size_t j = 0; j < k; ++j) variance += x[i] * covariance[i * k + j] * x[j];
  return std::max(variance, 0.0) / (ns * ns);
}

IntervalPrediction FittedCostModel::predict_interval(const RunRecord& run, double replicate_log_sigma,
                                                     double widening) const {
  const double noise = std::isfinite(replicate_log_sigma) ? std::max(residual_log_sigma, replicate_log_sigma)
                                                          : residual_log_sigma;
  const double parameter = parameter_log_variance(run);
  return log_normal_interval90(predict(run), std::sqrt(parameter + noise * noise), widening);
}

double range_widening(double factor) { return factor > 1.0 ? 1.0 + std::log2(factor) : 1.0; }

IntervalPrediction log_normal_interval90(double predicted, double log_sigma, double widening) {
  IntervalPrediction p;
  p.ns = predicted;
  p.widening = widening;
  if (!(predicted > 0) || !std::isfinite(log_sigma) || log_sigma < 0 || !(widening >= 1.0)) return p;
  p.log_sigma = log_sigma;
  const double half = kZ90 * log_sigma * widening;
  p.lo = predicted * std::exp(-half);
  p.hi = predicted * std::exp(half);
  return p;
}

double FittedCostModel::value_of(const std::string& name) const {
  const auto it = std::find(terms.begin(), terms.end(), name);
  return it == terms.end() ? 0.0 : values[static_cast<std::size_t>(it - terms.begin())];
}

bool FittedCostModel::has(const std::string& name) const {
  return std::find(terms.begin(), terms.end(), name) != terms.end();
}

}  // namespace raylab
