#include "cost/replicates.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "accel/common/tracer.h"

namespace raylab {
namespace {

/// The q-quantile of sorted `v` by linear interpolation between order statistics.
double quantile_of_sorted(const std::vector<double>& v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

IntervalEstimate percentile_interval(double value, std::vector<double> resampled, int replicates) {
  std::sort(resampled.begin(), resampled.end());
  IntervalEstimate out;
  out.value = value;
  out.lo = quantile_of_sorted(resampled, 0.025);
  out.hi = quantile_of_sorted(resampled, 0.975);
  out.replicates = replicates;
  return out;
}

}  // namespace

double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const std::size_t m = values.size() / 2;
  return values.size() % 2 ? values[m] : 0.5 * (values[m - 1] + values[m]);
}

double quantile90(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(values.size())));
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(std::max<std::size_t>(rank, 1) - 1);
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

double coefficient_of_variation(const std::vector<double>& values) {
  if (values.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  double mean = 0;
  for (double v : values) mean += v;
  mean /= static_cast<double>(values.size());
  double ss = 0;
  for (double v : values) ss += (v - mean) * (v - mean);
  if (mean == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(ss / static_cast<double>(values.size() - 1)) / std::abs(mean);
}

IntervalEstimate bootstrap_median(const std::vector<double>& values, int resamples, std::uint64_t seed) {
  if (values.empty()) throw std::invalid_argument("bootstrap_median: no values");
  if (resamples < 1) throw std::invalid_argument("bootstrap_median: resamples must be positive");
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  std::vector<double> draw(values.size()), medians(static_cast<std::size_t>(resamples));
  for (double& m : medians) {
    for (double& d : draw) d = values[pick(rng)];
    m = median(draw);
  }
  return percentile_interval(median(values), std::move(medians), static_cast<int>(values.size()));
}

BootstrapFit bootstrap_fit(const std::vector<std::vector<double>>& replicates,
                           const std::function<std::vector<double>(const std::vector<double>&)>& fit, int resamples,
                           std::uint64_t seed) {
  if (replicates.empty()) throw std::invalid_argument("bootstrap_fit: no points");
  if (resamples < 1) throw std::invalid_argument("bootstrap_fit: resamples must be positive");
  std::size_t fewest = replicates.front().size();
  std::vector<double> medians;
  for (const auto& r : replicates) {
    if (r.empty()) throw std::invalid_argument("bootstrap_fit: a point without replicates");
    fewest = std::min(fewest, r.size());
    medians.push_back(median(r));
  }
  const std::vector<double> values = fit(medians);
  std::vector<std::vector<double>> resampled(values.size());
  std::mt19937_64 rng(seed);
  std::vector<double> point(replicates.size()), draw;
  for (int b = 0; b < resamples; ++b) {
    for (std::size_t i = 0; i < replicates.size(); ++i) {
      const auto& r = replicates[i];
      std::uniform_int_distribution<std::size_t> pick(0, r.size() - 1);
      draw.resize(r.size());
      for (double& d : draw) d = r[pick(rng)];
      point[i] = median(draw);
    }
    const std::vector<double> p = fit(point);
    if (p.size() != values.size()) throw std::logic_error("bootstrap_fit: the fit changed its parameter count");
    for (std::size_t k = 0; k < p.size(); ++k)
      if (std::isfinite(p[k])) resampled[k].push_back(p[k]);
  }
  BootstrapFit out;
  for (std::size_t k = 0; k < values.size(); ++k) {
    out.finite_fraction.push_back(static_cast<double>(resampled[k].size()) / resamples);
    out.parameters.push_back(percentile_interval(values[k], std::move(resampled[k]), static_cast<int>(fewest)));
  }
  return out;
}

BootstrapFit fit_each_round(const std::vector<std::vector<double>>& replicates,
                            const std::function<std::vector<double>(const std::vector<double>&)>& fit, int resamples,
                            std::uint64_t seed) {
  if (replicates.empty() || replicates.front().empty()) throw std::invalid_argument("fit_each_round: no points or no rounds");
  const std::size_t rounds = replicates.front().size();
  for (const auto& r : replicates)
    if (r.size() != rounds) throw std::invalid_argument("fit_each_round: points with unequal round counts");
  std::vector<std::vector<double>> by_parameter;  // [parameter][kept round]
  std::vector<double> point(replicates.size());
  for (std::size_t r = 0; r < rounds; ++r) {
    for (std::size_t i = 0; i < replicates.size(); ++i) point[i] = replicates[i][r];
    const std::vector<double> p = fit(point);
    if (r == 0) by_parameter.resize(p.size());
    if (p.size() != by_parameter.size()) throw std::logic_error("fit_each_round: the fit changed its parameter count");
    for (std::size_t k = 0; k < p.size(); ++k)
      if (std::isfinite(p[k])) by_parameter[k].push_back(p[k]);
  }
  BootstrapFit out;
  for (const auto& values : by_parameter) {
    out.finite_fraction.push_back(static_cast<double>(values.size()) / static_cast<double>(rounds));
    if (values.empty()) {
      out.parameters.push_back(IntervalEstimate{});
      continue;
    }
    out.parameters.push_back(bootstrap_median(values, resamples, seed));
  }
  return out;
}

IntervalEstimate geometric_mean_by_round(const std::vector<std::vector<double>>& values, int resamples,
                                         std::uint64_t seed) {
  if (values.empty() || values.front().empty())
    throw std::invalid_argument("geometric_mean_by_round: no cases or no rounds");
  const std::size_t rounds = values.front().size();
  std::vector<double> by_round(rounds, 0.0);
  for (const auto& c : values) {
    if (c.size() != rounds) throw std::invalid_argument("geometric_mean_by_round: cases with unequal round counts");
    for (std::size_t r = 0; r < rounds; ++r) {
      if (!(c[r] > 0)) throw std::invalid_argument("geometric_mean_by_round: a value that is not positive");
      by_round[r] += std::log(c[r]);
    }
  }
  for (double& g : by_round) g = std::exp(g / static_cast<double>(values.size()));
  return bootstrap_median(by_round, resamples, seed);
}

std::vector<double> per_round_ratios(const std::vector<double>& numerator, const std::vector<double>& denominator) {
  if (numerator.size() != denominator.size())
    throw std::invalid_argument("per_round_ratios: " + std::to_string(numerator.size()) + " rounds against " +
                                std::to_string(denominator.size()));
  std::vector<double> r(numerator.size());
  for (std::size_t i = 0; i < r.size(); ++i) r[i] = numerator[i] / denominator[i];
  return r;
}

std::vector<double> ReplicateTiming::ratios(std::size_t numerator, std::size_t denominator) const {
  return per_round_ratios(ns.at(numerator), ns.at(denominator));
}

std::vector<std::vector<double>> alternate_rounds(const std::vector<std::function<double()>>& measure, int rounds) {
  std::vector<std::vector<double>> seconds(measure.size());
  const std::size_t n = measure.size();
  for (int r = 0; r < rounds; ++r)
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t c = r % 2 == 0 ? i : n - 1 - i;  // ABBA: no contender always runs first
      seconds[c].push_back(measure[c]());
    }
  return seconds;
}

ReplicateTiming time_replicates(const std::vector<TimedCase>& cases, const ReplicateOptions& options) {
  if (cases.empty()) throw std::invalid_argument("time_replicates: no contenders");
  for (const TimedCase& c : cases) {
    if (!c.primitive) throw std::invalid_argument("time_replicates: a contender without a structure");
    if (!c.rays || c.rays->empty()) throw std::invalid_argument("time_replicates: no rays");
  }
  if (options.rounds < 1) throw std::invalid_argument("time_replicates: fewer than one round");
  const TraceOptions trace{options.threads, false, options.any_hit};
  ReplicateTiming t;
  t.thread_cpu = resolve_thread_count(options.threads) == 1;
  std::vector<std::function<double()>> measure;
  for (const TimedCase& c : cases)
    measure.push_back([&, c] {
      double best = std::numeric_limits<double>::infinity(), spent = 0;
      for (int pass = 0; pass < 1000 && (pass == 0 || spent < options.min_round_seconds); ++pass) {
        const TraceResult r = trace_rays(*c.primitive, *c.rays, trace);
        const double s = t.thread_cpu ? r.thread_cpu_seconds : r.seconds;
        best = std::min(best, s);
        spent += s;
      }
      return best * 1e9 / static_cast<double>(c.rays->size());
    });
  t.ns = alternate_rounds(measure, options.rounds);
  return t;
}

ReplicateTiming time_replicates(const std::vector<const Primitive*>& contenders, const std::vector<Ray>& rays,
                                const ReplicateOptions& options) {
  std::vector<TimedCase> cases;
  for (const Primitive* p : contenders) cases.push_back({p, &rays});
  return time_replicates(cases, options);
}

std::string format_interval(const IntervalEstimate& i, int digits) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.*g [%.*g, %.*g]", digits, i.value, digits, i.lo, digits, i.hi);
  return buf;
}

}  // namespace raylab
