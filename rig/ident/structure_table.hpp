// The fit table of `rig identify` (as seed 001's Table 1): every model structure (order n/m,
// with or without an estimated dead time, and the estimator: MMFM, MMFM refined by the
// time-domain output error, or SRIVC) is estimated on the estimation records and scored by
// its simulation fit on a validation record that took no part in the estimate. AIC and BIC
// of the estimation fit are shown beside it.
//
// The rule that chooses (docs/identify.md): among the stable structures, those whose
// validation fit is within kAdequacyMarginPct of the best are adequate; the simplest of them
// (fewest parameters, then the higher validation fit) is chosen. AIC and BIC are not the
// rule: with tens of thousands of coloured-noise samples both keep rewarding parameters
// that a second record does not confirm.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::ident {

enum class IdentMethod { kMmfm, kMmfmOe, kSrivc };
const char* to_string(IdentMethod method);                       // "mmfm", "mmfm+oe", "srivc"
std::optional<IdentMethod> ident_method_from(std::string_view);  // inverse of to_string

// A validation fit within this many points of the best is adequate: differences that small
// are within the spread of the validation fit between emulated commissioning records of the
// same plant at different noise seeds (docs/identify.md, "The fit table").
inline constexpr double kAdequacyMarginPct = 0.5;
// Highest denominator order in the table (seed 001 goes to 4; a governor, a fuel lag, the
// shaft and the alternator's swing make 5-6 physical states).
inline constexpr int kMaxTableOrder = 6;

struct Structure {
  model::ModelOrder order;
  bool delay_estimated = true;  // false: the dead time is fixed (0, or the value given)
  IdentMethod method = IdentMethod::kMmfm;
  int parameters() const { return order.n + order.m + 1 + (delay_estimated ? 1 : 0); }
  std::string name() const;  // "2/0 +Td mmfm+oe"
};

// Records joined end to end, each with its own mean removed (different loads have different
// levels); each starts from rest in every simulation (model::RecordStarts).
struct RecordSet {
  Eigen::VectorXd u, y;
  model::RecordStarts starts;
  void add(const Eigen::VectorXd& u_raw, const Eigen::VectorXd& y_raw);
  Eigen::Index size() const { return u.size(); }
  Eigen::VectorXd simulate(const model::TransferFunction& tf, double dt_s) const;
};

struct StructureFit {
  Structure structure;
  bool ok = false;
  std::string error;              // why not, when !ok
  model::TransferFunction model;  // monic; dead time in the records' own timing
  double estimation_fit_pct = 0.0;
  double validation_fit_pct = 0.0;
  double aic = 0.0, bic = 0.0;  // N ln(V) + 2p, N ln(V) + p ln(N): V the estimation records'
                                // mean square simulation error, N their samples
  bool adequate = false;
  MmfmSettings mmfm_settings;     // MMFM-based methods: what the estimator used
  double condition_number = 0.0;  // MMFM equation matrix (NaN for SRIVC)
};

struct StructureTableOptions {
  std::vector<IdentMethod> methods = {IdentMethod::kMmfm};
  std::optional<model::ModelOrder> order;  // only this order; else n <= max_order, m < n
  int max_order = kMaxTableOrder;
  std::optional<double> delay_s;         // given: every structure uses it; else estimated, and 0
  bool without_delay = true;             // delay not given: also the structures without one
  double max_delay_s = -1.0;             // < 0: each estimator's default
  signal::CorrelatorOptions correlator;  // dt_s is overwritten
  MmfmOptions mmfm;                      // order and delay fields are overridden
  double adequacy_margin_pct = kAdequacyMarginPct;
  // Added to a model's dead time on the validation record (its samples are timed
  // differently from the estimation records', e.g. realtime against lockstep).
  double validation_delay_shift_s = 0.0;
  // Score the validation fit from this sample of the validation data on (the simulation
  // runs from its start): one record split in two is validated on its tail, which then
  // starts in the state the head left.
  Eigen::Index validation_from = 0;
};

struct StructureTable {
  std::vector<StructureFit> rows;
  int chosen = -1;  // index into rows (-1: nothing stable)
  int best = -1;    // the highest validation fit
  std::string rule;
  const StructureFit* chosen_fit() const {
    return chosen < 0 ? nullptr : &rows[static_cast<std::size_t>(chosen)];
  }
};

std::vector<Structure> table_structures(const StructureTableOptions& options);

// One structure on the estimation records (fills model, ok/error and estimation_fit_pct).
StructureFit fit_structure(const RecordSet& estimation, double dt_s, const Structure& structure,
                           const StructureTableOptions& options);

// progress(done, total) after each structure.
using TableProgress = std::function<void(int, int)>;
StructureTable structure_table(const RecordSet& estimation, const RecordSet& validation,
                               double dt_s, const StructureTableOptions& options,
                               const TableProgress& progress = {});

// The records' correlations averaged over the records, each weighted by its length.
signal::Correlation averaged_auto_correlation(const RecordSet& records,
                                              const signal::CorrelatorOptions& options);
signal::Correlation averaged_cross_correlation(const RecordSet& records,
                                               const signal::CorrelatorOptions& options);

}  // namespace rig::ident
