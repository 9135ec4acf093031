// Automatic model order with the dead time, judged in the user's units (the frequency
// response over the compare band), so that the online estimate has no structural floor:
// as the record grows and the bands narrow, a richer structure is taken as soon as the data
// show that it is the more accurate.
//
// Each candidate order is fitted by the time-domain output error on the record
// (output_error.hpp) from several starts, keeping the lowest cost: its previous fit (or MMFM
// from the averaged correlations when there is none), every simpler candidate extended by a
// far pole or a zero (a nested start, so that a richer structure never ends worse than a
// simpler one by a poor local minimum), and a prior model (the pilot's) when one is given
// (with a periodic excitation MMFM alone can start a second order in the wrong basin). Each
// has its asymptotic covariance and simultaneous 95 % band (frf_uncertainty.hpp).
//
// Each candidate's bound must also hold when its structure is biased: it is the larger of
// its own band and the tightest bound a richer candidate gives, at each frequency the
// distance to that candidate plus its band (the truth lies in the richer band; this model is
// that far from it). The tightest, because a richer structure the data do not determine has
// a huge band that bounds nothing. So the stopping rule cannot be met by a structure whose
// error the data already show.
//
// The rule: the candidate with the smallest bound (dB + deg / 6, the default targets' ratio),
// or the simplest whose bound is within 10 % of it. A candidate that fails or is unstable
// takes no part.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "rig/ident/frf_uncertainty.hpp"
#include "rig/ident/mmfm.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"

namespace rig::ident {

struct OrderCandidate {
  model::ModelOrder order;
  bool ok = false;
  std::string error;                 // why not, when !ok
  model::TransferFunction model;     // monic, with the delay
  Eigen::MatrixXd covariance;        // asymptotic, of [a_{n-1}..a_0, b_m..b_0 (, Td)]
  std::vector<FrfUncertainty> band;  // at the compare frequencies
  double band_factor = 0.0;          // simultaneous 95 % factor over the compare frequencies
  BandWidth95 width;                 // widest simultaneous 95 % half-band (chosen: widened)
  double cost = 0.0;                 // mean square output error on the record
  double fit_pct = 0.0;              // output-error fit on the record
};

struct OrderChoiceOptions {
  std::vector<model::ModelOrder> orders = {{2, 0}, {3, 0}, {3, 1}};
  std::optional<double> delay_s;         // nullopt: estimated
  std::vector<double> compare_freqs_hz;  // where the response is judged
  MmfmOptions mmfm;                      // start estimates (order, delay and refine overridden)
  // A model known beforehand (the pilot's): one more start for every order, nested up to it.
  std::optional<model::TransferFunction> prior;
  // Lag window of the spectra (samples): record / kSpectrumRecordShare within these bounds,
  // so that a long record resolves narrow noise lines (the firing ripple) in Phi_v.
  int min_spectrum_half_width = 256;
  int max_spectrum_half_width = 2048;
};

struct OrderChoice {
  std::vector<OrderCandidate> candidates;  // in the order of options.orders
  int chosen = -1;                         // index into candidates, -1 when none fitted
  const OrderCandidate* best() const {
    return chosen < 0 ? nullptr : &candidates[static_cast<std::size_t>(chosen)];
  }
};

// u, y: the record (after the matched coupling) the correlations ruu, ryu were formed from.
// warm: previous candidates of the same options (may be empty), used as start models.
OrderChoice choose_order(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                         const signal::Correlation& ruu, const signal::Correlation& ryu,
                         const OrderChoiceOptions& options,
                         const std::vector<OrderCandidate>& warm = {});

// The rule above on fitted candidates whose widths are already their bounds (index of the
// chosen one, -1 when none is ok).
int best_bound(const std::vector<OrderCandidate>& candidates);

}  // namespace rig::ident
