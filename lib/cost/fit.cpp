#include "cost/fit.h"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "geometry/input_error.h"

namespace raylab {
namespace {

/// One measurement of a model linear in its K coefficients: residual (Σ c_j·x_j - y)·w, with
/// w = 1/y for relative residuals. The coefficients are one parameter block of size K, so each
/// Jacobian is one pass of K-wide jets; K is fixed at compile time (make_linear_residual
/// dispatches on it).
template <int K>
struct LinearTermsResidual {
  LinearTermsResidual(const std::vector<double>& features, double y, double weight) : y_(y), weight_(weight) {
    std::copy(features.begin(), features.end(), features_);
  }

  template <typename T>
  bool operator()(const T* const coefficients, T* residual) const {
    T prediction(0.0);
    for (int j = 0; j < K; ++j) prediction += coefficients[j] * features_[j];
    residual[0] = (prediction - y_) * weight_;
    return true;
  }

  static ceres::CostFunction* Create(const std::vector<double>& features, double y, double weight) {
    return new ceres::AutoDiffCostFunction<LinearTermsResidual, 1, K>(new LinearTermsResidual(features, y, weight));
  }

 private:
  double features_[K];
  double y_, weight_;
};

/// The most terms a linear model may have.
constexpr int kMaxLinearTerms = 16;

template <int... K>
ceres::CostFunction* make_linear_residual_of(std::integer_sequence<int, K...>, const std::vector<double>& features,
                                             double y, double weight) {
  ceres::CostFunction* cost = nullptr;
  const int k = static_cast<int>(features.size());
  ((k == K + 1 ? (cost = LinearTermsResidual<K + 1>::Create(features, y, weight), 0) : 0), ...);
  return cost;
}

ceres::CostFunction* make_linear_residual(const std::vector<double>& features, double y, double weight) {
  return make_linear_residual_of(std::make_integer_sequence<int, kMaxLinearTerms>{}, features, y, weight);
}

/// One measurement of y = c·n^α: residual (c·n^α - y)·w. Parameters: c and α, one block each.
struct PowerLawResidual {
  PowerLawResidual(double n, double y, double weight) : log_n_(std::log(n)), y_(y), weight_(weight) {}

  template <typename T>
  bool operator()(const T* const c, const T* const alpha, T* residual) const {
    residual[0] = (c[0] * exp(alpha[0] * log_n_) - y_) * weight_;
    return true;
  }

  static ceres::CostFunction* Create(double n, double y, double weight) {
    return new ceres::AutoDiffCostFunction<PowerLawResidual, 1, 1, 1>(new PowerLawResidual(n, y, weight));
  }

 private:
  double log_n_, y_, weight_;
};

/// glog writes Ceres' warnings to stderr unless told otherwise; the lab reports fit problems itself.
void quiet_glog() {
  static const bool done = [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    FLAGS_logtostderr = false;
    return true;
  }();
  (void)done;
}

void check_finite(const std::vector<double>& v, const char* what) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) throw InputError(std::string("fit: ") + what + " " + std::to_string(i) + " is not finite");
}

double weight_of(double y, ResidualKind kind) { return kind == ResidualKind::relative ? 1.0 / y : 1.0; }

ceres::LossFunction* make_loss(double scale) { return scale > 0 ? new ceres::HuberLoss(scale) : nullptr; }

/// A parameter block of the problem and its size.
struct Block {
  double* values;
  int size;
};

/// Solves `problem` over `blocks` and fills the solver and covariance parts of `out` (values,
/// standard errors, bounds, convergence), parameters in block order. `residual_count` is n.
void solve_and_describe(ceres::Problem& problem, const std::vector<Block>& blocks, const FitOptions& options,
                        std::size_t residual_count, FitResult& out) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  solver.function_tolerance = 1e-10;
  solver.gradient_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-10;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  out.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  if (!out.converged) out.message = summary.message;

  std::size_t k = 0;
  for (const Block& b : blocks) k += static_cast<std::size_t>(b.size);
  out.values.clear();
  out.at_bound.clear();
  out.std_errors.assign(k, std::numeric_limits<double>::quiet_NaN());
  for (const Block& b : blocks)
    for (int i = 0; i < b.size; ++i) {
      const double v = b.values[i];
      const double lo = problem.GetParameterLowerBound(b.values, i);
      out.values.push_back(v);
      out.at_bound.push_back(lo > -std::numeric_limits<double>::max() && v <= lo + 1e-12 * (1 + std::abs(lo)));
    }

  // σ² from the plain residuals at the solution (the robust loss only reweights outliers).
  ceres::Problem::EvaluateOptions eval;
  eval.apply_loss_function = false;
  std::vector<double> residuals;
  double cost = 0;
  problem.Evaluate(eval, &cost, &residuals, nullptr, nullptr);
  out.rss = 0;
  for (double r : residuals) out.rss += r * r;
  out.points = residual_count;
  const double dof = static_cast<double>(residual_count) - static_cast<double>(k);
  const double sigma2 = dof > 0 ? out.rss / dof : std::numeric_limits<double>::quiet_NaN();

  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.null_space_rank = -1;  // pseudo-inverse: report rather than fail on rank deficiency
  cov_options.apply_loss_function = true;
  ceres::Covariance covariance(cov_options);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (std::size_t a = 0; a < blocks.size(); ++a)
    for (std::size_t b = a; b < blocks.size(); ++b) pairs.emplace_back(blocks[a].values, blocks[b].values);
  if (covariance.Compute(pairs, &problem) && std::isfinite(sigma2)) {
    // The whole matrix, block by block: rows of block a, columns of block b.
    std::vector<double> full(k * k, 0.0);
    bool complete = true;
    std::size_t row = 0;
    for (std::size_t a = 0; a < blocks.size(); ++a) {
      std::size_t col = 0;
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        const auto na = static_cast<std::size_t>(blocks[a].size), nb = static_cast<std::size_t>(blocks[b].size);
        std::vector<double> cov(na * nb);
        if (!covariance.GetCovarianceBlock(blocks[a].values, blocks[b].values, cov.data())) {
          complete = false;
          std::fill(cov.begin(), cov.end(), std::numeric_limits<double>::quiet_NaN());
        }
        for (std::size_t i = 0; i < na; ++i)
          for (std::size_t j = 0; j < nb; ++j) full[(row + i) * k + col + j] = cov[i * nb + j] * sigma2;
        col += nb;
      }
      row += static_cast<std::size_t>(blocks[a].size);
    }
    for (std::size_t i = 0; i < k; ++i)
      if (full[i * k + i] >= 0) out.std_errors[i] = std::sqrt(full[i * k + i]);
    bool finite = true;
    for (double v : full) finite = finite && std::isfinite(v);
    if (complete && finite) out.covariance = std::move(full);
  }
  const double n = static_cast<double>(residual_count);
  const double rss_per_point = std::max(out.rss / n, 1e-300);
  out.aic = n * std::log(rss_per_point) + 2.0 * static_cast<double>(k);
  out.bic = n * std::log(rss_per_point) + static_cast<double>(k) * std::log(n);
}

/// R² and MAPE of predictions `yhat` against `y`.
void describe_agreement(const std::vector<double>& y, const std::vector<double>& yhat, FitResult& out) {
  out.r2 = coefficient_of_determination(yhat, y);
  out.mape = mean_absolute_percentage_error(yhat, y);
}

/// Condition number of a matrix whose columns are first scaled to unit length.
double scaled_condition_number(Eigen::MatrixXd m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    const double norm = m.col(j).norm();
    if (norm > 0) m.col(j) /= norm;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  const auto& s = svd.singularValues();
  if (s.size() == 0) return 0;
  const double smallest = s(s.size() - 1);
  return smallest > 0 ? s(0) / smallest : std::numeric_limits<double>::infinity();
}

}  // namespace

FitResult fit_linear_terms(const std::vector<std::vector<double>>& x, const std::vector<double>& y,
                           const FitOptions& options) {
  quiet_glog();
  if (x.empty() || x.size() != y.size()) throw InputError("fit: no measurements, or features and times of unequal count");
  const std::size_t k = x.front().size();
  if (k == 0) throw InputError("fit: a model needs at least one term");
  if (k > static_cast<std::size_t>(kMaxLinearTerms))
    throw InputError("fit: at most " + std::to_string(kMaxLinearTerms) + " terms");
  if (x.size() < k)
    throw InputError("fit: " + std::to_string(x.size()) + " measurements cannot determine " + std::to_string(k) + " terms");
  for (const auto& row : x) {
    if (row.size() != k) throw InputError("fit: feature rows of unequal length");
    check_finite(row, "feature of row");
  }
  check_finite(y, "measurement");
  if (options.residual == ResidualKind::relative)
    for (double v : y)
      if (!(v > 0)) throw InputError("fit: relative residuals need positive measurements");

  // Start from the plain least-squares solution, clamped to the bounds.
  Eigen::MatrixXd a(x.size(), k);
  Eigen::VectorXd b(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double w = weight_of(y[i], options.residual);
    for (std::size_t j = 0; j < k; ++j) a(i, j) = x[i][j] * w;
    b(i) = y[i] * w;
  }
  Eigen::VectorXd start = a.completeOrthogonalDecomposition().solve(b);
  std::vector<double> coefficients(k);
  for (std::size_t j = 0; j < k; ++j)
    coefficients[j] = std::isfinite(start(j)) ? (options.nonnegative ? std::max(start(j), 0.0) : start(j)) : 0.0;

  ceres::Problem problem;
  for (std::size_t i = 0; i < x.size(); ++i)
    problem.AddResidualBlock(make_linear_residual(x[i], y[i], weight_of(y[i], options.residual)),
                             make_loss(options.loss_scale), coefficients.data());
  if (options.nonnegative)
    for (std::size_t j = 0; j < k; ++j) problem.SetParameterLowerBound(coefficients.data(), static_cast<int>(j), 0.0);

  FitResult out;
  solve_and_describe(problem, {{coefficients.data(), static_cast<int>(k)}}, options, x.size(), out);
  std::vector<double> yhat(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) yhat[i] = predict_linear_terms(out.values, x[i]);
  describe_agreement(y, yhat, out);
  out.condition_number = scaled_condition_number(a);
  return out;
}

double predict_linear_terms(const std::vector<double>& coefficients, const std::vector<double>& features) {
  double s = 0;
  for (std::size_t j = 0; j < coefficients.size() && j < features.size(); ++j) s += coefficients[j] * features[j];
  return s;
}

FitResult fit_basis(const std::vector<double>& n, const std::vector<double>& y, const std::function<double(double)>& basis,
                    ResidualKind residual, double loss_scale) {
  std::vector<std::vector<double>> x;
  x.reserve(n.size());
  for (double v : n) x.push_back({1.0, basis(v)});
  FitOptions options;
  options.residual = residual;
  options.loss_scale = loss_scale;
  options.nonnegative = false;
  return fit_linear_terms(x, y, options);
}

FitResult fit_power_law(const std::vector<double>& n, const std::vector<double>& y, ResidualKind residual,
                        double loss_scale) {
  quiet_glog();
  if (n.size() < 2 || n.size() != y.size()) throw InputError("fit: a power law needs at least two (n, y) points");
  check_finite(n, "n of point");
  check_finite(y, "y of point");
  for (std::size_t i = 0; i < n.size(); ++i)
    if (!(n[i] > 0) || !(y[i] > 0)) throw InputError("fit: a power law needs positive n and y");

  // Start: the least-squares line through (ln n, ln y).
  std::vector<double> log_y(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) log_y[i] = std::log(y[i]);
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const double lx = std::log(n[i]);
    sx += lx; sy += log_y[i]; sxx += lx * lx; sxy += lx * log_y[i];
  }
  const double k = static_cast<double>(n.size());
  const double det = k * sxx - sx * sx;
  double alpha = det != 0 ? (k * sxy - sx * sy) / det : 0.0;
  double c = std::exp((sy - alpha * sx) / k);

  ceres::Problem problem;
  for (std::size_t i = 0; i < n.size(); ++i)
    problem.AddResidualBlock(PowerLawResidual::Create(n[i], y[i], weight_of(y[i], residual)), make_loss(loss_scale),
                             &c, &alpha);
  problem.SetParameterLowerBound(&c, 0, 0.0);

  FitOptions options;
  options.residual = residual;
  options.loss_scale = loss_scale;
  FitResult out;
  solve_and_describe(problem, {{&c, 1}, {&alpha, 1}}, options, n.size(), out);
  std::vector<double> yhat(n.size());
  Eigen::MatrixXd jacobian(n.size(), 2);
  for (std::size_t i = 0; i < n.size(); ++i) {
    yhat[i] = c * std::pow(n[i], alpha);
    jacobian(i, 0) = std::pow(n[i], alpha);
    jacobian(i, 1) = yhat[i] * std::log(n[i]);
  }
  describe_agreement(y, yhat, out);
  out.condition_number = scaled_condition_number(jacobian);
  return out;
}

double mean_absolute_percentage_error(const std::vector<double>& predicted, const std::vector<double>& measured) {
  double ape = 0;
  for (std::size_t i = 0; i < measured.size(); ++i)
    ape += measured[i] != 0 ? std::abs(predicted[i] - measured[i]) / std::abs(measured[i]) : 0.0;
  return measured.empty() ? 0.0 : ape / static_cast<double>(measured.size());
}

double coefficient_of_determination(const std::vector<double>& predicted, const std::vector<double>& measured) {
  if (measured.empty()) return 0.0;
  const double mean = std::accumulate(measured.begin(), measured.end(), 0.0) / static_cast<double>(measured.size());
  double ss_res = 0, ss_tot = 0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    ss_res += (measured[i] - predicted[i]) * (measured[i] - predicted[i]);
    ss_tot += (measured[i] - mean) * (measured[i] - mean);
  }
  return ss_tot > 0 ? 1.0 - ss_res / ss_tot : 1.0;
}

double spearman_rank_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = a.size();
  if (n < 2 || b.size() != n) return std::numeric_limits<double>::quiet_NaN();
  auto ranks = [n](const std::vector<double>& v) {
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return v[i] < v[j]; });
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n;) {
      std::size_t j = i;
      while (j + 1 < n && v[order[j + 1]] == v[order[i]]) ++j;
      const double average = 0.5 * static_cast<double>(i + j);  // ties share their mean rank
      for (std::size_t k = i; k <= j; ++k) r[order[k]] = average;
      i = j + 1;
    }
    return r;
  };
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double mean = 0.5 * static_cast<double>(n - 1);
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (ra[i] - mean) * (rb[i] - mean);
    saa += (ra[i] - mean) * (ra[i] - mean);
    sbb += (rb[i] - mean) * (rb[i] - mean);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : std::numeric_limits<double>::quiet_NaN();
}

std::string format_with_error(double value, double std_error, int digits) {
  char buf[96];
  if (!std::isfinite(std_error) || std_error <= 0) {
    std::snprintf(buf, sizeof buf, "%.4g", value);
    return buf;
  }
  // Round the error to `digits` significant digits and the value to the same decimal place.
  const int exponent = static_cast<int>(std::floor(std::log10(std_error)));
  const int decimals = std::max(0, digits - 1 - exponent);
  if (decimals > 12 || std::abs(value) >= 1e9 || (std::abs(value) < 1e-6 && value != 0)) {
    std::snprintf(buf, sizeof buf, "%.3g ± %.2g", value, std_error);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.*f ± %.*f", decimals, value, decimals, std_error);
  return buf;
}

}  // namespace raylab
