// Whole-record identification (`rig identify` and the online loop's final step).
//
// Means are removed; the first estimation_fraction of the record estimates every candidate
// order, the rest validates it (simulation fit, DESIGN.md 5); the chosen order is then
// re-estimated on the whole record. Standard errors: from the spread of estimates over
// consecutive blocks (batch means, std / sqrt(blocks)) when the record is long enough,
// otherwise the estimator's own analytic value.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/parameters.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::ident {

enum class IdentMethod { kMmfm, kSrivc };
const char* to_string(IdentMethod method);

struct OrderScore {
  model::ModelOrder order;
  double fit_pct = 0.0;             // on the estimation part
  double validation_fit_pct = 0.0;  // on the held-out part
  double score = 0.0;               // validation fit - penalty * parameters
  double delay_s = 0.0;
};

struct IdentifyOptions {
  IdentMethod method = IdentMethod::kMmfm;
  std::optional<model::ModelOrder> order;  // nullopt: selected from candidates
  std::optional<double> delay_s;           // nullopt: estimated
  signal::CorrelatorOptions correlator;    // dt_s is overwritten with the record's dt
  double estimation_fraction = 0.5;
  std::vector<model::ModelOrder> candidates = {{1, 0}, {2, 0}, {2, 1}, {3, 0}, {3, 1},
                                               {3, 2}, {4, 0}, {4, 1}, {4, 2}};
  double penalty_pct_per_parameter = 0.1;
  int blocks = 8;             // for block-spread standard errors; 0: analytic
  double max_delay_s = -1.0;  // < 0: automatic
  MmfmOptions mmfm;           // order/delay fields are overridden
};

struct IdentifyResult {
  IdentMethod method = IdentMethod::kMmfm;
  model::TransferFunction model;
  std::vector<ParameterEstimate> parameters;
  double delay_s = 0.0;
  double delay_std_s = 0.0;
  DerivedFigures derived;
  std::vector<OrderScore> order_table;
  model::ModelOrder order;
  double validation_fit_pct = 0.0;
  double condition_number = 0.0;  // MMFM equation matrix (NaN for SRIVC)
  std::string std_error_method;   // "block spread (8 blocks)" or "analytic"
  std::string settings;           // human-readable summary of what was used
  MmfmSettings mmfm_settings;
  signal::Correlation ruu, ryu;   // correlations of the whole record
  signal::Correlation model_ryu;  // the model's cross-correlation on ruu's lags
};

// Throws std::invalid_argument (one line) for mismatched lengths, too short a record,
// dt_s <= 0 or an inadmissible order.
IdentifyResult identify(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                        const IdentifyOptions& options);

}  // namespace rig::ident
