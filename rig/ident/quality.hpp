// Data-quality checks run before estimation (`rig identify`, `rig diagnose`, the online
// loop). Each check is a named flag with a severity and one sentence a technician can act
// on. Fatal flags mean an estimate from these data would be meaningless.
//
//   no_response               fatal    no significant cross-correlation peak
//   acausal                   fatal/w  impulse-response mass at negative lags (fatal only
//                                      when the cross-correlation also peaks at a negative lag)
//   not_persistently_exciting fatal    too few excited frequencies for the order asked
//   input_clipped             fatal/w  flat tops at the input's extremes
//   output_clipped            fatal/w  flat tops at the output's extremes
//   undecayed                 warning  cross-correlation still large at the window end
//   coupling_mismatch         fatal/w  AC-coupling networks of the two channels differ
//   non_uniform_sampling      fatal/w  time-stamp jitter
//
// The response checks work on the correlations (rig::signal correlators) and on the
// impulse response deconvolved from them: with r_yu = h * r_uu over the lag window,
//     (R + lambda r_uu(0) I) h = r_yu,   R_ij = r_uu(i - j),
// a regularised Wiener-Hopf solution over lags -z..P; lambda keeps the unexcited band of h
// at zero instead of amplifying noise.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::ident {

enum class Severity { kWarning, kFatal };
const char* to_string(Severity severity);

struct QualityFlag {
  std::string name;
  Severity severity = Severity::kWarning;
  std::string message;                                          // one sentence, says what to check
  double value = std::numeric_limits<double>::quiet_NaN();      // the measured figure
  double threshold = std::numeric_limits<double>::quiet_NaN();  // the limit it crossed
};

// A raw channel and the same channel after an AC-coupling network, both in the recording.
struct CoupledPair {
  std::string name;  // e.g. "y_ac"
  Eigen::VectorXd raw;
  Eigen::VectorXd coupled;
};

struct QualityOptions {
  signal::CorrelatorOptions correlator;  // lags and zero index; dt_s is set from the data
  model::ModelOrder order{2, 0};         // the most demanding order that will be estimated
  bool delay_estimated = true;           // the delay is one more unknown
  double regularisation = 1e-2;          // lambda above
  double significance_sigma = 5.0;       // no_response: peak / Bartlett std below this
  double acausal_warning = 0.25;         // fraction of |h|^2 at negative lags
  double acausal_fatal = 0.5;
  double clip_warning = 0.005;  // fraction of samples at one extreme
  double clip_fatal = 0.05;
  double undecayed_ratio = 0.3;  // tail |r_yu| / peak |r_yu|
  double sag_ratio = 0.2;        // step-response tail / peak below this: sag
  // Coupling declared in the sidecar, and coupled channels with their raw sources.
  std::optional<double> coupling_rc_s;
  std::vector<CoupledPair> coupled_pairs;
  double coupling_tolerance = 0.1;  // relative RC difference
  // Time-stamp jitter from the recording (0 when it had no time column).
  double jitter_max_s = 0.0;
  double jitter_warning = 0.01;  // |step - dt| / dt
  double jitter_fatal = 0.25;
};

struct QualityReport {
  std::vector<QualityFlag> flags;
  // Figures behind every check, fired or not (for report.json): peak_sigma, peak_lag_s,
  // acausal_fraction, excited_lines, required_lines, input_clip_fraction,
  // output_clip_fraction, tail_ratio, step_tail_ratio, jitter_ratio, coupling_rc_<name>_s.
  std::vector<std::pair<std::string, double>> figures;

  bool has_fatal() const;
  const QualityFlag* find(const std::string& name) const;
};

// u, y equally long (std::invalid_argument otherwise, or when shorter than the lag window).
// The samples of x at its extremes (to 1e-9 of its range): how many sit at the maximum and
// at the minimum, and the most that any of the next kExtremeNeighbours distinct values inward
// holds (a clipped channel piles up at its extreme; a quantised one thins out towards it).
inline constexpr std::size_t kExtremeNeighbours = 3;
struct ExtremePile {
  double hi = 0.0, lo = 0.0;
  Eigen::Index at_hi = 0, at_lo = 0, near_hi = 0, near_lo = 0;
};
ExtremePile extreme_pile(const Eigen::VectorXd& x);

QualityReport check_quality(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                            const QualityOptions& options);

// The RC time constant that best explains `coupled` as the first-order high-pass of `raw`
// (the AcCoupler recursion v_k = a v_{k-1} + x_k - x_{k-1}, a = exp(-dt/RC), solved for a
// by least squares). NaN when the data cannot tell (a outside (0, 1)).
double fitted_coupling_rc_s(const Eigen::VectorXd& raw, const Eigen::VectorXd& coupled,
                            double dt_s);

}  // namespace rig::ident
