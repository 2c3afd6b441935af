#pragma once
/// Every fit of the lab: weighted nonlinear least squares with Ceres (Agarwal, Mierle et al.,
/// "Ceres Solver"), in Ceres' own idiom (fit.cpp: one residual functor per measurement, a static
/// `Create`, a robust loss, parameter bounds, ceres::Covariance for standard errors). This header
/// includes no Ceres header; fit.cpp is the only translation unit of the lab that does.
///
/// Residuals. With `relative` residuals (the default) a measurement y_i and its prediction ŷ_i
/// give r_i = (ŷ_i - y_i) / y_i, so every point counts by its percentage error, as timings of
/// different magnitudes should; `absolute` residuals give r_i = ŷ_i - y_i.
///
/// Robust loss. Ceres' HuberLoss with scale `loss_scale` (in the residual's units: 0.1 means 10%
/// for relative residuals): quadratic below the scale, linear above, so a few noisy timings do
/// not pull the fit. loss_scale <= 0 gives plain least squares.
///
/// Uncertainty. The standard errors are the square roots of the diagonal of
/// σ²·(JᵀJ)⁻¹, J the Jacobian of the residuals at the solution (ceres::Covariance, dense SVD,
/// so rank deficiency is reported rather than fatal) and σ² = Σr²/(n - k) the residual variance.
/// A parameter held at a bound is reported `at_bound`; its standard error then describes the
/// unconstrained curvature only. `covariance` is the whole matrix σ²·(JᵀJ)⁻¹ (k×k, row-major,
/// parameters in the model's order), from which a prediction's variance follows (cost_model.h).
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace raylab {

enum class ResidualKind { relative, absolute };

struct FitOptions {
  ResidualKind residual = ResidualKind::relative;
  double loss_scale = 0.1;     ///< Huber scale in residual units; <= 0 for plain least squares
  bool nonnegative = true;     ///< linear models: every coefficient >= 0 (Ceres parameter bounds)
  int max_iterations = 2000;
};

/// The result of one fit. Values and standard errors are in the order of the model's terms.
struct FitResult {
  std::vector<double> values;
  std::vector<double> std_errors;  ///< NaN where the covariance could not be computed
  /// σ²·(JᵀJ)⁻¹, k×k row-major in the order of `values`; empty when it could not be computed
  /// (n ≤ k, or Ceres' covariance failed).
  std::vector<double> covariance;
  std::vector<bool> at_bound;
  std::size_t points = 0;
  double rss = 0.0;        ///< Σ r_i² of the (relative or absolute) residuals
  double r2 = 0.0;         ///< 1 - Σ(y - ŷ)²/Σ(y - ȳ)² on the measurements themselves
  double mape = 0.0;       ///< mean |ŷ - y|/|y|, as a fraction
  double aic = 0.0;        ///< n·ln(rss/n) + 2k (Gaussian likelihood, Akaike 1974)
  double bic = 0.0;        ///< n·ln(rss/n) + k·ln n (Schwarz 1978)
  /// Ratio of the largest to the smallest singular value of the column-scaled design (linear
  /// models) or Jacobian: above ~1e8 the parameters are not separately determined.
  double condition_number = 0.0;
  bool converged = false;
  std::string message;  ///< Ceres' termination message when not converged
};

/// y ≈ Σ_j c_j·x_ij: a linear model in named terms, x[i] the feature row of measurement i (all
/// of one length k ≥ 1). Throws InputError for empty or ragged input, non-finite values, y <= 0
/// with relative residuals, or fewer points than terms.
FitResult fit_linear_terms(const std::vector<std::vector<double>>& x, const std::vector<double>& y,
                           const FitOptions& options = {});

/// Prediction of a linear model for one feature row.
double predict_linear_terms(const std::vector<double>& coefficients, const std::vector<double>& features);

/// y ≈ a + b·basis(n): a curve linear in its two coefficients (a + b·log2 N, a + b·N, a + b·N log N),
/// coefficients of either sign. values = {a, b}.
FitResult fit_basis(const std::vector<double>& n, const std::vector<double>& y,
                    const std::function<double(double)>& basis, ResidualKind residual = ResidualKind::relative,
                    double loss_scale = 0.1);

/// y ≈ c·n^α with c > 0: values = {c, α}. Started from the log-log least-squares line, then fitted
/// with the chosen residuals and robust loss. Every n and y must be positive.
FitResult fit_power_law(const std::vector<double>& n, const std::vector<double>& y,
                        ResidualKind residual = ResidualKind::relative, double loss_scale = 0.1);

/// Spearman's rank correlation of two equally long series (average ranks for ties); NaN for
/// fewer than two points or a constant series.
double spearman_rank_correlation(const std::vector<double>& a, const std::vector<double>& b);

/// Mean absolute percentage error of `predicted` against `measured` (a fraction).
double mean_absolute_percentage_error(const std::vector<double>& predicted, const std::vector<double>& measured);

/// 1 - Σ(y - ŷ)²/Σ(y - ȳ)².
double coefficient_of_determination(const std::vector<double>& predicted, const std::vector<double>& measured);

/// "1.23 ± 0.04" with `digits` significant digits of the error.
std::string format_with_error(double value, double std_error, int digits = 2);

}  // namespace raylab
