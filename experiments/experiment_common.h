#pragma once
/// Shared plumbing of the experiment binaries: options (--mode quick|full, --out DIR), timing
/// by repetition, CSV output, and the provenance every result page states.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "accel/common/tracer.h"
#include "cost/csv.h"
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

/// Trace time per ray on `threads` threads (single-thread by default), in nanoseconds of wall
/// clock: the trace is repeated until at least `min_seconds` have been spent and the fastest
/// repetition is kept.
inline double ns_per_ray(const Primitive& accel, const std::vector<Ray>& rays, bool any_hit, double min_seconds = 0.2,
                         int threads = 1) {
  double best = 1e300, spent = 0;
  int reps = 0;
  while (spent < min_seconds || reps < 2) {
    const TraceResult r = trace_rays(accel, rays, TraceOptions{threads, false, any_hit});
    best = std::min(best, r.seconds);
    spent += r.seconds;
    ++reps;
    if (reps >= 1000) break;
  }
  return best / static_cast<double>(rays.size()) * 1e9;
}

inline double seconds_of(const std::function<void()>& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
