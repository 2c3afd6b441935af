// The build-time model (build_time_model.h) and the fit it rests on (selected_linear_model.h):
// known constants recovered from synthetic build times, the held-out interval, and model.json.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "cost/accel_spec_key.h"
#include "accel/common/accel_factory.h"
#include "cost/build_time_model.h"
#include "cost/scene_features.h"
#include "cost/tree_features.h"
#include "geometry/input_error.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

/// Rows of one accelerator over `scenes` scenes of 10^3..10^6 primitives, build seconds
/// a·N·log2 N + b·N times lognormal noise of `sigma` (seeded).
std::vector<RunRecord> synthetic_build_rows(double a, double b, double sigma, int scenes, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<RunRecord> rows;
  for (int s = 0; s < scenes; ++s) {
    const double n = std::round(std::pow(10.0, 3.0 + 3.0 * s / (scenes - 1)));
    RunRecord r;
    r.scene = "scene" + std::to_string(s);
    r.accel = "bvh:builder=spatial";
    r.primitives = static_cast<std::int64_t>(n);
    r.build_s = (a * n * std::log2(n) + b * n) * std::exp(noise(rng));
    rows.push_back(r);
    // A second ray set of the same (scene, accel) shares its build: one row of the fit.
    r.rays = "diffuse:16";
    rows.push_back(r);
  }
  return rows;
}

/// The features of a scene known by its count alone (spread 0).
SceneFeatures counted(double primitives) {
  SceneFeatures f;
  f.primitives = primitives;
  return f;
}

TEST(BuildTimeModel, RecoversKnownConstantsWithinTheirStandardErrors) {
  const double a = 40e-9, b = 300e-9;
  const BuildTimeModels models = fit_build_time_models(synthetic_build_rows(a, b, 0.03, 14, 7), {}, FitOptions{});
  ASSERT_EQ(models.size(), 1u);
  const SelectedLinearModel& m = models.at("bvh:builder=spatial");
  EXPECT_EQ(m.rows, 14u);  // one row per (scene, accel)
  ASSERT_TRUE(m.cross_validated);
  const double a_hat = m.value_of("n_log2_n"), b_hat = m.value_of("n");
  const double a_se = m.std_error_of("n_log2_n"), b_se = m.std_error_of("n");
  ASSERT_TRUE(std::isfinite(a_se) && std::isfinite(b_se));
  // The constants within three of their stated standard errors, and the errors small enough for
  // that to say something (3% noise over three decades of N).
  EXPECT_LE(std::abs(a_hat - a), 3 * a_se) << a_hat << " ± " << a_se;
  EXPECT_LE(std::abs(b_hat - b), 3 * b_se) << b_hat << " ± " << b_se;
  EXPECT_LT(a_se, 0.1 * a);
  EXPECT_LT(b_se, 0.5 * b);
  // Held out: the error is the noise's (3% lognormal: mean |error| ≈ 2.4%), and about 90% of the
  // held-out scenes fall in intervals their own data did not set.
  EXPECT_LT(m.held_out_mape, 0.06);
  EXPECT_GE(m.coverage90, 0.7);
  EXPECT_EQ(m.range_lo, 1000.0);
  EXPECT_EQ(m.range_hi, 1e6);
  const FeatureRow f = build_time_features(counted(2e5));
  const auto [lo, hi] = m.interval90(f, 2e5);
  const double truth = a * 2e5 * std::log2(2e5) + b * 2e5;
  EXPECT_LT(lo, truth);
  EXPECT_GT(hi, truth);
}

/// Rows of `scenes` scenes whose build seconds are b·N + e·spread (3% lognormal noise), the
/// spread 0.3 to 8 references per triangle independently of N (as a grid's over meshes, soups
/// and walls), with their scene features.
std::pair<std::vector<RunRecord>, SceneFeatureTable> spread_build_rows(double b, double e, int scenes) {
  std::vector<RunRecord> rows = synthetic_build_rows(0, b, 0.0, scenes, 4);
  SceneFeatureTable table;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.03);
  const double per_triangle[] = {0.3, 8.0, 2.0, 0.8, 5.0};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    RunRecord& r = rows[i];
    const double n = static_cast<double>(r.primitives);
    SceneFeatures f;
    f.primitives = f.triangles = n;
    f.largest_extent = 1;
    const double spread = per_triangle[(i / 2) % 5] * n;
    f.sqrt_area_sum = spread / (0.75 * std::sqrt(12 * std::sqrt(3.0)) * std::cbrt(n));  // spread_references' form
    EXPECT_NEAR(spread_references(f), spread, 1e-9 * spread);
    table[r.scene] = f;
    if (i % 2 == 0) r.build_s = (b * n + e * spread) * std::exp(noise(rng));
    else r.build_s = rows[i - 1].build_s;  // the same (scene, accel): one build
  }
  return {rows, table};
}

bool has_term(const SelectedLinearModel& m, const std::string& term) {
  return std::find(m.terms.begin(), m.terms.end(), term) != m.terms.end();
}

TEST(BuildTimeModel, KeepsTheSpreadWhereBuildTimesFollowIt) {
  // The fit keeps the spread and recovers e; without scene features the N terms alone cannot
  // follow the times.
  const double b = 60e-9, e = 25e-9;
  const auto [rows, table] = spread_build_rows(b, e, 12);
  const SelectedLinearModel with = fit_build_time_models(rows, table, FitOptions{}).at("bvh:builder=spatial");
  ASSERT_TRUE(with.cross_validated);
  EXPECT_TRUE(has_term(with, "spread"));
  EXPECT_LE(std::abs(with.value_of("spread") - e), 3 * with.std_error_of("spread"))
      << with.value_of("spread") << " ± " << with.std_error_of("spread");
  EXPECT_LT(with.held_out_mape, 0.06);
  const SelectedLinearModel without = fit_build_time_models(rows, {}, FitOptions{}).at("bvh:builder=spatial");
  EXPECT_GT(without.held_out_mape, 3 * with.held_out_mape);
}

TEST(BuildTimeModel, WithTooFewScenesForEveryTermSelectionRunsForward) {
  // Four scenes cannot hold out a fit of all four terms: from the two required ones the spread is
  // added, since it lowers the held-out error, and the constant is not.
  const auto [rows, table] = spread_build_rows(60e-9, 25e-9, 4);
  const SelectedLinearModel m = fit_build_time_models(rows, table, FitOptions{}).at("bvh:builder=spatial");
  ASSERT_TRUE(m.cross_validated);
  EXPECT_TRUE(has_term(m, "spread"));
  EXPECT_FALSE(has_term(m, "one"));
  EXPECT_LT(m.held_out_mape, 0.1);
  // Two scenes hold out no fit of the two required terms: those alone, in-sample.
  const auto [two, two_table] = spread_build_rows(60e-9, 25e-9, 2);
  const SelectedLinearModel least = fit_build_time_models(two, two_table, FitOptions{}).at("bvh:builder=spatial");
  EXPECT_FALSE(least.cross_validated);
  EXPECT_EQ(least.terms, (std::vector<std::string>{"n_log2_n", "n"}));
}

TEST(BuildTimeModel, AFitWithoutTheRightFormIsNotHiddenByTheInterval) {
  // Pure N² build times: the N·log N + N form cannot follow them, and says so in its held-out error.
  std::vector<RunRecord> rows = synthetic_build_rows(1e-9, 0, 0.0, 10, 1);
  for (RunRecord& r : rows) r.build_s = 1e-12 * static_cast<double>(r.primitives) * static_cast<double>(r.primitives);
  const SelectedLinearModel m = fit_build_time_models(rows, {}, FitOptions{}).at("bvh:builder=spatial");
  EXPECT_GT(m.held_out_mape, 0.3);
  EXPECT_GT(m.log_q90, std::log(1.5));
}

TEST(BuildTimeModel, IntervalWidensOutsideTheFittedRange) {
  const SelectedLinearModel m = fit_build_time_models(synthetic_build_rows(40e-9, 300e-9, 0.05, 8, 3), {}, FitOptions{})
                                    .at("bvh:builder=spatial");
  auto relative_width = [&](double n) {
    const auto [lo, hi] = m.interval90(build_time_features(counted(n)), n);
    return hi / lo;
  };
  EXPECT_EQ(m.extrapolation_factor(5e5), 1.0);
  EXPECT_DOUBLE_EQ(m.extrapolation_factor(1e7), 10.0);
  EXPECT_GT(relative_width(1e7), relative_width(5e5));
  EXPECT_GT(relative_width(100), relative_width(5e3));
}

TEST(BuildTimeModel, RowsWithoutBuildTimesOrTooFewScenesAreLeftOut) {
  std::vector<RunRecord> rows = synthetic_build_rows(40e-9, 300e-9, 0.03, 6, 5);
  rows.front().build_s = 0;  // one scene's rows of this ray set without a build time
  RunRecord lone;
  lone.scene = "only";
  lone.accel = "grid";
  lone.primitives = 1000;
  lone.build_s = 1e-3;
  rows.push_back(lone);
  std::vector<std::string> notes;
  const BuildTimeModels models =
      fit_build_time_models(rows, {}, FitOptions{}, [&](const std::string& line) { notes.push_back(line); });
  EXPECT_EQ(models.count("grid"), 0u);  // one row cannot fit two terms
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes.front().find("grid"), std::string::npos);
  EXPECT_EQ(models.at("bvh:builder=spatial").rows, 6u);
}

TEST(BuildTimeModel, ModelFileSectionRoundTripsAndRejectsBadEntries) {
  const BuildTimeModels models = fit_build_time_models(synthetic_build_rows(40e-9, 300e-9, 0.03, 8, 9), {}, FitOptions{});
  const nlohmann::ordered_json j = build_time_models_json(models);
  const auto& e = j.at("bvh:builder=spatial");
  for (const char* key : {"terms", "values", "std_errors", "held_out", "range"}) EXPECT_TRUE(e.contains(key)) << key;
  EXPECT_TRUE(e.at("held_out").contains("mape"));
  EXPECT_TRUE(e.at("held_out").contains("coverage90"));
  const BuildTimeModels back = read_build_time_models(j, "model.json.build");
  const SelectedLinearModel &m = models.at("bvh:builder=spatial"), &r = back.at("bvh:builder=spatial");
  EXPECT_EQ(r.terms, m.terms);
  EXPECT_EQ(r.values, m.values);
  EXPECT_EQ(r.log_q90, m.log_q90);
  EXPECT_EQ(r.range_hi, m.range_hi);

  nlohmann::ordered_json bad = j;
  bad["bvh:builder=spatial"]["terms"][0] = "n_squared";
  try {
    read_build_time_models(bad, "model.json.build");
    ADD_FAILURE() << "an unknown term was read";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("model.json.build.bvh:builder=spatial.terms"), std::string::npos) << err.what();
  }
  bad = j;
  bad["bvh:builder=spatial"]["values"].push_back(1.0);
  EXPECT_THROW(read_build_time_models(bad, "model.json.build"), InputError);
  bad = j;
  bad["bvh:builder=spatial"].erase("range");
  EXPECT_THROW(read_build_time_models(bad, "model.json.build"), InputError);
}

TEST(BuildTimeModel, SpecsOfTheSameStructureFindTheSameEntry) {
  EXPECT_EQ(canonical_accel_spec("bvh"), canonical_accel_spec("bvh:width=8"));
  EXPECT_EQ(canonical_accel_spec("grid"), canonical_accel_spec("grid:d=3"));
  EXPECT_NE(canonical_accel_spec("grid"), canonical_accel_spec("grid:d=1"));
  // Trees built from fitted constants are one structure whichever model supplied them.
  EXPECT_EQ(canonical_accel_spec("bvh:cost=default"), canonical_accel_spec("bvh:width=8,cost=(/tmp/m.json)"));
  EXPECT_NE(canonical_accel_spec("bvh:cost=default"), canonical_accel_spec("bvh"));
  EXPECT_NE(canonical_accel_spec("kdtree:cost=default"), canonical_accel_spec("bvh:cost=default"));
  const std::map<std::string, int> models = {{"bvh", 1}, {"grid:d=1", 2}};
  ASSERT_NE(find_spec_model(models, "bvh:width=8"), nullptr);
  EXPECT_EQ(*find_spec_model(models, "bvh:width=8"), 1);
  EXPECT_EQ(find_spec_model(models, "bvh:width=4"), nullptr);
  EXPECT_EQ(find_spec_model(models, "grid"), nullptr);
  EXPECT_THROW(canonical_accel_spec("no-such-structure"), InputError);
}

TEST(SceneFeatures, CountAreasAndTheirSpread) {
  // Two unit right triangles and one 100 times larger: total 102 · 0.5, median 0.5, ratio 100.
  auto scene = std::make_shared<Scene>();
  scene->mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {10, 0, 1}, {0, 10, 1}};
  scene->mesh.triangles = {{0, 1, 2}, {0, 1, 2}, {3, 4, 5}};
  const SceneFeatures f = scene_features(*scene);
  EXPECT_EQ(f.triangles, 3.0);
  EXPECT_DOUBLE_EQ(f.total_area, 51.0);
  EXPECT_DOUBLE_EQ(f.median_area, 0.5);
  EXPECT_DOUBLE_EQ(f.area_ratio, 100.0);
  // The box 10 × 10 × 1: surface area 2·(100 + 10 + 10).
  EXPECT_DOUBLE_EQ(f.box_area, 240.0);
  EXPECT_DOUBLE_EQ(f.crossings, 51.0 / 240.0);
  // A uniform mesh has a small spread.
  const SceneFeatures sphere = scene_features(*make_scene("sphere:n=2000"));
  EXPECT_LT(sphere.area_ratio, 4.0);
  EXPECT_NEAR(sphere.crossings, 4 * M_PI / 24, 0.02);  // 4πr² over the box 6·(2r)²
}

TEST(SceneFeatures, TheSpreadEstimatesTheReferencesOfAGridOfNCells) {
  // N + spread_references against the references grid:d=1 places (clipped, one per cell a
  // triangle meets): a closed mesh, a soup of random triangles and a sphereflake of several sizes.
  for (const char* spec : {"sphere:n=3000", "soup:n=3000,seed=3", "sphereflake:depth=1,as=triangles"}) {
    const auto scene = make_scene(spec);
    const SceneFeatures f = scene_features(*scene);
    const auto grid = make_accelerator("grid:d=1", scene);
    const double counted = static_cast<double>(tree_features(*grid, *scene).references);
    const double estimated = f.primitives + spread_references(f);
    EXPECT_GT(estimated, 0.75 * counted) << spec << ": estimated " << estimated << ", counted " << counted;
    EXPECT_LT(estimated, 1.25 * counted) << spec << ": estimated " << estimated << ", counted " << counted;
    // A property of the shape alone: the same scene scaled by 1000 has the same spread.
    const SceneFeatures scaled =
        scene_features(*make_scene("transformed:of=(" + std::string(spec) + "),scale=1000"));
    EXPECT_NEAR(spread_references(scaled), spread_references(f), 1e-4 * spread_references(f)) << spec;
  }
  // One unit triangle in its own box: h = the box's side, the spread (3/4)·P + (3/2)·A of it.
  auto one = std::make_shared<Scene>();
  one->mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0.5f, std::sqrt(3.0f) / 2, 0}};
  one->mesh.triangles = {{0, 1, 2}};
  const SceneFeatures f = scene_features(*one);
  EXPECT_NEAR(spread_references(f), 0.75 * 3 + 1.5 * std::sqrt(3.0) / 4, 1e-5);
  EXPECT_EQ(spread_references(SceneFeatures{}), 0.0);
}

TEST(SceneFeatures, TheSameOnOneThreadAndOnMany) {
  // Several chunks of the parallel pass: the features are bit for bit those of one thread, and
  // agree with a plain sequential sum of the areas.
  const auto scene = make_scene("soup:n=150000,seed=5");
  SceneFeatures one;
  tbb::task_arena(1).execute([&] { one = scene_features(*scene); });
  SceneFeatures many;
  tbb::task_arena(4).execute([&] { many = scene_features(*scene); });
  EXPECT_EQ(one.total_area, many.total_area);
  EXPECT_EQ(one.max_area, many.max_area);
  EXPECT_EQ(one.median_area, many.median_area);
  EXPECT_EQ(one.box_area, many.box_area);
  double total = 0, largest = 0;
  for (std::size_t t = 0; t < scene->mesh.size(); ++t) {
    const Vec3f a = scene->mesh.vertex(t, 0);
    const double area =
        0.5 * static_cast<double>(length(cross(scene->mesh.vertex(t, 1) - a, scene->mesh.vertex(t, 2) - a)));
    total += area;
    largest = std::max(largest, area);
  }
  EXPECT_NEAR(one.total_area, total, 1e-12 * total);
  EXPECT_EQ(one.max_area, largest);
  EXPECT_EQ(one.box_area, static_cast<double>(scene->mesh.bounds().surface_area()));
}

}  // namespace
}  // namespace raylab
