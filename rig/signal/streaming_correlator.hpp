// Streaming auto- and cross-correlation for the online loop (DESIGN.md section 2).
//
// Samples arrive in blocks of any size (one sample per 100 Hz tick, or a logger's 2048).
// The correlator keeps the last lags-1 samples of the previous block so that every lag
// window spans block boundaries, and forms exactly the products the batch estimator of
// correlators.hpp would form on the concatenated record: anchors t = P, P+s, ... (global
// sample index) once sample t + z has arrived. Hence in kCumulative mode ruu()/ryu() equal
// auto_correlation(u_all)/cross_correlation(y_all, u_all) up to summation rounding.
//
// Averaging (MMFM.md section 2, thesis 5-2):
//   kCumulative   R = (sum of all products) / (number of products): the plain mean.
//   kExponential  at the end of each averaging block, R_new = block sums / block products,
//                 and R <- R + (R_new - R) / W (the first block initialises R = R_new).
//                 W = 10 and W = 50 were used in the thesis.
// A block ends every `block_samples` received samples (0: at the end of every push()).
// Polarity with arcsine_correction averages the raw polarity correlation and applies
// rho = sin(pi/2 r) to the average when ruu()/ryu() are read.
// Before the first exponential block completes, ruu()/ryu() return the running mean of
// the current block, so the live view has something to draw.
//
// The kFft kind is accepted: each push() correlates its newly completed anchors by FFT
// (efficient for large blocks only). Allocation happens at construction and while the
// internal buffer grows to hold one push(); steady-state per-sample pushes do not allocate.
// Per-sample pushes defer the products until a few anchors are ready (the kernels fold
// several anchors into one pass over the lag window); readers include the deferred ones.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "rig/signal/correlation.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::signal {

enum class Averaging { kExponential, kCumulative };

struct StreamingOptions {
  CorrelatorOptions correlator;
  Averaging averaging = Averaging::kExponential;
  double weight = 10.0;               // W of the exponential average (>= 1)
  Eigen::Index block_samples = 2048;  // samples per averaging block; 0: one push() = one block
};

class StreamingCorrelator {
 public:
  // Throws std::invalid_argument for unusable options (see validate() in correlators.hpp).
  explicit StreamingCorrelator(const StreamingOptions& options);

  // Appends equally long blocks of excitation u and response y.
  void push(const Eigen::VectorXd& u_block, const Eigen::VectorXd& y_block);
  void push(double u, double y);  // one sample (the 100 Hz tick)

  Correlation ruu() const;  // auto-correlation of u (relay: E[u(t) sgn(u(t - tau))])
  Correlation ryu() const;  // cross-correlation r_yu(tau) = E[y(t) u(t - tau)]

  Eigen::Index blocks() const { return blocks_; }     // completed averaging blocks
  Eigen::Index samples() const { return received_; }  // samples received since reset
  Eigen::Index products() const { return products_ + ready_anchors(); }  // per lag, since reset
  const StreamingOptions& options() const { return options_; }
  void reset();

 private:
  struct Sums {  // per-lag sums in reverse lag order (j = P - k)
    std::vector<double> uu, yu;
    std::vector<std::int64_t> neg_uu, neg_yu;  // polarity: disagreement counts
  };
  void append(double u, double y);
  Eigen::Index ready_anchors() const;
  void accumulate(Eigen::Index count, Sums& sums) const;
  void process_ready();
  void finish_block();
  void compact();
  Correlation finalise(const Eigen::VectorXd& r) const;
  Correlation block_mean(int channel) const;

  StreamingOptions options_;
  Eigen::Index lags_ = 0, zero_ = 0, positive_ = 0;
  // Buffered samples, global index buf_start_ + i; kept from the oldest unconsumed window.
  std::vector<double> u_, y_;
  std::vector<std::uint64_t> u_mask_;        // relay: sign bit of u
  std::vector<std::uint8_t> u_neg_, y_neg_;  // polarity: 1 where negative
  Eigen::Index buf_start_ = 0, received_ = 0, next_anchor_ = 0;
  Sums sums_;  // of the current block (kCumulative: of everything since reset)
  Eigen::Index block_products_ = 0, block_received_ = 0, products_ = 0, blocks_ = 0;
  Eigen::VectorXd avg_uu_, avg_yu_;  // exponential averages (reverse order)
};

}  // namespace rig::signal
