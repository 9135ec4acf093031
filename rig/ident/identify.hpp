// Whole-record identification (`rig identify`, and the pilot's model for a sweep-only test).
//
// Every structure of the fit table (structure_table.hpp) is estimated on the estimation data
// and scored on validation data; the table's rule chooses one. Two ways in:
//  * one record: the first estimation_fraction estimates, the rest validates; the chosen
//    structure is then re-estimated on the whole record;
//  * estimation records and a separate validation record (seed 001's practice): the model is
//    the chosen structure's estimate from the estimation records, the validation record
//    takes no part in it.
// Standard errors: one record with MMFM, the spread of estimates over consecutive blocks
// (batch means, std / sqrt(blocks)) when the record is long enough; otherwise the asymptotic
// covariance of frf_uncertainty.hpp, the same one the online stop rule uses. That covariance
// (all its correlations, not independent errors) also gives the Bode band.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "rig/ident/frf_uncertainty.hpp"
#include "rig/ident/mmfm.hpp"
#include "rig/ident/parameters.hpp"
#include "rig/ident/residual_tests.hpp"
#include "rig/ident/structure_table.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::ident {

// Residual tests on the validation data over this many seconds of lag (the plant's
// memory: the Stornoway set's impulse response has decayed to 5 % within 2 s).
inline constexpr double kResidualMaxLagS = 2.0;

struct IdentifyOptions : StructureTableOptions {
  double estimation_fraction = 0.5;   // one record: the share that estimates
  int blocks = 8;                     // block-spread standard errors; 0: asymptotic
  std::vector<double> band_freqs_hz;  // Bode band; empty: 160 log-spaced up to 0.4 / dt
  TableProgress progress;
};

// The validation data with the model's output on them (the table's chosen estimate).
struct ValidationData {
  std::string what;  // "held-out part" or "validation record"
  Eigen::VectorXd u, y, y_model;
  double fit_pct = 0.0;
  ResidualTests residuals;
};

struct IdentifyResult {
  Structure structure;  // the chosen one
  model::TransferFunction model;
  std::vector<ParameterEstimate> parameters;
  double delay_s = 0.0;
  double delay_std_s = 0.0;
  DerivedFigures derived;
  StructureTable table;
  model::ModelOrder order;
  double validation_fit_pct = 0.0;
  double condition_number = 0.0;  // MMFM equation matrix (NaN for SRIVC)
  std::string std_error_method;   // "block spread (8 blocks)" or "asymptotic covariance"
  std::string settings;           // human-readable summary of what was used
  MmfmSettings mmfm_settings;
  signal::Correlation ruu, ryu;   // correlations of the estimation data
  signal::Correlation model_ryu;  // the model's cross-correlation on ruu's lags
  ValidationData validation;
  // Asymptotic covariance of [a_{n-1}..a_0, b_m..b_0 (, Td)] (monic model) and the band it
  // gives: the response with its standard deviations, and the simultaneous 95 % factor.
  Eigen::MatrixXd covariance;
  std::vector<FrfUncertainty> band;
  double band_factor = 0.0;
};

// No structure of the table gave a stable model: the data do not support one (not a usage
// error; `rig identify` exits 1 and writes no model).
struct NoStableModel : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One record. Throws std::invalid_argument (one line) for mismatched lengths, too short a
// record, dt_s <= 0 or an inadmissible order, NoStableModel when no structure gave a
// stable model.
IdentifyResult identify(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                        const IdentifyOptions& options);

// Estimation records and a separate validation record (means removed from each).
IdentifyResult identify(const RecordSet& estimation, const RecordSet& validation, double dt_s,
                        const IdentifyOptions& options);

}  // namespace rig::ident
