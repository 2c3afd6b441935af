// The cost-model layer (lib/cost): Ceres fits recover known constants within their reported
// standard errors, model selection picks the terms that made the data, the data set's CSV and
// the model file round-trip and reject bad input, merged shards of a sweep equal the whole sweep, the
// builders take fitted constants, and `auto` chooses among the lab's structures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <tbb/task_arena.h>

#include "accel/bvh/bvh.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "cost/auto_accel.h"
#include "cost/fit.h"
#include "cost/merge.h"
#include "cost/model_file.h"
#include "cost/model_fit.h"
#include "cost/model_selection.h"
#include "cost/run_record.h"
#include "cost/sweep.h"
#include "cost/tree_features.h"
#include "geometry/input_error.h"
#include "geometry/triangle_clipping.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("raylab_cost_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

/// Runs of one structure family over `scenes` scenes whose time is made by known constants:
/// ns = 20 + 1.5·nodes + 6·leaves + 3·tests + c_hit·hits, times (1 + 2% Gaussian noise).
std::vector<RunRecord> synthetic_runs(double c_hit, std::uint32_t seed, int scenes = 8, int per_scene = 12) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> nodes(5, 60), leaves(1, 10), tests(2, 40), hits(0.2, 3);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<RunRecord> runs;
  for (int s = 0; s < scenes; ++s)
    for (int i = 0; i < per_scene; ++i) {
      RunRecord r;
      r.case_number = static_cast<std::int64_t>(runs.size());
      r.scene = "scene" + std::to_string(s);
      r.scene_family = s % 2 ? "odd" : "even";
      r.accel = "kdtree";
      r.family = "kdtree";
      r.rays = "primary:100";
      r.ray_kind = "primary";
      r.query = "intersect";
      r.nodes_per_ray = nodes(rng);
      r.leaves_per_ray = leaves(rng);
      r.tests_per_ray = tests(rng);
      r.hits_per_ray = hits(rng);
      const double ns = 20 + 1.5 * r.nodes_per_ray + 6 * r.leaves_per_ray + 3 * r.tests_per_ray + c_hit * r.hits_per_ray;
      r.ns_per_ray_min = ns * (1 + noise(rng));
      runs.push_back(r);
    }
  return runs;
}

TEST(CostFit, RecoversKnownConstantsWithinTwoStandardErrors) {
  const std::vector<RunRecord> runs = synthetic_runs(0.0, 7);
  FitResult details;
  const FittedCostModel m = fit_cost_model(ModelLevel::counters, {"c0", "node", "leaf", "test"}, runs, {}, &details);
  EXPECT_TRUE(details.converged) << details.message;
  const double truth[] = {20, 1.5, 6, 3};
  for (std::size_t j = 0; j < 4; ++j) {
    ASSERT_TRUE(std::isfinite(m.std_errors[j])) << m.terms[j];
    EXPECT_GT(m.std_errors[j], 0.0) << m.terms[j];
    EXPECT_LE(std::abs(m.values[j] - truth[j]), 2 * m.std_errors[j])
        << m.terms[j] << " = " << m.values[j] << " ± " << m.std_errors[j] << ", true " << truth[j];
  }
  EXPECT_LT(details.mape, 0.03);
  EXPECT_GT(details.r2, 0.98);
}

TEST(CostFit, RobustLossKeepsOutliersFromPullingTheFit) {
  std::vector<RunRecord> runs = synthetic_runs(0.0, 11);
  for (std::size_t i = 0; i < runs.size(); i += 17) runs[i].ns_per_ray_min *= 3;  // a few disturbed timings
  FitOptions plain;
  plain.loss_scale = 0;
  const FittedCostModel robust = fit_cost_model(ModelLevel::counters, {"c0", "node", "leaf", "test"}, runs, {});
  const FittedCostModel squares = fit_cost_model(ModelLevel::counters, {"c0", "node", "leaf", "test"}, runs, plain);
  EXPECT_LT(std::abs(robust.value_of("test") - 3), std::abs(squares.value_of("test") - 3));
  EXPECT_NEAR(robust.value_of("test"), 3.0, 0.3);
}

TEST(CostFit, PowerLawAndBasisFitsRecoverTheirCurves) {
  std::vector<double> n, y_pow, y_log;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double x = 1024; x <= (1 << 20); x *= 2) {
    n.push_back(x);
    y_pow.push_back(3.0 * std::pow(x, 0.75) * (1 + noise(rng)));
    y_log.push_back((40.0 + 7.0 * std::log2(x)) * (1 + noise(rng)));
  }
  const FitResult p = fit_power_law(n, y_pow);
  EXPECT_LE(std::abs(p.values[1] - 0.75), 2 * p.std_errors[1]) << p.values[1] << " ± " << p.std_errors[1];
  const FitResult l = fit_basis(n, y_log, [](double x) { return std::log2(x); });
  EXPECT_LE(std::abs(l.values[1] - 7.0), 2 * l.std_errors[1]) << l.values[1] << " ± " << l.std_errors[1];
  EXPECT_LE(std::abs(l.values[0] - 40.0), 2 * l.std_errors[0]) << l.values[0] << " ± " << l.std_errors[0];
}

TEST(CostFit, RejectsInputItCannotFit) {
  EXPECT_THROW(fit_linear_terms({}, {}), InputError);
  EXPECT_THROW(fit_linear_terms({{1, 2}}, {3}), InputError);                // fewer points than terms
  EXPECT_THROW(fit_linear_terms({{1}, {2}}, {1, NAN}), InputError);         // non-finite
  EXPECT_THROW(fit_linear_terms({{1}, {2}}, {1, -1}), InputError);          // relative residuals need y > 0
  EXPECT_THROW(fit_power_law({1, 2, 3}, {1, 0, 2}), InputError);
}

TEST(CostModelSelection, KeepsTheTermsThatMadeTheDataAndDropsOneThatDidNot) {
  // Without a hit term in the truth, `hit` lowers no held-out error and is dropped.
  const TermSelection without = select_terms(ModelLevel::counters, synthetic_runs(0.0, 5), {});
  EXPECT_TRUE(without.cross_validated);
  for (const char* t : {"c0", "node", "leaf", "test"})
    EXPECT_NE(std::find(without.terms.begin(), without.terms.end(), t), without.terms.end()) << t;
  EXPECT_EQ(std::find(without.terms.begin(), without.terms.end(), "hit"), without.terms.end());
  EXPECT_NE(std::find(without.dropped.begin(), without.dropped.end(), "hit"), without.dropped.end());
  // Features that are zero on every run are not candidates at all.
  EXPECT_NE(std::find(without.unused.begin(), without.unused.end(), "mailbox"), without.unused.end());
  // With a real hit cost in the data, `hit` is kept.
  const TermSelection with = select_terms(ModelLevel::counters, synthetic_runs(25.0, 5), {});
  EXPECT_NE(std::find(with.terms.begin(), with.terms.end(), "hit"), with.terms.end());
  EXPECT_LT(with.held_out.mape, 0.03);
  EXPECT_EQ(with.by_scene_family.size(), 2u);
}

TEST(CostModelSelection, SpearmanRanksWithTies) {
  EXPECT_DOUBLE_EQ(spearman_rank_correlation({1, 2, 3, 4}, {10, 20, 30, 40}), 1.0);
  EXPECT_DOUBLE_EQ(spearman_rank_correlation({1, 2, 3, 4}, {4, 3, 2, 1}), -1.0);
  EXPECT_NEAR(spearman_rank_correlation({1, 2, 2, 3}, {1, 2, 3, 4}), 0.9487, 1e-4);
  EXPECT_TRUE(std::isnan(spearman_rank_correlation({1, 1}, {1, 2})));
}

TEST(CostRuns, CsvRoundTripsEveryColumnAndRejectsMalformedRows) {
  std::vector<RunRecord> runs = synthetic_runs(0.0, 2, 2, 3);
  runs[0].scene = "stadium:object=(sphere:n=10),ratio=5";  // commas and parentheses: quoted
  runs[1].cpu_model = "CPU \"quoted\" model";
  runs[2].ns_per_ray_min = 0.1 + 0.2;  // needs 17 digits to round-trip
  const auto path = scratch("roundtrip.csv").string();
  {
    std::ofstream out(path);
    out << runs_csv_header() << '\n';
    for (const RunRecord& r : runs) out << to_csv_row(r) << '\n';
  }
  const std::vector<RunRecord> back = read_runs_csv(path);
  ASSERT_EQ(back.size(), runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(to_csv_row(back[i]), to_csv_row(runs[i]));
  EXPECT_EQ(back[2].ns_per_ray_min, runs[2].ns_per_ray_min);

  auto write = [&](const std::string& text) {
    std::ofstream(path, std::ios::trunc) << text;
    return path;
  };
  const std::string row = to_csv_row(runs[1]);
  EXPECT_THROW(read_runs_csv(write("")), InputError);
  EXPECT_THROW(read_runs_csv(write("case,scene\n1,x\n")), InputError);              // columns missing
  EXPECT_THROW(read_runs_csv(write(runs_csv_header() + "\n")), InputError);          // no rows
  EXPECT_NO_THROW(read_runs_csv(write(runs_csv_header() + "\n"), true));
  EXPECT_THROW(read_runs_csv(write(runs_csv_header() + "\n" + row)), InputError);    // last line unterminated
  std::string bad_number = row;
  bad_number.replace(bad_number.rfind(','), std::string::npos, ",nan");
  try {
    read_runs_csv(write(runs_csv_header() + "\n" + bad_number + "\n"));
    ADD_FAILURE() << "a NaN field was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":2:"), std::string::npos) << e.what();  // names the line
  }
}

TEST(CostSweep, PlansAndShardsAreValidated) {
  EXPECT_EQ(parse_shard("0/1").count, 1);
  EXPECT_EQ(parse_shard("3/4").index, 3);
  for (const char* bad : {"3/2", "1/0", "-1/2", "a/b", "2", "0/", "/3"}) EXPECT_THROW(parse_shard(bad), InputError) << bad;

  auto plan_file = [](const std::string& text) {
    const auto p = scratch("plan.json").string();
    std::ofstream(p, std::ios::trunc) << text;
    return p;
  };
  const char* bad_plans[] = {
      "{",                                                                                 // malformed JSON
      R"({"scenes": ["soup:n=10"], "accels": ["bvh"]})",                                    // missing key
      R"({"scenes": [], "accels": ["bvh"], "rays": ["primary:4"]})",                         // empty list
      R"({"scenes": ["soup:n=10"], "accels": ["bvh", "bvh"], "rays": ["primary:4"]})",       // repeated
      R"({"scenes": ["soup:n=10"], "accels": ["embree"], "rays": ["primary:4"]})",           // no features
      R"({"scenes": ["soup:n=10"], "accels": ["bvh:nonsense=1"], "rays": ["primary:4"]})",   // bad parameter
      R"({"scenes": ["nowhere:n=1"], "accels": ["bvh"], "rays": ["primary:4"]})",            // unknown scene
      R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "rays": ["beams:4"]})",                // unknown rays
      R"({"scenes": ["soup:n=10"], "accels": ["bvh"], "rays": ["primary:4"], "extra": 1})",  // unknown key
      R"({"scenes": ["soup:n=10"], "accels": [3], "rays": ["primary:4"]})",                  // not a string
  };
  for (const char* text : bad_plans) EXPECT_THROW(load_plan(plan_file(text)), InputError) << text;
  EXPECT_THROW(load_plan("/no/such/plan.json"), InputError);
  const SweepPlan quick = load_plan("quick");
  EXPECT_GT(quick.case_count(), 100);
  const SweepPlan p = load_plan(plan_file(R"({"scenes": ["sphere:n=10", "soup:n=10"], "accels": ["bvh", "kdtree", "grid"],
                                              "rays": ["primary:4", "diffuse:4"]})"));
  EXPECT_EQ(p.case_count(), 12);
  const SweepCase c = p.case_at(9);  // (1·3 + 1)·2 + 1
  EXPECT_EQ(c.scene, "soup:n=10");
  EXPECT_EQ(c.accel, "kdtree");
  EXPECT_EQ(c.rays, "diffuse:4");
}

/// A small plan whose sweep takes a few seconds.
SweepPlan small_plan() {
  SweepPlan p;
  p.source = "test";
  p.scenes = {"sphere:n=300", "walls:n=8,angle=20"};
  p.accels = {"bvh", "kdtree", "grid"};
  p.rays = {"primary:1024", "shadow:512"};
  return p;
}

std::vector<RunRecord> sweep_into(const SweepPlan& plan, const std::string& out, ShardSpec shard) {
  SweepOptions o;
  o.out = out;
  o.shard = shard;
  o.timing.min_seconds = 0;
  std::filesystem::remove(out);
  run_sweep(plan, o);
  return read_runs_csv(out);
}

/// The columns a repeated measurement must reproduce exactly: identity, counters and features.
std::string deterministic_part(RunRecord r) {
  r.ns_per_ray_min = r.ns_per_ray_median = r.ns_per_ray_max = r.embree_ns_per_ray_min = r.build_s = 0;
  r.embree_ns_per_ray_max = r.build_s_max = 0;
  r.embree_bytes = 0;  // Embree's allocator
  r.passes = 0;
  r.build_passes = 0;  // no third build once they total kSweepBuildSeconds
  return to_csv_row(r);
}

TEST(CostSweep, BuildTimeIsTheFastestOfAtLeastTwoPassesWithinTheirBudget) {
  const auto scene = make_scene("soup:n=2000");
  const BuiltStructure once = build_structure("bvh", scene, 1);
  EXPECT_EQ(once.build_passes, 1);
  const BuiltStructure thrice = build_structure("bvh", scene, 1, 3, 1e9);
  EXPECT_EQ(thrice.build_passes, 3);
  EXPECT_GT(thrice.build_s, 0.0);
  EXPECT_EQ(thrice.accel->structure_hash(), once.accel->structure_hash());  // the same tree, built again
  // A budget the first build already spends: two builds all the same (the first of a process
  // pays for memory it has never touched), and no third.
  EXPECT_EQ(build_structure("bvh", scene, 1, 3, 1e-12).build_passes, 2);
  EXPECT_EQ(build_structure("bvh", scene, 1, 1, 1e-12).build_passes, 1);
}

TEST(CostSweep, ShardsMergeToTheUnshardedDataSet) {
  const SweepPlan plan = small_plan();
  const std::vector<RunRecord> whole = sweep_into(plan, scratch("whole.csv").string(), {0, 1});
  ASSERT_EQ(static_cast<std::int64_t>(whole.size()), plan.case_count());
  const std::vector<RunRecord> first = sweep_into(plan, scratch("shard0.csv").string(), {0, 2});
  sweep_into(plan, scratch("shard1.csv").string(), {1, 2});
  for (const RunRecord& r : first) EXPECT_EQ(r.case_number % 2, 0);
  MergeOptions o;
  o.shard_files = {scratch("shard1.csv").string(), scratch("shard0.csv").string()};
  o.out = scratch("merged.csv").string();
  std::filesystem::remove(o.out);
  EXPECT_TRUE(merge_shards(plan, o).complete());
  const std::vector<RunRecord> merged = read_runs_csv(o.out);
  ASSERT_EQ(merged.size(), whole.size());
  for (const RunRecord& r : first)  // the merge copies rows, timings included
    EXPECT_EQ(to_csv_row(merged[static_cast<std::size_t>(r.case_number)]), to_csv_row(r));
  for (std::size_t i = 0; i < whole.size(); ++i) {
    EXPECT_EQ(deterministic_part(merged[i]), deterministic_part(whole[i]));
    EXPECT_GE(whole[i].passes, 5);
    EXPECT_GE(whole[i].build_passes, 2);
    EXPECT_LE(whole[i].build_passes, kSweepBuildPasses);
    EXPECT_GT(whole[i].ns_per_ray_min, 0);
    EXPECT_GT(whole[i].embree_ns_per_ray_min, 0);
    EXPECT_LE(whole[i].ns_per_ray_min, whole[i].ns_per_ray_median);
    EXPECT_LE(whole[i].ns_per_ray_median, whole[i].ns_per_ray_max);  // the passes' range
    EXPECT_LE(whole[i].embree_ns_per_ray_min, whole[i].embree_ns_per_ray_max);
    EXPECT_LE(whole[i].build_s, whole[i].build_s_max);
  }
  // Every case of the plan once, with its key.
  for (std::size_t i = 0; i < whole.size(); ++i) {
    const SweepCase c = plan.case_at(static_cast<std::int64_t>(i));
    EXPECT_EQ(whole[i].case_number, static_cast<std::int64_t>(i));
    EXPECT_EQ(whole[i].scene + whole[i].accel + whole[i].rays, c.scene + c.accel + c.rays);
  }
}

TEST(CostSweep, ResumeSkipsFinishedCasesAndRejectsAnotherPlansFile) {
  const SweepPlan plan = small_plan();
  const std::string out = scratch("resume.csv").string();
  SweepOptions o;
  o.out = out;
  o.timing.min_seconds = 0;
  std::filesystem::remove(out);
  o.shard = {0, 3};
  run_sweep(plan, o);
  // An existing file without --resume is an error, and leaves the file as it was.
  const auto size = std::filesystem::file_size(out);
  o.shard = {0, 1};
  EXPECT_THROW(run_sweep(plan, o), InputError);
  EXPECT_EQ(std::filesystem::file_size(out), size);
  // A half-written last line (a killed sweep) is dropped and that case measured again.
  std::ofstream(out, std::ios::app) << "5,sphere:n=300,kdtr";
  o.resume = true;
  const SweepSummary s = run_sweep(plan, o);
  EXPECT_EQ(s.skipped, 4);
  EXPECT_EQ(s.measured, plan.case_count() - 4);
  std::vector<RunRecord> rows = read_runs_csv(out);
  ASSERT_EQ(static_cast<std::int64_t>(rows.size()), plan.case_count());
  std::sort(rows.begin(), rows.end(), [](const RunRecord& a, const RunRecord& b) { return a.case_number < b.case_number; });
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i].case_number, static_cast<std::int64_t>(i));
  // The file of another plan is refused.
  SweepPlan other = plan;
  std::swap(other.accels[0], other.accels[1]);
  EXPECT_THROW(run_sweep(other, o), InputError);
}

TEST(CostSweep, BadInputLeavesNoFileBehind) {
  SweepPlan plan = small_plan();
  plan.scenes = {"/no/such/mesh.off"};
  SweepOptions o;
  o.out = scratch("never.csv").string();
  std::filesystem::remove(o.out);
  EXPECT_THROW(run_sweep(plan, o), InputError);
  EXPECT_FALSE(std::filesystem::exists(o.out));
}

/// The end-point overlap by its definition (tree_features.h): every node against every triangle
/// outside its subtree, O(nodes × N).
double epo_by_definition(const Bvh2& tree, const Scene& scene) {
  double total = 0, sum = 0;
  for (std::size_t t = 0; t < scene.mesh.size(); ++t)
    total += clipped_triangle_area(scene.mesh.vertex(t, 0), scene.mesh.vertex(t, 1), scene.mesh.vertex(t, 2),
                                   scene.mesh.triangle_bounds(t));
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {
    std::vector<bool> own(scene.mesh.size(), false);
    std::vector<std::uint32_t> stack = {static_cast<std::uint32_t>(n)};
    while (!stack.empty()) {
      const Bvh2Node& m = tree.nodes[stack.back()];
      stack.pop_back();
      if (m.is_leaf()) {
        for (std::uint32_t i = m.first; i < m.first + m.count; ++i) own[tree.prims[i]] = true;
      } else {
        stack.push_back(m.first);
        stack.push_back(m.first + 1);
      }
    }
    const Bvh2Node& node = tree.nodes[n];
    double area = 0;
    for (std::size_t t = 0; t < scene.mesh.size(); ++t)
      if (!own[t] && scene.mesh.triangle_bounds(t).overlaps(node.box))
        area += clipped_triangle_area(scene.mesh.vertex(t, 0), scene.mesh.vertex(t, 1), scene.mesh.vertex(t, 2), node.box);
    sum += (node.is_leaf() ? static_cast<double>(node.count) : 1.0) * area;
  }
  return sum / total;
}

TEST(TreeFeatures, EndPointOverlapMatchesItsDefinitionOnAnyThreadCount) {
  const auto scene = make_scene("soup:n=400,seed=3");
  for (const char* spec : {"bvh:width=2", "bvh:width=2,builder=spatial", "bvh:width=2,builder=median"}) {
    const auto accel = make_accelerator(spec, scene);
    const Bvh2& tree = dynamic_cast<const Bvh&>(*accel).tree();
    double one = 0, two = 0;
    tbb::task_arena(1).execute([&] { one = tree_features(*accel, *scene).epo; });
    tbb::task_arena(2).execute([&] { two = tree_features(*accel, *scene).epo; });
    EXPECT_EQ(one, two) << spec;
    EXPECT_NEAR(one, epo_by_definition(tree, *scene), 1e-9 * one) << spec;
    EXPECT_GT(one, 0.0) << spec;
  }
}

TEST(TreeFeatures, SurfaceAreaExpectationsOfSimpleStructures) {
  const auto scene = make_scene("soup:n=500");
  // Brute force: one leaf holding every primitive.
  const TreeFeatures brute = tree_features(*make_accelerator("brute", scene), *scene);
  EXPECT_DOUBLE_EQ(brute.expected_tests, 500.0);
  EXPECT_EQ(brute.inner_nodes, 0u);
  // A uniform grid: every cell is visited with probability SA(cell)/SA(root).
  const auto grid = make_accelerator("grid:d=2", scene);
  const TreeFeatures g = tree_features(*grid, *scene);
  EXPECT_EQ(g.inner_nodes, grid->stats().nodes);
  EXPECT_GT(g.expected_inner, 1.0);
  EXPECT_GE(g.references, 500u);
  // A kd-tree: the root is visited by every line through its box; spatial subdivisions have no EPO.
  const TreeFeatures kd = tree_features(*make_accelerator("kdtree", scene), *scene);
  EXPECT_GE(kd.expected_inner, 1.0);
  EXPECT_GT(kd.expected_tests, 0.0);
  EXPECT_LT(kd.expected_tests, 500.0);
  EXPECT_EQ(kd.epo, 0.0);
  // BVHs: every width gets its own features, and overlapping boxes give a positive EPO.
  for (const char* spec : {"bvh:width=2", "bvh:width=4", "bvh:width=8"}) {
    const TreeFeatures b = tree_features(*make_accelerator(spec, scene), *scene);
    EXPECT_GT(b.epo, 0.0) << spec;
    EXPECT_GE(b.expected_inner, 1.0) << spec;
    EXPECT_LE(b.expected_test_groups, b.expected_tests) << spec;
  }
  EXPECT_EQ(structure_family("bvh"), "bvh8");
  EXPECT_EQ(structure_family("bvh:width=2"), "bvh");
  EXPECT_EQ(structure_family("kdtree:clip=none"), "kdtree");
  EXPECT_THROW(tree_features(*make_accelerator("embree", scene), *scene), InputError);
}

/// A model fitted on synthetic tree-level data with known constants, written to a file.
std::string synthetic_model_file(const std::string& name, double c_node, double c_test) {
  std::vector<RunRecord> runs;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(1, 40);
  for (const char* family : {"kdtree", "bvh8", "octree", "bsp", "grid"})
    for (int s = 0; s < 4; ++s)
      for (int i = 0; i < 6; ++i) {
        RunRecord r;
        r.scene = "scene" + std::to_string(s);
        r.scene_family = "synthetic";
        r.family = family;
        r.accel = family;
        r.rays = "primary:10";
        r.ray_kind = "primary";
        r.query = "intersect";
        r.nodes_per_ray = r.e_inner = u(rng);
        r.tests_per_ray = r.e_tests = u(rng);
        r.leaves_per_ray = r.e_leaves = 1;
        r.ns_per_ray_min = 10 + c_node * r.e_inner + c_test * r.e_tests;
        runs.push_back(r);
      }
  const CostModelSet set = fit_cost_model_set(runs, {}, FitTarget::minimum);
  const std::string path = scratch(name).string();
  write_model_file(set, path);
  return path;
}

TEST(CostModelFile, RoundTripsAndRejectsOtherVersionsAndMissingFamilies) {
  const std::string path = synthetic_model_file("model.json", 2.0, 8.0);
  const CostModelSet back = read_model_file(path);
  const FamilyModel& kd = back.family("kdtree");
  EXPECT_NEAR(kd.counters.model.value_of("test") / kd.counters.model.value_of("node"), 4.0, 0.05);
  EXPECT_NEAR(kd.builder.c_isect / kd.builder.c_trav, 4.0, 0.05);
  EXPECT_THROW(back.family("nested-grid"), InputError);

  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  auto variant = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    const std::string p = scratch("variant.json").string();
    std::ofstream(p, std::ios::trunc) << t;
    return p;
  };
  EXPECT_THROW(read_model_file(variant("\"version\": 2", "\"version\": 3")), InputError);
  EXPECT_THROW(read_model_file(variant("\"covariance\": [", "\"covariance\": [[1], ")), InputError);
  EXPECT_THROW(read_model_file(variant("\"replicate_error\"", "\"replicate_err\"")), InputError);
  EXPECT_THROW(read_model_file(variant("raylab-cost-model", "something-else")), InputError);
  EXPECT_THROW(read_model_file(variant("\"families\": {", "\"families\": {,")), InputError);
  EXPECT_THROW(read_model_file(variant("\"c_trav\"", "\"c_travel\"")), InputError);
  EXPECT_THROW(read_model_file("/no/such/model.json"), InputError);
}

/// Runs of one family over `scenes` scenes made by ns = 20 + 1.5·nodes + 3·tests (counters) =
/// 20 + 5·e_inner + 7.5·e_tests (tree), times exp(N(0, σ²)): log-normal noise of known spread.
/// Scene s has 1000·(s + 1) primitives. With `replicates`, every case is measured twice (two rows,
/// one key, independent noise).
std::vector<RunRecord> log_normal_runs(double sigma, std::uint32_t seed, int scenes, int per_scene, bool replicates = false) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> nodes(5, 60), tests(2, 40);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<RunRecord> runs;
  for (int s = 0; s < scenes; ++s)
    for (int i = 0; i < per_scene; ++i) {
      RunRecord r;
      r.scene = "scene" + std::to_string(s);
      r.scene_family = s % 2 ? "odd" : "even";
      r.accel = "kdtree";
      r.family = "kdtree";
      r.rays = "primary:" + std::to_string(100 + i);
      r.ray_kind = "primary";
      r.query = "intersect";
      r.primitives = 1000 * (s + 1);
      r.nodes_per_ray = nodes(rng);
      r.tests_per_ray = tests(rng);
      r.e_inner = 0.3 * r.nodes_per_ray;
      r.e_tests = 0.4 * r.tests_per_ray;
      const double ns = 20 + 1.5 * r.nodes_per_ray + 3 * r.tests_per_ray;
      for (int k = 0; k < (replicates ? 2 : 1); ++k) {
        r.case_number = static_cast<std::int64_t>(runs.size());
        r.ns_per_ray_min = ns * std::exp(noise(rng));
        runs.push_back(r);
      }
    }
  return runs;
}

TEST(CostIntervals, NinetyPercentIntervalsCoverFreshPointsAndWidenOutsideTheRange) {
  const double sigma = 0.05;
  const CostModelSet set = fit_cost_model_set(log_normal_runs(sigma, 21, 8, 15), {}, FitTarget::minimum);
  const FamilyModel& kd = set.family("kdtree");
  for (const LevelFit* f : {&kd.counters, &kd.tree}) {
    ASSERT_TRUE(f->cross_validated);
    EXPECT_EQ(f->model.covariance.size(), f->model.terms.size() * f->model.terms.size());
    // The held-out spread estimates the noise that made the data, and the held-out intervals cover about 90%.
    EXPECT_GT(f->model.residual_log_sigma, 0.8 * sigma) << level_name(f->model.level);
    EXPECT_LT(f->model.residual_log_sigma, 1.3 * sigma) << level_name(f->model.level);
    EXPECT_GE(f->held_out_coverage90, 0.8) << level_name(f->model.level);
    EXPECT_LE(f->held_out_coverage90, 0.98) << level_name(f->model.level);
  }
  EXPECT_TRUE(std::isnan(kd.replicate_error));
  EXPECT_EQ(kd.replicate_groups, 0u);

  // Fresh points of the same process, inside the fitted range.
  const std::vector<RunRecord> fresh = log_normal_runs(sigma, 22, 8, 100);
  for (ModelLevel level : {ModelLevel::counters, ModelLevel::tree}) {
    std::size_t inside = 0;
    for (const RunRecord& r : fresh) {
      const IntervalPrediction p = kd.level_fit(level).model.predict_interval(r);
      ASSERT_LT(p.lo, p.ns);
      ASSERT_GT(p.hi, p.ns);
      inside += p.lo <= r.ns_per_ray_min && r.ns_per_ray_min <= p.hi;
    }
    const double coverage = static_cast<double>(inside) / static_cast<double>(fresh.size());
    EXPECT_GE(coverage, 0.8) << level_name(level);
    EXPECT_LE(coverage, 0.97) << level_name(level);
  }

  // Ten times the largest scene's primitives: flagged, named, and its interval 1 + log2(10) times as wide in log space.
  RunRecord far = fresh.front();
  far.primitives = 4000;
  far.nodes_per_ray = 30;
  far.tests_per_ray = 20;
  far.e_inner = 9;
  far.e_tests = 8;
  const FamilyPrediction near = kd.predict(ModelLevel::tree, far);
  ASSERT_FALSE(near.range.extrapolated()) << near.range.worst.describe();
  EXPECT_DOUBLE_EQ(near.range.widening(), 1.0);
  far.primitives = 80000;
  const FamilyPrediction outside = kd.predict(ModelLevel::tree, far);
  ASSERT_TRUE(outside.range.extrapolated());
  EXPECT_EQ(outside.range.worst.feature, "primitives");
  EXPECT_TRUE(outside.range.worst.above());
  EXPECT_DOUBLE_EQ(outside.range.worst.factor, 10.0);
  EXPECT_EQ(outside.range.worst.describe(), "primitives 8e+04 is 10x above the fitted 1000..8000");
  EXPECT_DOUBLE_EQ(outside.interval.ns, near.interval.ns);
  EXPECT_NEAR(std::log(outside.interval.hi / outside.interval.ns), (1 + std::log2(10.0)) * std::log(near.interval.hi / near.interval.ns),
              1e-9);
  EXPECT_LT(outside.interval.lo, near.interval.lo);
  // Below the range too.
  far.primitives = 250;
  EXPECT_DOUBLE_EQ(kd.check_range(far).worst.factor, 4.0);
  EXPECT_FALSE(kd.check_range(far).worst.above());
  EXPECT_DOUBLE_EQ(kd.check_range(far).widening(), 3.0);
  EXPECT_DOUBLE_EQ(check_feature_range("primitives", 5.0, {10.0, 20.0}).factor, 2.0);
  EXPECT_DOUBLE_EQ(check_feature_range("primitives", 15.0, {10.0, 20.0}).factor, 1.0);
  EXPECT_DOUBLE_EQ(range_widening(0.5), 1.0);
}

TEST(CostIntervals, ConstantsCovarianceWidensPredictionsAwayFromTheData) {
  // Few rows: the constants' uncertainty is a visible part of the interval, and grows with the features.
  const std::vector<RunRecord> runs = log_normal_runs(0.05, 5, 1, 12);
  FitResult details;
  FittedCostModel m = fit_cost_model(ModelLevel::counters, {"c0", "node", "test"}, runs, {}, &details);
  ASSERT_EQ(m.covariance.size(), 9u);
  for (std::size_t j = 0; j < 3; ++j) EXPECT_NEAR(std::sqrt(m.covariance[j * 3 + j]), m.std_errors[j], 1e-9 * m.std_errors[j]);
  EXPECT_NEAR(m.covariance[1], m.covariance[3], 1e-12 * std::abs(m.covariance[1]) + 1e-300);  // symmetric
  RunRecord typical = runs.front(), far = runs.front();
  typical.nodes_per_ray = 30;
  typical.tests_per_ray = 20;
  far.nodes_per_ray = 600;
  far.tests_per_ray = 20;
  EXPECT_GT(m.parameter_log_variance(far), m.parameter_log_variance(typical));
  m.residual_log_sigma = 0.05;
  const IntervalPrediction a = m.predict_interval(typical), b = m.predict_interval(typical, 0.2);
  EXPECT_GT(a.log_sigma, 0.05);                       // the covariance adds to the residual spread
  EXPECT_GT(b.log_sigma, 0.2);                        // the replicate spread is a floor
  EXPECT_LT(b.log_sigma, std::hypot(0.2, 0.05));      // and not added to the residual spread
  const IntervalPrediction none = log_normal_interval90(-1.0, 0.1);
  EXPECT_TRUE(std::isnan(none.lo) && std::isnan(none.hi));
}

TEST(CostReplicates, ReplicateErrorIsTheMeanPairwiseSpreadOfCasesMeasuredAgain) {
  auto row = [](const std::string& scene, const std::string& accel, std::int64_t threads, double ns) {
    RunRecord r;
    r.scene = scene;
    r.accel = accel;
    r.rays = "primary:64";
    r.threads = threads;
    r.ns_per_ray_min = ns;
    return r;
  };
  // (a, bvh): 100 and 110; (b, bvh): 50, 50 and 60 (pairs 0, 10/55, 10/55); singletons and another
  // thread count are not replicates.
  const ReplicateError e = replicate_error({row("a", "bvh", 1, 100), row("b", "bvh", 1, 50), row("a", "bvh", 1, 110),
                                            row("b", "bvh", 1, 50), row("b", "bvh", 1, 60), row("a", "kdtree", 1, 70),
                                            row("a", "bvh", 2, 300)});
  EXPECT_EQ(e.groups, 2u);
  EXPECT_NEAR(e.mape, 0.5 * (10.0 / 105.0 + (2.0 / 3.0) * (10.0 / 55.0)), 1e-12);
  EXPECT_TRUE(std::isnan(replicate_error({row("a", "bvh", 1, 100), row("b", "bvh", 1, 100)}).mape));

  // Log-normal noise of spread σ: the replicate error is 2σ/√π, and the fit recovers σ from it.
  const double sigma = 0.05;
  const std::vector<RunRecord> runs = log_normal_runs(sigma, 31, 8, 100, true);
  const CostModelSet set = fit_cost_model_set(runs, {}, FitTarget::minimum);
  const FamilyModel& kd = set.family("kdtree");
  EXPECT_EQ(kd.replicate_groups, 800u);
  EXPECT_NEAR(kd.replicate_error, 2 * sigma / std::sqrt(std::acos(-1.0)), 0.1 * sigma);
  EXPECT_NEAR(replicate_log_sigma(kd.replicate_error), sigma, 0.1 * sigma);
  // Replicates share their scene: eight scenes, and both rows of a pair are held out together (the
  // same fold's model predicts both identically).
  EXPECT_EQ(kd.scenes.size(), 8u);
  const std::vector<double>& held_out = kd.counters.held_out_predictions;
  ASSERT_EQ(held_out.size(), runs.size());
  for (std::size_t i = 0; i + 1 < runs.size(); i += 2) ASSERT_DOUBLE_EQ(held_out[i], held_out[i + 1]) << i;

  // The file keeps what the intervals need.
  const std::string path = scratch("replicates.json").string();
  write_model_file(set, path);
  const FamilyModel back = read_model_file(path).family("kdtree");
  EXPECT_DOUBLE_EQ(back.replicate_error, kd.replicate_error);
  EXPECT_EQ(back.replicate_groups, kd.replicate_groups);
  EXPECT_DOUBLE_EQ(back.tree.held_out_coverage90, kd.tree.held_out_coverage90);
  EXPECT_DOUBLE_EQ(back.tree.model.residual_log_sigma, kd.tree.model.residual_log_sigma);
  EXPECT_EQ(back.tree.model.covariance, kd.tree.model.covariance);
  const RunRecord probe = runs.front();
  EXPECT_DOUBLE_EQ(back.predict(ModelLevel::tree, probe).interval.hi, kd.predict(ModelLevel::tree, probe).interval.hi);
}

TEST(CostFitTarget, EmbreeNormalisedTimesScaleEveryPassStatisticAlike) {
  auto row = [](const std::string& scene, double embree, double fastest, double slowest) {
    RunRecord r;
    r.scene = scene;
    r.rays = "primary:64";
    r.embree_ns_per_ray_min = embree;
    r.ns_per_ray_min = fastest;
    r.ns_per_ray_median = 0.5 * (fastest + slowest);
    r.ns_per_ray_max = slowest;
    return r;
  };
  // Scene a: Embree read 100 and 200 ns; the second row is brought to the first's Embree time.
  const std::vector<RunRecord> runs = {row("a", 100, 50, 60), row("a", 200, 80, 120), row("b", 300, 90, 99)};
  const std::vector<RunRecord> same = with_fit_target(runs, FitTarget::minimum);
  EXPECT_EQ(same[1].ns_per_ray_min, 80);
  EXPECT_EQ(same[1].ns_per_ray_max, 120);
  const std::vector<RunRecord> scaled = with_fit_target(runs, FitTarget::embree_normalized);
  EXPECT_DOUBLE_EQ(scaled[0].ns_per_ray_min, 50);
  EXPECT_DOUBLE_EQ(scaled[0].ns_per_ray_max, 60);
  EXPECT_DOUBLE_EQ(scaled[1].ns_per_ray_min, 40);
  EXPECT_DOUBLE_EQ(scaled[1].ns_per_ray_median, 50);
  EXPECT_DOUBLE_EQ(scaled[1].ns_per_ray_max, 60);
  EXPECT_DOUBLE_EQ(scaled[2].ns_per_ray_max, 99);
  // A row without Embree's time cannot be normalised.
  EXPECT_THROW(with_fit_target({row("a", 0, 50, 60)}, FitTarget::embree_normalized), InputError);
}

TEST(CostModelFile, TheCommittedModelLoadsWithIntervals) {
  const CostModelSet set = read_model_file("default");
  ASSERT_FALSE(set.families.empty());
  for (const auto& [name, m] : set.families)
    for (const LevelFit* f : {&m.counters, &m.tree}) {
      EXPECT_TRUE(std::isfinite(f->model.residual_log_sigma)) << name;
      EXPECT_GT(f->model.residual_log_sigma, 0.0) << name;
    }
}

TEST(CostModelFile, BuildersTakeTheFittedConstants) {
  const std::string path = synthetic_model_file("builders.json", 1.0, 20.0);
  const auto scene = make_scene("sphere:n=2000");
  const FittedSahCost c = load_builder_costs(path, "kdtree");
  // cost=model builds the tree the same constants give by hand (C_leaf is 0: the data had no leaf cost).
  const BuildContext context = model_build_context();
  const auto fitted = make_accelerator("kdtree:cost=" + path, scene, context);
  char manual[128];
  std::snprintf(manual, sizeof manual, "kdtree:c_trav=%.17g,c_isect=%.17g", c.c_trav, c.c_isect);
  ASSERT_EQ(c.c_leaf, 0.0);
  EXPECT_EQ(fitted->structure_hash(), make_accelerator(manual, scene)->structure_hash()) << manual;
  // A ratio of 1:20 builds a deeper tree than the default 1:1.5.
  EXPECT_GT(fitted->stats().nodes, make_accelerator("kdtree", scene)->stats().nodes);
  for (const char* spec : {"bvh:cost=", "octree:cost=", "bsp:cost="}) {
    const auto a = make_accelerator(spec + path, scene, context);
    EXPECT_GT(a->stats().nodes, 0u) << spec;
  }
  // A wide BVH takes its family's constants (per wide node visit, per primitive test) in the SAH
  // collapse: the binary tree is the default one, and 1:20 (a packet test 80 node visits)
  // collapses it into more wide nodes than the default 3:1. With collapse=greedy, which has no
  // costs, the binary SAH takes them.
  const auto wide_fitted = make_accelerator("bvh:width=8,cost=" + path, scene, context);
  const auto wide_default = make_accelerator("bvh:width=8", scene);
  const Bvh& fitted_bvh = dynamic_cast<const Bvh&>(*wide_fitted);
  const Bvh& default_bvh = dynamic_cast<const Bvh&>(*wide_default);
  const FittedSahCost c8 = load_builder_costs(path, "bvh8");
  EXPECT_EQ(fitted_bvh.config().wide_cost.c_node, c8.c_trav);
  EXPECT_EQ(fitted_bvh.config().wide_cost.c_packet, kPacketWidth * c8.c_isect);
  ASSERT_EQ(fitted_bvh.tree().nodes.size(), default_bvh.tree().nodes.size());
  EXPECT_EQ(fitted_bvh.tree().prims, default_bvh.tree().prims);
  EXPECT_GT(fitted_bvh.wide8().nodes.size(), default_bvh.wide8().nodes.size());
  std::snprintf(manual, sizeof manual, "bvh:width=8,collapse=greedy,c_trav=%.17g,c_isect=%.17g", c8.c_trav, c8.c_isect);
  EXPECT_EQ(make_accelerator("bvh:width=8,collapse=greedy,cost=" + path, scene, context)->structure_hash(),
            make_accelerator(manual, scene)->structure_hash())
      << manual;
  EXPECT_THROW(make_accelerator("kdtree:cost=" + path + ",c_trav=2", scene, context), InputError);
  EXPECT_THROW(make_accelerator("nested-grid:cost=" + path, scene, context), InputError);   // no such parameter
  EXPECT_THROW(make_accelerator("bvh:width=2,cost=" + path, scene, context), InputError);   // no bvh (width 2) entry
  EXPECT_THROW(make_accelerator("kdtree:cost=/no/such.json", scene, context), InputError);
  // lib/accel reads no model: without a context that resolves cost=, the spec is an input error,
  // and reading a spec with cost= (its accuracy, its canonical form) reads no file.
  EXPECT_THROW(make_accelerator("kdtree:cost=" + path, scene), InputError);
  EXPECT_NO_THROW(accuracy_bound("kdtree:cost=/no/such.json"));
  EXPECT_NO_THROW(canonical_spec("bvh:cost=/no/such.json"));
}

TEST(AutoAccelerator, ChoosesAStructureThatAgreesWithTheOracle) {
  const std::string path = synthetic_model_file("auto.json", 1.0, 3.0);
  const auto scene = make_scene("sphere:n=1000");
  const auto accel = make_accelerator("auto:model=" + path + ",rays=primary", scene);
  const auto* chooser = dynamic_cast<const AutoAccelerator*>(accel.get());
  ASSERT_NE(chooser, nullptr);
  const AutoChoice& c = chooser->choice();
  EXPECT_FALSE(c.chosen.empty());
  // The model covers five families: their candidates are built, predicted, and the cheapest kept.
  double best = INFINITY;
  for (const AutoCandidate& k : c.candidates)
    if (k.skipped.empty()) best = std::min(best, k.predicted_ns_per_ray);
  EXPECT_EQ(best, c.predicted_ns_per_ray);
  EXPECT_GE(c.candidates.size(), 8u);
  const std::vector<Ray> rays = make_ray_set("primary:2048", scene);
  const auto oracle = make_accelerator("exact", scene);
  const TraceResult got = trace_rays(*accel, rays, {1});
  const TraceResult ref = trace_rays(*oracle, rays, {1});
  EXPECT_EQ(compare_hits(rays, got.hits, ref.hits, length(Vec3d(scene->bounds().diagonal()))).mismatches, 0u);
  EXPECT_THROW(make_accelerator("auto:model=/no/such.json", scene), InputError);
  EXPECT_THROW(make_accelerator("auto:model=" + path + ",rays=sideways", scene), InputError);
}

}  // namespace
}  // namespace raylab
