// The two helpers of experiment_common.h whose headers (CLI11, Boost.Math) take ~14 s to compile:
// compiled once here instead of in every experiment.
#include "experiment_common.h"

#include <CLI/CLI.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace raylab::experiments {

Options parse_options(int argc, char** argv, const std::string& description) {
  Options o;
  CLI::App app{description};
  app.add_option("--mode", o.mode, "quick | full")->check(CLI::IsMember({"quick", "full"}));
  app.add_option("--out", o.out, "output directory for CSV and Markdown");
  app.add_option("--claim", o.claim, "run only the part of the experiment that decides this claim (e.g. 1b)");
  app.add_option("--runs", o.runs, "exp_cost_model: a runs CSV (raylab sweep, or a Slurm-merged one) to fit instead of sweeping");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    std::exit(app.exit(e));
  } catch (const CLI::ParseError& e) {
    std::cerr << argv[0] << ": error: " << e.what() << "\n";
    std::exit(2);
  }
  try {
    (void)timing_cpu();  // a bad RAYLAB_TIMING_CPU fails here, before any work
  } catch (const InputError& e) {
    std::cerr << argv[0] << ": error: " << e.what() << "\n";
    std::exit(2);
  }
  std::filesystem::create_directories(o.out);
  return o;
}

KeyNumber fitted_key(std::string name, double value, double std_error, std::size_t points, std::size_t parameters,
                     std::string spec) {
  KeyNumber k;
  k.name = std::move(name);
  k.value = value;
  k.replicates = static_cast<long>(points);
  k.spec = std::move(spec);
  const double dof = static_cast<double>(points) - static_cast<double>(parameters);
  if (std::isfinite(std_error) && dof >= 1) {
    const double t = boost::math::quantile(boost::math::students_t(dof), 0.975);
    k.lo = value - t * std_error;
    k.hi = value + t * std_error;
    char buf[96];
    std::snprintf(buf, sizeof buf, "± t(0.975, %g)·s.e. = ± %.3g·s.e. of the fit (%zu points, %zu parameters)", dof,
                  t, points, parameters);
    k.interval = buf;
  } else {
    k.interval = "no interval: the fit's standard error is undefined";
  }
  return k;
}

}  // namespace raylab::experiments
