// Modified Modulating Function Method (MMFM.md sections 2-4 and 7, thesis chapter 3).
//
// The model A(p) y = B(p) u(t - Td) holds between the correlation functions:
//     A(p) r_yu(tau) = B(p) r_uu(tau - Td),  p = d/dtau.
// Multiplying by a modulating function phi and integrating by parts i times for p^i:
//     sum_i a_i (-1)^i <phi^(i), r_yu> = sum_j b_j (-1)^j <phi^(j)(. + Td), r_uu>
// (the delay moves onto the analytic modulating function, so any fractional Td is exact).
// Each function (several shapes, several centres) gives one linear equation in
// theta = [a_n..a_0, b_m..b_0]; the overdetermined set is solved by least squares with one
// normalisation, or by total least squares (normalisation-free, then rescaled).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "rig/ident/modulating.hpp"
#include "rig/ident/parameters.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"

namespace rig::ident {

enum class MmfmSolver { kLeastSquares, kTotalLeastSquares };
const char* to_string(MmfmSolver solver);

// A further time scale with its own centres: equations from functions of several widths
// share one solve (narrow functions resolve fast modes, wide ones the slow modes and gain).
struct MmfmBand {
  double scale_s = 0.0;
  std::vector<double> centres_s;
};

// One fixed configuration of the equation set.
struct MmfmSettings {
  ModulatingFamily family = ModulatingFamily::kHermite;
  int functions = 8;                  // modulating functions per centre
  double scale_s = 0.1;               // Hermite S; polynomial: window = centre +- 4 S
  std::vector<double> centres_s;      // lags of the function centres (in r_yu's lag axis)
  std::vector<MmfmBand> extra_bands;  // further scales (none by default)
  MmfmSolver solver = MmfmSolver::kLeastSquares;
  Normalisation normalisation = Normalisation::kMonicDen;
};

struct MmfmOptions {
  model::ModelOrder order;
  std::optional<double> delay_s;  // nullopt: estimated (search near the onset lag)
  double max_delay_s = -1.0;      // search range upper end; < 0: automatic
  ModulatingFamily family = ModulatingFamily::kHermite;
  int functions = 8;
  int centres = 5;                // minimum centres (more are added so supports overlap)
  std::optional<double> scale_s;  // nullopt: scanned (scored by correlation fit)
  int scale_levels = 3;           // bands at S, 3 S, 9 S ... where they fit the window
  // After the MMFM solve, minimise |r_yu - h * r_uu|^2 over the coefficients and Td by
  // Levenberg-Marquardt from the MMFM estimate (a correlation-domain output error; the thesis'
  // own model check turned into the criterion). Off: the plain MMFM estimate.
  bool refine = false;
  MmfmSolver solver = MmfmSolver::kLeastSquares;
  Normalisation normalisation = Normalisation::kMonicDen;
};

struct MmfmResult {
  model::TransferFunction model;              // normalised as settings.normalisation
  std::vector<ParameterEstimate> parameters;  // with std errors, last row delay_s
  Eigen::MatrixXd covariance;                 // of theta (ParameterEstimate order without delay)
  double delay_s = 0.0;
  double delay_std_s = 0.0;
  DerivedFigures derived;            // second order only
  double condition_number = 0.0;     // of the column-equilibrated equation matrix
  double equation_residual = 0.0;    // relative residual of the equation set
  double correlation_fit_pct = 0.0;  // model r_yu (= h * r_uu) against measured r_yu
  int equations = 0;
  MmfmSettings settings;          // what was used (scale, centres, solver, ...)
  bool refined = false;           // correlation-domain output-error refinement applied
  signal::Correlation model_ryu;  // the model's cross-correlation, for plots
};

// One solve with fixed settings and a given delay: builds the equations and solves them.
// Standard errors come from the equation residual: cov = s^2 (Phi^T Phi)^-1 with
// s^2 = |e|^2 / (K - p) (equations treated as independent; see the block estimate in
// identify() for a spread-based alternative). Throws std::invalid_argument when the
// functions do not fit inside the correlation window or the lag axes differ.
MmfmResult mmfm_solve(const signal::Correlation& ruu, const signal::Correlation& ryu,
                      model::ModelOrder order, double delay_s, const MmfmSettings& settings);

// Full estimator: automatic time scale (scan around the cross-correlation's dominant time
// scale), automatic dead time (1-D search scored by the correlation-domain output error,
// fractional-sample resolution), standard errors and derived figures.
MmfmResult estimate_mmfm(const signal::Correlation& ruu, const signal::Correlation& ryu,
                         const MmfmOptions& options);

// Levenberg-Marquardt on V = |r_yu - h * r_uu|^2 over theta = [a_{n-1}..a_0, b_m..b_0, Td]
// (monic; Td fixed when delay_free is false) from start.model. Covariance s^2 (J^T J)^-1 with
// s^2 = V / (L - p): it treats correlation errors as white, so it is optimistic.
MmfmResult refine_correlation_output_error(const signal::Correlation& ruu,
                                           const signal::Correlation& ryu, const MmfmResult& start,
                                           bool delay_free);

// The model's cross-correlation r_yu_hat = h * r_uu on r_uu's lag axis (lsim of r_uu).
signal::Correlation model_cross_correlation(const model::TransferFunction& tf,
                                            const signal::Correlation& ruu);

// Same, plus the free response that best explains r_yu: r_uu is not zero before the window
// (a finite record's autocorrelation has a noise floor), so the lsim starting at rest at the
// first lag misses a transient that, for a lightly damped system, lasts the whole window.
// Its n initial states are fitted by least squares. Used for every correlation-domain score.
signal::Correlation model_cross_correlation(const model::TransferFunction& tf,
                                            const signal::Correlation& ruu,
                                            const signal::Correlation& ryu);

// Half-width (s) of the support of the functions of `settings` for the given order.
double support_half_width_s(model::ModelOrder order, const MmfmSettings& settings);

// Centres spread evenly over the lags where every function fits inside both windows for any
// delay in [min_delay_s, max_delay_s], kept near the significant part of r_yu (count of
// them; empty when none fits).
std::vector<double> admissible_centres(const signal::Correlation& ruu,
                                       const signal::Correlation& ryu, model::ModelOrder order,
                                       double min_delay_s, double max_delay_s,
                                       const MmfmSettings& settings, int count);

}  // namespace rig::ident
