// Online MMFM (DESIGN.md section 2): every sample of the excitation phase goes through the
// matched AC coupling (the same high-pass on excitation and response, MMFM.md section 6) into
// streaming correlators and a record; after every block the model is refreshed and the
// stopping rule is checked.
//
// The refresh (rig/ident/order_choice.hpp): each candidate order is started by MMFM from the
// averaged correlations (later: from its previous fit) and refined by the time-domain output
// error on the record; the simplest order whose response lies inside the 95 % band of every
// more complex one is taken. Standard errors and the frequency-response band come from the
// estimator's asymptotic covariance (rig/ident/frf_uncertainty.hpp), not from the spread of a
// few block estimates. The stopping rule is in the user's units: the 95 % band of the
// model's response over the compare frequencies within +-target_db and +-target_deg.
// Exponential averaging of weight W keeps the last (2W - 1) blocks of the record (the
// effective length of an exponential average of blocks), so memory stays bounded.
//
// Asynchronous mode (realtime loops): a refresh takes tens to hundreds of ms, longer than a
// sample period, so push() only copies what the refresh needs (a snapshot) and hands it to
// one worker; the finished estimate is returned by a later push(). At most one estimate is
// in flight; blocks completed meanwhile are covered by the next snapshot. While a worker runs
// it alone touches the warm-start state; the caller's thread reads it only after collecting
// the result (future::get orders the two).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <future>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/order_choice.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/streaming_correlator.hpp"

namespace rig::session {

// The candidates of the automatic order, simplest first: the thesis's second order, a third
// pole (the governor and transducer lags that add to the dead time), a zero with it, and a
// fourth pole (so that the third order's own bias shows in its widened band).
inline const std::vector<model::ModelOrder> kAutoOrders = {{2, 0}, {3, 0}, {3, 1}, {4, 1}};
// Frequencies of the compare band where the stopping rule judges the response.
inline constexpr int kCompareFrequencies = 24;

struct OnlineMmfmOptions {
  model::ModelOrder order;                // the structure when `orders` is empty
  std::vector<model::ModelOrder> orders;  // candidates, simplest first (automatic order)
  std::optional<double> delay_s;          // nullopt: estimated
  signal::CorrelatorOptions correlator;
  Eigen::Index block_samples = 1024;
  bool exponential = false;              // else cumulative
  double weight = 8.0;                   // W of the exponential average
  double ac_coupling_rc_s = 0.0;         // 0: no coupling
  std::vector<double> compare_freqs_hz;  // where the stopping rule judges the response
  double target_db = 0.5;                // 95 % band half-widths of the stopping rule
  double target_deg = 3.0;
  bool asynchronous = false;                     // estimate on a worker thread (else inside push())
  std::optional<model::TransferFunction> prior;  // a start model for every order (pilot's)
};

// One refresh, after a block.
struct BlockEstimate {
  double t_s = 0.0;  // excitation time at the end of the block
  int block = 0;
  bool ok = false;                // false: the estimator failed on this block
  std::string error;              // why, when !ok
  model::TransferFunction model;  // the chosen structure, monic, with delay
  model::ModelOrder order;
  std::vector<ident::ParameterEstimate> parameters;  // with asymptotic standard errors
  ident::DerivedFigures derived;  // gain, fn, zeta with se of the second-order candidate
  double delay_s = 0.0;
  double band_db95 = 0.0;  // widest 95 % half-band over the compare frequencies (NaN: unknown)
  double band_deg95 = 0.0;
  double fit_pct = 0.0;  // output-error fit on the record
};

class OnlineMmfm {
 public:
  explicit OnlineMmfm(const OnlineMmfmOptions& options);

  // One sample: excitation as applied (% of rated power) and power deviation (kW).
  // Returns the refreshed estimate when this sample completes a block (synchronous) or when
  // an estimate finished since the last call (asynchronous).
  std::optional<BlockEstimate> push(double u_pct, double y_kw);
  // Waits for the estimate in flight and any pending one (asynchronous mode); history(),
  // converged() and final_result() then cover every completed block.
  void finish();
  // Room for this many samples of record, so that push() never reallocates on the loop
  // thread (a realtime tick must not copy the whole record).
  // Exponential averaging keeps at most (2W + 1) blocks, so no more is reserved.
  void reserve(Eigen::Index samples) {
    if (options_.exponential) {
      samples = std::min<Eigen::Index>(
          samples, static_cast<Eigen::Index>((2.0 * options_.weight + 1.0) *
                                             static_cast<double>(options_.block_samples)));
    }
    u_.reserve(static_cast<std::size_t>(samples));
    y_.reserve(static_cast<std::size_t>(samples));
  }

  bool converged() const;  // latest finished estimate's band is within the targets
  const std::vector<BlockEstimate>& history() const { return history_; }
  // The estimate of the whole excitation (final model) as an MMFM result (settings and
  // equations of the chosen order's MMFM start; model, covariance and errors of its
  // output-error refinement). Throws std::invalid_argument when no block has completed or
  // no candidate could be fitted, std::logic_error while an estimate is in flight.
  ident::MmfmResult final_result() const;
  // The candidates of the final refresh (the order table), empty before one finished.
  const std::optional<ident::OrderChoice>& final_choice() const { return last_choice_; }
  signal::Correlation ruu() const { return main_.ruu(); }
  signal::Correlation ryu() const { return main_.ryu(); }
  Eigen::Index samples() const { return main_.samples(); }

 private:
  // What one estimate needs, copied on the caller's thread when a block completes.
  struct Snapshot {
    int block = 0;
    double t_s = 0.0;
    signal::Correlation ruu, ryu;  // averaged correlations
    Eigen::VectorXd u, y;          // the record the estimate is fitted to
  };
  BlockEstimate refresh(const Snapshot& s);
  const BlockEstimate& collect();  // waits for the worker's estimate and records it
  void launch();                   // starts the pending snapshot on a worker
  Snapshot snapshot() const;
  ident::OrderChoiceOptions choice_options() const;

  OnlineMmfmOptions options_;
  std::optional<signal::AcCoupler> couple_u_, couple_y_;
  bool coupler_primed_ = false;
  signal::StreamingCorrelator main_;  // averaged correlations (start estimates)
  std::vector<double> u_, y_;         // coupled record (exponential: the last N_eff samples)
  Eigen::Index in_block_ = 0;
  int blocks_done_ = 0;
  std::vector<ident::OrderCandidate> warm_;        // latest fits per order (worker's state)
  std::optional<ident::OrderChoice> last_choice_;  // of the latest finished estimate
  std::vector<BlockEstimate> history_;
  std::optional<Snapshot> pending_;  // asynchronous: blocks awaiting the worker
  // Last member: destroyed first, so a running worker ends before the state it uses.
  std::future<BlockEstimate> job_;
};

}  // namespace rig::session
