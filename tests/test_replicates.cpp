// Replicated timings and their bootstrap intervals (lib/cost/replicates.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "cost/fit.h"
#include "cost/replicates.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

TEST(Replicates, MedianAndCoefficientOfVariation) {
  EXPECT_DOUBLE_EQ(median({3, 1, 2}), 2.0);
  EXPECT_DOUBLE_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_TRUE(std::isnan(median({})));
  // mean 2, sample standard deviation 1
  EXPECT_NEAR(coefficient_of_variation({1, 2, 3}), 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(coefficient_of_variation({1})));
}

TEST(Replicates, PerRoundRatiosPairTheRoundsAndRefuseUnequalCounts) {
  EXPECT_EQ(per_round_ratios({2.0, 9.0, 4.0}, {1.0, 3.0, 8.0}), (std::vector<double>{2.0, 3.0, 0.5}));
  EXPECT_THROW(per_round_ratios({1.0, 2.0}, {1.0}), std::invalid_argument);
  ReplicateTiming t;
  t.ns = {{10.0, 20.0}, {5.0, 40.0}};
  EXPECT_EQ(t.ratios(1, 0), (std::vector<double>{0.5, 2.0}));
}

TEST(Replicates, BootstrapMedianIntervalHoldsTheMedianAndWidensWithTheSpread) {
  const std::vector<double> tight = {1.00, 1.01, 0.99, 1.02, 0.98, 1.00, 1.01};
  const std::vector<double> loose = {1.00, 1.30, 0.70, 1.40, 0.60, 1.00, 1.20};
  const IntervalEstimate a = bootstrap_median(tight), b = bootstrap_median(loose);
  EXPECT_DOUBLE_EQ(a.value, 1.00);
  EXPECT_EQ(a.replicates, 7);
  EXPECT_LE(a.lo, a.value);
  EXPECT_GE(a.hi, a.value);
  EXPECT_GE(a.lo, 0.98);
  EXPECT_LE(a.hi, 1.02);
  EXPECT_GT(b.hi - b.lo, 5 * (a.hi - a.lo));
  // The seed is fixed: the same data give the same interval.
  const IntervalEstimate again = bootstrap_median(loose);
  EXPECT_EQ(again.lo, b.lo);
  EXPECT_EQ(again.hi, b.hi);
  const IntervalEstimate constant = bootstrap_median({2, 2, 2, 2, 2});
  EXPECT_EQ(constant.lo, 2.0);
  EXPECT_EQ(constant.hi, 2.0);
  EXPECT_THROW(bootstrap_median({}), std::invalid_argument);
}

TEST(Replicates, BootstrapFitCoversTheTrueSlopeAndShrinksWithLessNoise) {
  // y = 2 + 0.5·x, each of 6 points replicated 7 times with ±noise.
  auto replicated = [](double noise) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-noise, noise);
    std::vector<std::vector<double>> reps;
    for (int x = 1; x <= 6; ++x) {
      reps.emplace_back();
      for (int r = 0; r < 7; ++r) reps.back().push_back((2 + 0.5 * x) * (1 + u(rng)));
    }
    return reps;
  };
  const std::vector<double> xs = {1, 2, 3, 4, 5, 6};
  const auto slope = [&](const std::vector<double>& y) {
    const FitResult f = fit_basis(xs, y, [](double x) { return x; });
    return std::vector<double>{f.values[1]};
  };
  const BootstrapFit noisy = bootstrap_fit(replicated(0.2), slope, 200);
  const BootstrapFit quiet = bootstrap_fit(replicated(0.02), slope, 200);
  ASSERT_EQ(noisy.parameters.size(), 1u);
  EXPECT_EQ(noisy.parameters[0].replicates, 7);
  EXPECT_DOUBLE_EQ(noisy.finite_fraction[0], 1.0);
  EXPECT_LT(quiet.parameters[0].lo, 0.5);
  EXPECT_GT(quiet.parameters[0].hi, 0.5);
  EXPECT_LT(noisy.parameters[0].lo, 0.5);
  EXPECT_GT(noisy.parameters[0].hi, 0.5);
  EXPECT_LT(quiet.parameters[0].hi - quiet.parameters[0].lo, 0.5 * (noisy.parameters[0].hi - noisy.parameters[0].lo));
  EXPECT_THROW(bootstrap_fit({{1.0}, {}}, slope, 10), std::invalid_argument);
}

TEST(Replicates, FitEachRoundCancelsASlowSpellCommonToARound) {
  // y = 2 + 0.5·x at 6 points measured in the same 9 rounds; round r slows every point by a common
  // factor of up to 30% (a slow spell of the machine), and each point has ±1% of its own noise.
  // The slope over the intercept does not see the common factor: fitted round by round, its
  // interval is narrow and covers 0.25; resampled point by point, the common factor widens it.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> spell(1.0, 1.3), own(-0.01, 0.01);
  std::vector<double> round_factor(9);
  for (double& f : round_factor) f = spell(rng);
  std::vector<std::vector<double>> reps;
  for (int x = 1; x <= 6; ++x) {
    reps.emplace_back();
    for (double f : round_factor) reps.back().push_back((2 + 0.5 * x) * f * (1 + own(rng)));
  }
  const std::vector<double> xs = {1, 2, 3, 4, 5, 6};
  const auto slope_over_intercept = [&](const std::vector<double>& y) {
    const FitResult f = fit_basis(xs, y, [](double x) { return x; });
    return std::vector<double>{f.values[1] / f.values[0]};
  };
  const BootstrapFit per_round = fit_each_round(reps, slope_over_intercept, 500);
  const IntervalEstimate paired = per_round.parameters[0];
  const IntervalEstimate independent = bootstrap_fit(reps, slope_over_intercept, 500).parameters[0];
  EXPECT_EQ(paired.replicates, 9);
  EXPECT_DOUBLE_EQ(per_round.finite_fraction[0], 1.0);
  EXPECT_LT(paired.lo, 0.25);
  EXPECT_GT(paired.hi, 0.25);
  EXPECT_LT(paired.hi - paired.lo, 0.5 * (independent.hi - independent.lo));
  // A round whose fit is not finite is left out and counted.
  const BootstrapFit some_infinite = fit_each_round(reps, [&](const std::vector<double>& y) {
    return std::vector<double>{y[0] > 2.5 * 1.15 ? INFINITY : y[0]};
  });
  EXPECT_LT(some_infinite.finite_fraction[0], 1.0);
  EXPECT_EQ(some_infinite.parameters[0].replicates,
            static_cast<int>(std::lround(some_infinite.finite_fraction[0] * 9)));
  reps.back().pop_back();
  EXPECT_THROW(fit_each_round(reps, slope_over_intercept, 10), std::invalid_argument);
  EXPECT_THROW(fit_each_round({}, slope_over_intercept, 10), std::invalid_argument);
}

TEST(Replicates, GeometricMeanByRoundTakesEachRoundAcrossCases) {
  // Two cases, five rounds: round r's geometric mean is sqrt(a[r]·b[r]).
  const std::vector<double> a = {1, 4, 2, 2, 8}, b = {4, 1, 2, 8, 2};
  const IntervalEstimate g = geometric_mean_by_round({a, b});
  EXPECT_EQ(g.replicates, 5);
  EXPECT_NEAR(g.value, 2.0, 1e-12);  // rounds: 2, 2, 2, 4, 4
  EXPECT_NEAR(g.lo, 2.0, 1e-12);
  EXPECT_LE(g.hi, 4.0 + 1e-12);
  // One case: its own median and interval.
  const IntervalEstimate one = geometric_mean_by_round({a});
  EXPECT_DOUBLE_EQ(one.value, bootstrap_median(a).value);
  EXPECT_DOUBLE_EQ(one.lo, bootstrap_median(a).lo);
  EXPECT_THROW(geometric_mean_by_round({}), std::invalid_argument);
  EXPECT_THROW(geometric_mean_by_round({a, {1, 2}}), std::invalid_argument);
  EXPECT_THROW(geometric_mean_by_round({{1, 0, 2}}), std::invalid_argument);
}

TEST(Replicates, AlternateRoundsReversesTheOrderEveryOtherRound) {
  std::vector<int> calls;
  const auto contender = [&](int id) { return [&calls, id] { calls.push_back(id); return static_cast<double>(id); }; };
  const auto seconds = alternate_rounds({contender(0), contender(1), contender(2)}, 4);
  EXPECT_EQ(calls, (std::vector<int>{0, 1, 2, 2, 1, 0, 0, 1, 2, 2, 1, 0}));
  ASSERT_EQ(seconds.size(), 3u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(seconds[c], std::vector<double>(4, c)) << c;
}

TEST(Replicates, TimeReplicatesGivesOneTimePerContenderAndRound) {
  const auto scene = make_scene("sphere:n=200");
  const auto bvh = make_accelerator("bvh", scene);
  const auto brute = make_accelerator("brute", scene);
  const std::vector<Ray> rays = make_ray_set("primary:256", scene);
  ReplicateOptions o;
  o.rounds = 5;
  const ReplicateTiming t = time_replicates({bvh.get(), brute.get()}, rays, o);
  ASSERT_EQ(t.ns.size(), 2u);
  EXPECT_EQ(t.rounds(), 5);
  EXPECT_TRUE(t.thread_cpu);
  for (const auto& c : t.ns)
    for (double ns : c) EXPECT_GT(ns, 0.0);
  const IntervalEstimate r = t.ratio(1, 0);
  EXPECT_EQ(r.replicates, 5);
  EXPECT_LE(r.lo, r.value);
  EXPECT_GE(r.hi, r.value);
  EXPECT_THROW(time_replicates({}, rays, o), std::invalid_argument);
  o.rounds = 0;
  EXPECT_THROW(time_replicates({bvh.get()}, rays, o), std::invalid_argument);
}

TEST(Replicates, TimeReplicatesOfCasesTimesEachOnItsOwnRays) {
  const auto scene = make_scene("sphere:n=200");
  const auto bvh = make_accelerator("bvh", scene);
  const std::vector<Ray> primary = make_ray_set("primary:256", scene), diffuse = make_ray_set("diffuse:64", scene);
  const std::vector<Ray> none;
  ReplicateOptions o;
  o.rounds = 3;
  const ReplicateTiming t = time_replicates({{bvh.get(), &primary}, {bvh.get(), &diffuse}, {bvh.get(), &primary}}, o);
  ASSERT_EQ(t.ns.size(), 3u);
  EXPECT_EQ(t.rounds(), 3);
  for (const auto& c : t.ns)
    for (double ns : c) EXPECT_GT(ns, 0.0);
  EXPECT_THROW(time_replicates(std::vector<TimedCase>{}, o), std::invalid_argument);
  EXPECT_THROW(time_replicates({{bvh.get(), &none}}, o), std::invalid_argument);
  EXPECT_THROW(time_replicates({{bvh.get(), nullptr}}, o), std::invalid_argument);
  EXPECT_THROW(time_replicates({{nullptr, &primary}}, o), std::invalid_argument);
  o.rounds = 0;
  EXPECT_THROW(time_replicates({{bvh.get(), &primary}}, o), std::invalid_argument);
}

}  // namespace
}  // namespace raylab
