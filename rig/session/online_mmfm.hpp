// Online MMFM (DESIGN.md section 2): every sample of the excitation phase goes through the
// matched AC coupling (the same high-pass on excitation and response, MMFM.md section 6) into
// streaming correlators; after every block the MMFM estimate is refreshed with standard
// errors, and the stopping rule is checked.
//
// Standard errors come from the spread of independent per-block estimates (batch means):
//     se_j = s_b(theta_b,j) / sqrt(B_eff),  s_b = 1.4826 median|theta_b - median(theta_b)|,
// B_eff = number of blocks for cumulative averaging, min(B, 2W - 1) for exponential
// averaging of weight W (the variance of an exponential average of independent blocks is
// 1/(2W - 1) of one block's). Until three blocks exist the estimator's analytic value is
// used. The test may stop when every free parameter's se_j / |theta_j| is below the target.
//
// Asynchronous mode (realtime loops): a block estimate takes tens of ms, longer than a
// sample period, so push() only copies the block's correlations (a snapshot) and hands them
// to one worker; the finished estimate is returned by a later push(). At most one estimate
// is in flight; blocks completed meanwhile are queued in one pending snapshot (their
// per-block correlations all enter the spread; the averaged correlations are the newest).
// While a worker runs it alone touches the per-block state; the caller's thread reads it
// only after collecting the result (future::get orders the two).
#pragma once

#include <Eigen/Core>
#include <future>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/streaming_correlator.hpp"

namespace rig::session {

struct OnlineMmfmOptions {
  model::ModelOrder order;
  std::optional<double> delay_s;  // nullopt: estimated
  signal::CorrelatorOptions correlator;
  Eigen::Index block_samples = 2048;
  bool exponential = false;       // else cumulative
  double weight = 8.0;            // W of the exponential average
  double ac_coupling_rc_s = 0.0;  // 0: no coupling
  double target_rel_std_error = 0.05;
  bool asynchronous = false;  // estimate on a worker thread (else inside push())
};

// One refresh, after a block.
struct BlockEstimate {
  double t_s = 0.0;  // excitation time at the end of the block
  int block = 0;
  bool ok = false;                                   // false: the estimator failed on this block
  std::string error;                                 // why, when !ok
  std::vector<ident::ParameterEstimate> parameters;  // live values with se (batch means)
  ident::DerivedFigures derived;                     // gain, fn, zeta with se (second order)
  double delay_s = 0.0;
  double max_rel_std_error = 0.0;  // over the free parameters (NaN until known)
  double correlation_fit_pct = 0.0;
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

  bool converged() const;  // latest finished estimate meets the target (and enough blocks)
  const std::vector<BlockEstimate>& history() const { return history_; }
  // The estimate from the averaged correlations of the whole excitation (final model);
  // std errors replaced by the batch-means values. Throws std::invalid_argument when no
  // block has completed, std::logic_error while an estimate is in flight (call finish()).
  ident::MmfmResult final_result() const;
  signal::Correlation ruu() const { return main_.ruu(); }
  signal::Correlation ryu() const { return main_.ryu(); }
  Eigen::Index samples() const { return main_.samples(); }

 private:
  // What one estimate needs, copied on the caller's thread when a block completes.
  struct Snapshot {
    int block = 0;
    double t_s = 0.0;
    signal::Correlation ruu, ryu;  // averaged correlations
    std::vector<std::pair<signal::Correlation, signal::Correlation>> blocks;  // new blocks
  };
  BlockEstimate refresh(const Snapshot& s);
  const BlockEstimate& collect();  // waits for the worker's estimate and records it
  void launch();                   // starts the pending snapshot on a worker
  ident::MmfmOptions mmfm_options() const;
  void apply_spread(std::vector<ident::ParameterEstimate>& params,
                    ident::DerivedFigures& derived) const;

  OnlineMmfmOptions options_;
  std::optional<signal::AcCoupler> couple_u_, couple_y_;
  bool coupler_primed_ = false;
  signal::StreamingCorrelator main_;   // averaged correlations (live and final estimate)
  signal::StreamingCorrelator block_;  // this block only (W = 1), for the spread
  Eigen::Index in_block_ = 0;
  // Per-block correlations, re-solved with the current live delay and settings at every
  // refresh so that the spread reflects the data, not early automatic choices.
  std::vector<std::pair<signal::Correlation, signal::Correlation>> block_corr_;
  std::vector<Eigen::VectorXd> block_thetas_;   // parameters per block (current settings)
  std::vector<Eigen::Vector3d> block_derived_;  // gain, fn, zeta per block
  std::vector<BlockEstimate> history_;
  int blocks_done_ = 0;              // completed blocks (estimated or not yet)
  std::size_t spread_blocks_ = 0;    // block_thetas_.size() at the latest finished estimate
  std::optional<Snapshot> pending_;  // asynchronous: blocks awaiting the worker
  // Last member: destroyed first, so a running worker ends before the state it uses.
  std::future<BlockEstimate> job_;
};

}  // namespace rig::session
