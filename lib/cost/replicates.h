#pragma once
/// Replicated timings and their 95% intervals, shared by the experiments whose figures are times
/// or ratios of times (exp_noise_floor, exp_spatial, exp_grids, exp_bvh).
///
/// Replicates. A figure is measured in k alternated rounds: in each round every contender (our
/// structure, Embree, ...) traces the same rays in turn, so that a slow spell of a shared machine
/// falls on all of them alike; each round gives one time per contender, and a ratio of two
/// contenders one ratio per round. Single-threaded rounds are timed in the tracing thread's CPU
/// time (TraceResult::thread_cpu_seconds, as lib/cost/timing.h explains), multi-threaded ones in
/// the wall clock. All rounds run in one process: the rays, scenes and structures are built once
/// and shared, so what a round measures is the traversal, not allocation or page placement.
///
/// Intervals. The figure is the median over the rounds; its 95% interval is the percentile
/// bootstrap of that median (B. Efron and R. Tibshirani, *An Introduction to the Bootstrap*,
/// Chapman & Hall 1993, ch. 13): the rounds resampled with replacement `resamples` times with a
/// fixed seed, the 2.5% and 97.5% quantiles of the resampled medians. A ratio's interval is that
/// of the median of the per-round ratios (not Fieller's interval of a ratio of means).
///
/// Fits over replicated points (bootstrap_fit): each point's value is the median of its
/// replicates, and a fitted parameter's interval comes from resampling every point's replicate
/// set, taking the medians and refitting: the spread a rerun of the whole measurement would show,
/// rather than the standard error of one fit to points each measured once.
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "geometry/ray.h"
#include "scene/primitive.h"

namespace raylab {

inline constexpr int kBootstrapResamples = 2000;
inline constexpr std::uint64_t kBootstrapSeed = 20261204;

/// A figure from replicates: the point value, its 95% interval [lo, hi] and the replicates behind it.
struct IntervalEstimate {
  double value = std::numeric_limits<double>::quiet_NaN();
  double lo = std::numeric_limits<double>::quiet_NaN();
  double hi = std::numeric_limits<double>::quiet_NaN();
  int replicates = 0;  ///< rounds (a timing) or rounds per point (a fit)
  bool defined() const { return lo <= hi; }
};

/// The median of `values` (NaN for none).
double median(std::vector<double> values);

/// The 90% quantile of `values` by nearest rank (the ⌈0.9·n⌉-th smallest; NaN for none).
double quantile90(std::vector<double> values);

/// Standard deviation over mean (sample standard deviation, n − 1); NaN for fewer than two values
/// or a zero mean.
double coefficient_of_variation(const std::vector<double>& values);

/// The median of `values` with its percentile-bootstrap 95% interval. Throws std::invalid_argument
/// for no values or a non-positive resample count.
IntervalEstimate bootstrap_median(const std::vector<double>& values, int resamples = kBootstrapResamples,
                          std::uint64_t seed = kBootstrapSeed);

/// Parameters fitted to replicated points, with percentile-bootstrap 95% intervals.
/// `replicates[i]` holds point i's replicate values (each point at least one); `fit` maps one value
/// per point to the parameters (always the same count). The values are fit(medians); each
/// resample draws every point's replicates with replacement, takes their medians and refits.
/// Resamples whose fit gives a non-finite parameter are left out of that parameter's quantiles
/// (`finite_fraction` says how many were kept); every IntervalEstimate's `replicates` is the smallest
/// replicate count over the points.
struct BootstrapFit {
  std::vector<IntervalEstimate> parameters;
  std::vector<double> finite_fraction;  ///< per parameter: resamples with a finite value / resamples
};
BootstrapFit bootstrap_fit(const std::vector<std::vector<double>>& replicates,
                           const std::function<std::vector<double>(const std::vector<double>&)>& fit,
                           int resamples = kBootstrapResamples, std::uint64_t seed = kBootstrapSeed);
/// For points measured in the same alternated rounds (time_replicates): `fit` applied to each
/// round's points alone, and every parameter the median over the rounds with its percentile-
/// bootstrap 95% interval (bootstrap_median; `replicates` is the count of rounds whose fit gave a
/// finite value, `finite_fraction` their share). A slow spell that fell on a whole round scales
/// that round's curve and leaves a scale-free parameter (a ratio of times, an optimum) unchanged,
/// as the per-round ratios to Embree do; bootstrap_fit, which resamples every point's rounds on
/// its own, would let the spell bend the curve. Throws std::invalid_argument for no points, no
/// rounds or unequal round counts.
BootstrapFit fit_each_round(const std::vector<std::vector<double>>& replicates,
                            const std::function<std::vector<double>(const std::vector<double>&)>& fit,
                            int resamples = kBootstrapResamples, std::uint64_t seed = kBootstrapSeed);

struct ReplicateOptions {
  int rounds = 5;                  ///< alternated rounds (at least 1; the report uses at least 5)
  double min_round_seconds = 0.0;  ///< within a round, each contender traces until this much time
                                   ///< (at least one pass); its fastest pass is the round's time
  int threads = 1;                 ///< tracing threads (1: thread CPU time; more: wall clock)
  bool any_hit = false;            ///< occluded() queries instead of intersect()
};

/// numerator[r] / denominator[r] for every round r of two figures measured in the same alternated
/// rounds. Throws std::invalid_argument when their round counts differ.
std::vector<double> per_round_ratios(const std::vector<double>& numerator, const std::vector<double>& denominator);

/// Times per ray of several contenders over alternated rounds: ns[c][r] is contender c in round r.
struct ReplicateTiming {
  std::vector<std::vector<double>> ns;
  bool thread_cpu = false;  ///< timed in the tracing thread's CPU time (threads = 1)
  int rounds() const { return ns.empty() ? 0 : static_cast<int>(ns.front().size()); }
  /// ns[numerator][r] / ns[denominator][r] for every round r: with Embree's time over ours, the
  /// throughput relative to Embree (> 1: ours is faster).
  std::vector<double> ratios(std::size_t numerator, std::size_t denominator) const;
  IntervalEstimate ns_per_ray(std::size_t contender) const { return bootstrap_median(ns.at(contender)); }
  IntervalEstimate ratio(std::size_t numerator, std::size_t denominator) const {
    return bootstrap_median(ratios(numerator, denominator));
  }
};

/// Traces `rays` with every one of `contenders` in each of `options.rounds` rounds, in turn.
/// Throws std::invalid_argument for no contenders, no rays or fewer than one round.
ReplicateTiming time_replicates(const std::vector<const Primitive*>& contenders, const std::vector<Ray>& rays,
                                const ReplicateOptions& options);

/// One contender of a comparison across scenes: a structure and the rays it traces (both outlive
/// the call).
struct TimedCase {
  const Primitive* primitive = nullptr;
  const std::vector<Ray>* rays = nullptr;
};
/// As above, each contender on its own rays: the cases of a curve (one per angle, resolution or
/// scene) share every round, so a slow spell of a shared machine bends no curve. ns[c][r] is
/// case c's time per ray in round r. Throws std::invalid_argument for no cases, a case without a
/// primitive or rays, or fewer than one round.
ReplicateTiming time_replicates(const std::vector<TimedCase>& cases, const ReplicateOptions& options);

/// `rounds` alternated rounds of arbitrary timed work: seconds[c][r] = measure[c]() in round r,
/// the contenders called in turn within each round (builds, for example, timed by the caller):
/// in the given order in even rounds and in reverse in odd ones (ABBA), so that no contender
/// always runs first, after another's work has warmed or evicted the caches.
std::vector<std::vector<double>> alternate_rounds(const std::vector<std::function<double()>>& measure, int rounds);

/// The geometric mean of a ratio over several cases, replicated round by round: `values[c][r]` is
/// case c's figure in round r (every case measured in the same number of alternated rounds), and
/// round r's replicate is exp(mean over c of log values[c][r]), the geometric mean of the cases
/// as round r measured them. Returns the median over the rounds with its percentile-bootstrap
/// 95% interval (bootstrap_median; `replicates` is the round count). Throws
/// std::invalid_argument for no cases, no rounds, unequal round counts or a value ≤ 0.
IntervalEstimate geometric_mean_by_round(const std::vector<std::vector<double>>& values,
                                         int resamples = kBootstrapResamples, std::uint64_t seed = kBootstrapSeed);

/// "1.23 [1.10, 1.31]" with `digits` significant digits.
std::string format_interval(const IntervalEstimate& i, int digits = 3);

}  // namespace raylab
