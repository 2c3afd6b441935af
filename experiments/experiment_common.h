#pragma once
/// Shared plumbing of the experiment binaries: options (--mode quick|full, --out DIR), timing
/// by repetition, CSV output, and the provenance every result page states.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "cost/csv.h"
#include "cost/fit.h"
#include "scene/primitive.h"
#include "geometry/input_error.h"
#include "geometry/spec_string.h"

namespace raylab::experiments {

struct Options {
  std::string mode = "quick";  ///< quick: the default `./lab report`; full: `./lab report --full`
  std::string out = "docs/results";
  std::string runs;  ///< exp_cost_model: take the cost model's data set from this runs CSV instead of sweeping
  std::string claim;  ///< empty: every claim of the experiment; else only the part that decides this claim id
  bool full() const { return mode == "full"; }
  /// Whether the part deciding claim `id` (or any of `ids`) runs: every part when no --claim was given.
  bool runs_claim(std::initializer_list<const char*> ids) const {
    if (claim.empty()) return true;
    for (const char* id : ids)
      if (claim == id) return true;
    return false;
  }
};

/// Parses the common options; exits with a one-line error on bad ones (experiment_common.cpp).
Options parse_options(int argc, char** argv, const std::string& description);

/// Trace time per ray on `threads` threads (single-thread by default), in nanoseconds: the trace
/// is repeated until at least `min_seconds` have been spent and the fastest repetition is kept.
/// A single-thread trace is timed in the tracing thread's CPU time (TraceResult::
/// thread_cpu_seconds), which leaves out the time a shared machine kept it waiting for a core
/// (as the cost model's sweep does); several threads in wall clock.
inline double ns_per_ray(const Primitive& accel, const std::vector<Ray>& rays, bool any_hit, double min_seconds = 0.2,
                         int threads = 1) {
  double best = 1e300, spent = 0;
  int reps = 0;
  while (spent < min_seconds || reps < 2) {
    const TraceResult r = trace_rays(accel, rays, TraceOptions{threads, false, any_hit});
    const double s = threads == 1 ? r.thread_cpu_seconds : r.seconds;
    best = std::min(best, s);
    spent += s;
    ++reps;
    if (reps >= 1000) break;
  }
  return best / static_cast<double>(rays.size()) * 1e9;
}

/// Work and time per ray of one accelerator on one ray set: a counted single-thread trace (the
/// counters stay 0 for accelerators that report none, e.g. Embree), then single-thread traces
/// repeated until `min_seconds` (at least two), keeping the fastest. Time is the tracing thread's
/// CPU time (TraceResult::thread_cpu_seconds), which leaves out the time a shared machine keeps
/// the thread waiting for a core, as the cost model's sweep does.
struct TraceCost {
  double nodes = 0, leaves = 0, tests = 0, hit_rate = 0, ns = 0;
  double ops() const { return nodes + leaves + tests; }  ///< node and leaf visits plus primitive tests
};

inline TraceCost trace_cost(const Aggregate& accel, const std::vector<Ray>& rays, bool any_hit, double min_seconds) {
  TraceCost c;
  const double n = static_cast<double>(rays.size());
  const TraceResult counted = trace_rays(accel, rays, TraceOptions{1, accel.reports_counters(), any_hit});
  c.nodes = static_cast<double>(counted.counters.nodes) / n;
  c.leaves = static_cast<double>(counted.counters.leaves) / n;
  c.tests = static_cast<double>(counted.counters.prim_tests) / n;
  c.hit_rate = static_cast<double>(counted.hit_count) / n;
  double best = 1e300, spent = 0;
  for (int rep = 0; rep < 1000 && (rep < 2 || spent < min_seconds); ++rep) {
    const double s = trace_rays(accel, rays, TraceOptions{1, false, any_hit}).thread_cpu_seconds;
    best = std::min(best, s);
    spent += s;
  }
  c.ns = best / n * 1e9;
  return c;
}

/// A claim's threshold, stated in docs/theory.md and in its section before any number: the rule
/// that turns the key number's 95% interval into a verdict (decide_verdict).
///   below:  the claim predicts key < value;   above: key > value;
///   within: the claim predicts |key − value| < tolerance (value the target, tolerance δ).
/// Claims whose verdict is conditional by nature ("holds only under stated conditions") state
/// their rule in `text` and decide it with decide_conditional.
struct Threshold {
  std::string text;       ///< the rule in words, as docs/theory.md states it
  std::string direction;  ///< below | above | within | conditional
  double value = std::numeric_limits<double>::quiet_NaN();
  double tolerance = std::numeric_limits<double>::quiet_NaN();  ///< within: δ
};

/// The number a verdict is decided from, with its 95% interval and what produced it.
struct KeyNumber {
  std::string name;  ///< what it is, e.g. "α of ops/ray ∝ N^α, dust"
  double value = std::numeric_limits<double>::quiet_NaN();
  double lo = std::numeric_limits<double>::quiet_NaN();  ///< the 95% interval [lo, hi]
  double hi = std::numeric_limits<double>::quiet_NaN();
  long replicates = 0;   ///< the n behind it: points of a fit, or replicate runs
  std::string spec;      ///< the full spec that produced it, defaults expanded (canonical_spec)
  std::string interval;  ///< how [lo, hi] was obtained, e.g. "± t(0.975, 10)·s.e. of the Ceres fit"
};

/// The 95% interval of a fitted parameter from its standard error, on `dof` = points − parameters
/// degrees of freedom: value ± t(0.975, dof)·s.e. (Student's t; it is 1.96 as dof → ∞). NaN
/// bounds when the s.e. is not finite or dof < 1.
KeyNumber fitted_key(std::string name, double value, double std_error, std::size_t points, std::size_t parameters,
                     std::string spec);

/// fitted_key for parameter `index` of `fit`.
inline KeyNumber fitted_key(std::string name, const FitResult& fit, std::size_t index, std::string spec) {
  return fitted_key(std::move(name), fit.values[index], fit.std_errors[index], fit.points, fit.values.size(),
                    std::move(spec));
}

inline const char* const kConfirmed = "confirmed";
inline const char* const kRefuted = "refuted";
inline const char* const kInconclusive = "inconclusive at this noise";
inline const char* const kConditional = "holds only under stated conditions";

/// The verdict the key number's 95% interval gives under `threshold`: confirmed where the whole
/// interval lies on the claim's side, refuted where it lies wholly on the other, inconclusive at
/// this noise where it straddles the threshold (or is undefined).
inline std::string decide_verdict(const KeyNumber& key, const Threshold& threshold) {
  if (!(key.lo <= key.hi)) return kInconclusive;
  const double v = threshold.value;
  if (threshold.direction == "below") return key.hi < v ? kConfirmed : key.lo > v ? kRefuted : kInconclusive;
  if (threshold.direction == "above") return key.lo > v ? kConfirmed : key.hi < v ? kRefuted : kInconclusive;
  if (threshold.direction == "within") {
    const double d = threshold.tolerance;
    if (key.lo > v - d && key.hi < v + d) return kConfirmed;
    return key.lo >= v + d || key.hi <= v - d ? kRefuted : kInconclusive;
  }
  throw std::logic_error("decide_verdict: threshold direction '" + threshold.direction + "'");
}

/// The verdict of a claim that holds on some cases and is stated to fail on others, from the
/// verdicts (decide_verdict) of the cases where it should hold and of those where it may fail:
/// confirmed if it holds everywhere, refuted if it holds nowhere it should, holds only under
/// stated conditions if every case is decided and both kinds occur, inconclusive at this noise
/// if any case is.
inline std::string decide_conditional(const std::vector<std::string>& cases) {
  bool any_confirmed = false, any_refuted = false;
  for (const auto& c : cases) {
    if (c == kInconclusive) return kInconclusive;
    any_confirmed |= c == kConfirmed;
    any_refuted |= c == kRefuted;
  }
  if (any_confirmed && any_refuted) return kConditional;
  return any_confirmed ? kConfirmed : any_refuted ? kRefuted : kInconclusive;
}

/// The verdict of a claim with a precondition: `cases[0]` must hold (refuted if it fails), and the
/// other cases decide between confirmed (all hold) and holds only under stated conditions;
/// inconclusive at this noise if any case is, or if there is none.
inline std::string decide_gated(const std::vector<std::string>& cases) {
  if (cases.empty()) return kInconclusive;
  for (const auto& c : cases)
    if (c == kInconclusive) return kInconclusive;
  if (cases[0] == kRefuted) return kRefuted;
  for (std::size_t i = 1; i < cases.size(); ++i)
    if (cases[i] != kConfirmed) return kConditional;
  return kConfirmed;
}

/// The verdict of a claim that must hold in every case: confirmed if every case is, refuted if any
/// case is, inconclusive at this noise otherwise.
inline std::string decide_all(const std::vector<std::string>& cases) {
  bool all_confirmed = !cases.empty();
  for (const auto& c : cases) {
    if (c == kRefuted) return kRefuted;
    all_confirmed &= c == kConfirmed;
  }
  return all_confirmed ? kConfirmed : kInconclusive;
}

/// A 95% interval from a mean and its standard error over many samples (normal approximation,
/// value ± 1.96·s.e.), e.g. a proportion over thousands of lines.
inline KeyNumber normal_key(std::string name, double value, double std_error, long samples, std::string spec) {
  KeyNumber k;
  k.name = std::move(name);
  k.value = value;
  k.lo = value - 1.96 * std_error;
  k.hi = value + 1.96 * std_error;
  k.replicates = samples;
  k.spec = std::move(spec);
  k.interval = "± 1.96·s.e. (normal approximation over " + std::to_string(samples) + " samples)";
  return k;
}

/// One verdict of the report's summary table. Each experiment writes the verdicts of its section
/// to <section>.verdicts.csv (write_verdicts); make_report.py gathers every such file into the
/// table that opens docs/results/README.md, the list that closes it and results.json, so none is
/// edited by hand.
struct Verdict {
  std::string claim;    ///< "1", "1b", "6a", ...: the order of the summary table
  std::string title;    ///< the claim in a few words
  std::string verdict;  ///< confirmed | refuted | inconclusive at this noise | holds only under stated conditions
  std::string key;      ///< the key number, with its uncertainty, in words
  std::string anchor;   ///< the id of the section's HTML anchor (section_anchor)
  KeyNumber number = {};       ///< the key number the verdict is decided from
  Threshold threshold = {};    ///< the rule, stated before the measurement
  std::string command = {};    ///< the command that reproduces this claim alone
  /// A verdict combined from several decided parts (claim 6a: one per scene), each a key number
  /// under its own threshold; parts[0] is `number`. `parts_rule` names the combination:
  /// "conditional" (decide_conditional) or "gated" (decide_gated). Written to
  /// <section>.verdict_parts.csv, so that a claim replicated in separate processes is decided again
  /// part by part (experiments/process_replicates.py). Empty: `number` alone decides.
  std::vector<std::pair<KeyNumber, Threshold>> parts = {};
  std::string parts_rule = {};
};

/// decide_verdict of every part of `v`, combined by its parts_rule.
inline std::string decide_parts(const Verdict& v) {
  std::vector<std::string> cases;
  for (const auto& [key, threshold] : v.parts) cases.push_back(decide_verdict(key, threshold));
  if (v.parts_rule == "conditional") return decide_conditional(cases);
  if (v.parts_rule == "gated") return decide_gated(cases);
  throw std::logic_error("decide_parts: rule '" + v.parts_rule + "'");
}

/// The line that opens a section with an anchor the summary table links to.
inline std::string section_anchor(const std::string& id) { return "<a id=\"" + id + "\"></a>\n\n"; }

/// "0.152 (95% interval [0.115, 0.189], n = 6)", with enough significant digits to resolve the
/// interval's width (at least 3).
inline std::string interval_text(const KeyNumber& k) {
  int digits = 3;
  const double width = k.hi - k.lo, scale = std::max({std::abs(k.value), std::abs(k.lo), std::abs(k.hi)});
  if (std::isfinite(width) && width > 0 && scale > 0)
    digits = std::clamp(static_cast<int>(std::ceil(std::log10(scale / width))) + 2, 3, 10);
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.*g (95%% interval [%.*g, %.*g], n = %ld)", digits, k.value, digits, k.lo, digits,
                k.hi, k.replicates);
  return buf;
}

/// The paragraph that states a claim's threshold, before any of its numbers, with the command
/// that reproduces the claim.
inline std::string threshold_paragraph(const Verdict& v) {
  std::string p = "**Threshold (claim " + v.claim + "), stated before measuring:** " + v.threshold.text + "\n\n";
  if (!v.command.empty()) p += "Reproduce: `" + v.command + "`\n\n";
  return p;
}

/// The paragraph that states a claim's verdict at the end of its section, opened by the anchor
/// `verdict-<claim>` that the summary table links to.
inline std::string verdict_paragraph(const Verdict& v, const std::string& reason) {
  std::string p = "<a id=\"verdict-" + v.claim + "\"></a>**Verdict (claim " + v.claim + "): " + v.verdict + ".** " + v.key + ".";
  if (!v.number.name.empty())
    p += " Key number: " + v.number.name + " = " + interval_text(v.number) + (v.number.spec.empty() ? "" : ", spec `" + v.number.spec + "`") + ".";
  return p + " " + reason + "\n\n";
}

inline double seconds_of(const std::function<void()>& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// CPU time of the calling thread spent in `f` (CLOCK_THREAD_CPUTIME_ID): on a shared machine it
/// leaves out the time the thread waited for a core. Only for work done on the calling thread.
/// Runs on the timing CPU when `RAYLAB_TIMING_CPU` names one (accel/common/timing_cpu.h).
inline double thread_cpu_seconds_of(const std::function<void()>& f) {
  const TimingCpuScope pinned;
  timespec start{}, end{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
  f();
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &end);
  return static_cast<double>(end.tv_sec - start.tv_sec) + 1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec);
}

/// A CSV file written row by row. Contract: every row has one value per column (std::logic_error
/// otherwise, before anything of the row is written).
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& columns)
      : out_(path), path_(path), columns_(columns.size()) {
    if (!out_) throw InputError("cannot write " + path);
    for (std::size_t i = 0; i < columns.size(); ++i) out_ << (i ? "," : "") << columns[i];
    out_ << "\n";
  }
  template <class... T>
  void row(const T&... values) {
    if (sizeof...(T) != columns_)
      throw std::logic_error(path_ + ": a row of " + std::to_string(sizeof...(T)) + " values for " +
                             std::to_string(columns_) + " columns");
    std::size_t i = 0;
    ((out_ << (i++ ? "," : "") << field(values)), ...);
    out_ << "\n";
    out_.flush();
  }

 private:
  static std::string field(const std::string& s) { return csv_field(s); }
  static std::string field(const char* s) { return field(std::string(s)); }
  template <class T>
  static const T& field(const T& v) {
    return v;
  }

  std::ofstream out_;
  std::string path_;
  std::size_t columns_;
};

/// Writes `verdicts` to OUT/<section>.verdicts.csv (replacing an earlier run's).
/// The first five columns are the summary table's; the rest are the structured key number and
/// threshold that results.json carries (make_report.py). The parts of verdicts that have them go to
/// OUT/<section>.verdict_parts.csv, one row per part (none: no such file). Throws std::logic_error,
/// before writing anything, where a verdict's parts do not decide its verdict.
inline void write_verdicts(const std::string& out_dir, const std::string& section, const std::vector<Verdict>& verdicts) {
  for (const auto& v : verdicts)
    if (!v.parts.empty() && (v.parts.front().first.name != v.number.name || decide_parts(v) != v.verdict))
      throw std::logic_error("write_verdicts: claim " + v.claim + ": parts[0] is not the key number, or the parts "
                             "decide another verdict than the row's");
  CsvWriter csv(out_dir + "/" + section + ".verdicts.csv",
                {"claim", "title", "verdict", "key", "anchor", "key_name", "key_value", "ci95_lo", "ci95_hi",
                 "replicates", "spec", "interval", "threshold", "threshold_direction", "threshold_value",
                 "threshold_tolerance", "command"});
  for (const auto& v : verdicts)
    csv.row(v.claim, v.title, v.verdict, v.key, v.anchor, v.number.name, v.number.value, v.number.lo, v.number.hi,
            v.number.replicates, v.number.spec, v.number.interval, v.threshold.text, v.threshold.direction,
            v.threshold.value, v.threshold.tolerance, v.command);
  const std::string parts_path = out_dir + "/" + section + ".verdict_parts.csv";
  std::filesystem::remove(parts_path);
  if (std::none_of(verdicts.begin(), verdicts.end(), [](const Verdict& v) { return !v.parts.empty(); })) return;
  CsvWriter parts(parts_path, {"claim", "rule", "part", "name", "key_value", "ci95_lo", "ci95_hi", "replicates",
                               "threshold_direction", "threshold_value", "threshold_tolerance"});
  for (const auto& v : verdicts)
    for (std::size_t i = 0; i < v.parts.size(); ++i) {
      const auto& [key, threshold] = v.parts[i];
      parts.row(v.claim, v.parts_rule, i, key.name, key.value, key.lo, key.hi, key.replicates, threshold.direction,
                threshold.value, threshold.tolerance);
    }
}

/// Fitted curves for the plots: each experiment writes its fits to <name>_fits.csv, one row per
/// fit, and its plot module draws the curve from these coefficients (never refitting). `model`
/// names the curve in x: log (a + b·log2 x), power (a·x^b), linear (a + b·x), nlogn
/// (a + b·x·log2 x), nlog2n (a + b·x·log2² x).
class FitsCsv {
 public:
  explicit FitsCsv(const std::string& path)
      : csv_(path, {"series", "quantity", "model", "a", "a_se", "b", "b_se", "r2", "mape", "aic", "x_min", "x_max",
                    "points"}) {}
  void row(const std::string& series, const std::string& quantity, const std::string& model, const FitResult& f,
           const std::vector<double>& x) {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    csv_.row(series, quantity, model, f.values[0], f.std_errors[0], f.values[1], f.std_errors[1], f.r2, f.mape, f.aic,
             x.empty() ? 0.0 : *lo, x.empty() ? 0.0 : *hi, f.points);
  }

 private:
  CsvWriter csv_;
};

/// "α = 0.33 ± 0.02" for the exponent of a power-law fit.
inline std::string exponent_text(const FitResult& power) {
  return "α = " + format_with_error(power.values[1], power.std_errors[1]);
}

/// One line naming the machine state the numbers were measured under.
inline std::string provenance() {
  std::string flags = "Release -O3";
#ifdef __AVX512F__
  flags += " -march=native (AVX-512)";
#elif defined(__AVX2__)
  flags += " -march=native (AVX2)";
#endif
  flags += ", FTZ/DAZ on, " + std::to_string(resolve_thread_count(0)) + " hardware threads";
  const int cpu = timing_cpu();
  return cpu < 0 ? flags : flags + ", single-thread timings on CPU " + std::to_string(cpu) + " (RAYLAB_TIMING_CPU)";
}

inline void progress(const std::string& line) { std::cerr << (line + "\n") << std::flush; }  // one write: lines from threads do not mix

}  // namespace raylab::experiments
