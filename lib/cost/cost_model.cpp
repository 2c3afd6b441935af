#include "cost/cost_model.h"

#include <algorithm>
#include <cmath>

#include "geometry/input_error.h"

namespace raylab {
namespace {

double incoherent(const RunRecord& r) { return ray_kind_incoherent(r.ray_kind) ? 1.0 : 0.0; }
double inside(const RunRecord& r) { return ray_kind_starts_inside(r.ray_kind) ? 1.0 : 0.0; }
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

const std::vector<CostTerm> kTreeTerms = {
    {"c0", "1 per ray", false, [](const RunRecord&) { return 1.0; }},
    {"inner", "Σ SA(interior)/SA(root): expected interior visits", true, [](const RunRecord& r) { return r.e_inner; }},
    {"leaf", "Σ SA(leaf)/SA(root) over non-empty leaves", false, [](const RunRecord& r) { return r.e_leaves; }},
    {"test", "Σ N(leaf)·SA(leaf)/SA(root): expected tests", true, [](const RunRecord& r) { return r.e_tests; }},
    {"test_groups", "Σ ⌈N(leaf)/4⌉·SA(leaf)/SA(root): tests in SIMD groups of 4", false,
     [](const RunRecord& r) { return r.e_test_groups; }},
    {"epo", "end-point overlap at 1:1 weights (Aila, Karras and Laine 2013)", false,
     [](const RunRecord& r) { return r.epo; }},
    {"inside_inner", "expected interior visits, for rays starting on surfaces (diffuse, shadow, ao)", false,
     [](const RunRecord& r) { return r.e_inner * inside(r); }},
    {"inside_test", "expected tests, for rays starting on surfaces", false,
     [](const RunRecord& r) { return r.e_tests * inside(r); }},
    {"occluded_test", "expected tests, for any-hit queries (which stop at the first hit)", false,
     [](const RunRecord& r) { return r.e_tests * any_hit(r); }},
    {"incoherent_inner", "expected interior visits, for incoherent ray kinds", false,
     [](const RunRecord& r) { return r.e_inner * incoherent(r); }},
    {"inner_memory", "expected interior visits times log2(structure bytes / L2 bytes) when it exceeds L2", false,
     [](const RunRecord& r) { return r.e_inner * cache_doublings(r); }},
};

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

double FittedCostModel::value_of(const std::string& name) const {
  const auto it = std::find(terms.begin(), terms.end(), name);
  return it == terms.end() ? 0.0 : values[static_cast<std::size_t>(it - terms.begin())];
}

bool FittedCostModel::has(const std::string& name) const {
  return std::find(terms.begin(), terms.end(), name) != terms.end();
}

}  // namespace raylab
