#pragma once
/// Shared plumbing of the experiment binaries: options (--mode quick|full, --out DIR), timing
/// by repetition, CSV output, and the provenance every result page states.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "accel/common/tracer.h"
#include "cost/csv.h"
#include "cost/fit.h"
#include "scene/primitive.h"
#include "geometry/input_error.h"

namespace raylab::experiments {

struct Options {
  std::string mode = "quick";  ///< quick: the default `./lab report`; full: `./lab report --full`
  std::string out = "docs/results";
  std::string runs;  ///< exp_cost_model: take the cost model's data set from this runs CSV instead of sweeping
  bool full() const { return mode == "full"; }
};

/// Parses the common options; exits with a one-line error on bad ones.
inline Options parse_options(int argc, char** argv, const std::string& description) {
  Options o;
  CLI::App app{description};
  app.add_option("--mode", o.mode, "quick | full")->check(CLI::IsMember({"quick", "full"}));
  app.add_option("--out", o.out, "output directory for CSV and Markdown");
  app.add_option("--runs", o.runs, "exp_cost_model: a runs CSV (raylab sweep, or a Slurm-merged one) to fit instead of sweeping");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    std::exit(app.exit(e));
  } catch (const CLI::ParseError& e) {
    std::cerr << argv[0] << ": error: " << e.what() << "\n";
    std::exit(2);
  }
  std::filesystem::create_directories(o.out);
  return o;
}

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

/// One verdict of the report's summary table. Each experiment writes the verdicts of its section
/// to <section>.verdicts.csv (write_verdicts); make_report.py gathers every such file into the
/// table that opens docs/results/README.md and the list that closes it, so neither is edited by
/// hand.
struct Verdict {
  std::string claim;    ///< "1", "1b", "6a", ...: the order of the summary table
  std::string title;    ///< the claim in a few words
  std::string verdict;  ///< confirmed | refuted | holds only under stated conditions
  std::string key;      ///< the key number, with its uncertainty
  std::string anchor;   ///< the id of the section's HTML anchor (section_anchor)
};

/// The line that opens a section with an anchor the summary table links to.
inline std::string section_anchor(const std::string& id) { return "<a id=\"" + id + "\"></a>\n\n"; }

/// The paragraph that states a claim's verdict at the end of its section.
inline std::string verdict_paragraph(const Verdict& v, const std::string& reason) {
  return "**Verdict (claim " + v.claim + "): " + v.verdict + ".** " + v.key + ". " + reason + "\n\n";
}

inline double seconds_of(const std::function<void()>& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// CPU time of the calling thread spent in `f` (CLOCK_THREAD_CPUTIME_ID): on a shared machine it
/// leaves out the time the thread waited for a core. Only for work done on the calling thread.
inline double thread_cpu_seconds_of(const std::function<void()>& f) {
  timespec start{}, end{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
  f();
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &end);
  return static_cast<double>(end.tv_sec - start.tv_sec) + 1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec);
}

/// A CSV file written row by row.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& columns) : out_(path) {
    if (!out_) throw InputError("cannot write " + path);
    for (std::size_t i = 0; i < columns.size(); ++i) out_ << (i ? "," : "") << columns[i];
    out_ << "\n";
  }
  template <class... T>
  void row(const T&... values) {
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
};

/// Writes `verdicts` to OUT/<section>.verdicts.csv (replacing an earlier run's).
inline void write_verdicts(const std::string& out_dir, const std::string& section, const std::vector<Verdict>& verdicts) {
  CsvWriter csv(out_dir + "/" + section + ".verdicts.csv", {"claim", "title", "verdict", "key", "anchor"});
  for (const auto& v : verdicts) csv.row(v.claim, v.title, v.verdict, v.key, v.anchor);
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
  return flags + ", FTZ/DAZ on, " + std::to_string(resolve_thread_count(0)) + " hardware threads";
}

inline void progress(const std::string& line) { std::cerr << line << std::endl; }

}  // namespace raylab::experiments
