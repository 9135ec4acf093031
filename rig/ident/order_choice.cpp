#include "rig/ident/order_choice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "rig/ident/output_error.hpp"

namespace rig::ident {
namespace {

constexpr double kZ95 = 1.959963984540054;
// Weighs degrees against dB when ranking two bounds (the default targets: 3 deg ~ 0.5 dB).
constexpr double kDegPerDb = 6.0;
// A simpler structure is taken when its bound is within this factor of the best one.
constexpr double kSimplerTolerance = 1.1;

int parameter_count(model::ModelOrder o) { return o.n + o.m + 1; }

// A pole this many times faster than the fastest pole of the simpler model, added so that a
// nested start has (almost) the simpler model's response and cost.
constexpr double kNestedPoleFactor = 10.0;
// A nested zero sits this much further out than the nested pole (never on it, where the two
// would cancel and leave the fit degenerate).
constexpr double kNestedZeroFactor = 2.0;
// Steps of one pole or zero from the prior to a candidate order (4/1 from 2/0 takes 2).
constexpr int kMaxNestingSteps = 4;
// The spectra's lag half-width is the record length over this (Welch-like: about four
// independent windows' worth of averaging at the resolution it gives).
constexpr Eigen::Index kSpectrumRecordShare = 8;

// The simpler model with one more pole (far above its own) or one more numerator
// coefficient (zero): the richer structure started where the simpler one ended, so that its
// fit can only improve on it.
std::optional<model::TransferFunction> nested_start(const model::TransferFunction& simpler,
                                                    model::ModelOrder order) {
  const model::TransferFunction m = model::monic(simpler);
  const int n = m.order(), nb = static_cast<int>(m.num.size()) - 1;
  if (order.n < n || order.m < nb || order.n - n > 1 || order.m - nb > 1) return std::nullopt;
  model::TransferFunction t = m;
  const double fastest = m.poles().cwiseAbs().maxCoeff();
  if (order.n == n + 1) {
    const double p = kNestedPoleFactor * std::max(fastest, 1.0);
    Eigen::VectorXd den = Eigen::VectorXd::Zero(n + 2);
    den.head(n + 1) += m.den;      // s * A(s)
    den.tail(n + 1) += p * m.den;  // + p A(s)
    t.den = den;
    t.num = p * m.num;
  }
  if (order.m == nb + 1) {
    // A zero far above the poles (not a zero leading coefficient, which monic() trims).
    const double z = kNestedZeroFactor * kNestedPoleFactor * std::max(fastest, 1.0);
    Eigen::VectorXd num = Eigen::VectorXd::Zero(nb + 2);
    num.head(nb + 1) += t.num / z;  // (s / z) B(s)
    num.tail(nb + 1) += t.num;      // + B(s)
    t.num = num;
  }
  return model::monic(t);
}

// Start models for one order: its previous fit, MMFM on the correlations, and the nested
// extension of every simpler candidate already fitted.
std::vector<model::TransferFunction> start_models(const signal::Correlation& ruu,
                                                  const signal::Correlation& ryu,
                                                  model::ModelOrder order,
                                                  const OrderChoiceOptions& o,
                                                  const std::vector<OrderCandidate>& warm,
                                                  const std::vector<OrderCandidate>& simpler) {
  std::vector<model::TransferFunction> starts;
  for (const auto& w : warm) {
    if (w.ok && w.order == order) starts.push_back(w.model);
  }
  if (starts.empty()) {
    try {
      MmfmOptions m = o.mmfm;
      m.order = order;
      m.delay_s = o.delay_s;
      m.refine = false;
      starts.push_back(estimate_mmfm(ruu, ryu, m).model);
    } catch (const std::exception&) {
      // No MMFM start for this order: the nested starts remain.
    }
  }
  for (const auto& c : simpler) {
    if (!c.ok) continue;
    if (auto t = nested_start(c.model, order)) starts.push_back(*t);
  }
  if (o.prior) {
    std::optional<model::TransferFunction> t = model::monic(*o.prior);
    // Up one pole or one zero at a time until the order is reached.
    for (int step = 0;
         t && step < kMaxNestingSteps &&
         !(model::ModelOrder{t->order(), static_cast<int>(t->num.size()) - 1} == order);
         ++step) {
      const model::ModelOrder now{t->order(), static_cast<int>(t->num.size()) - 1};
      t = nested_start(*t, {std::min(order.n, now.n + 1), std::min(order.m, now.m + 1)});
    }
    if (t && model::ModelOrder{t->order(), static_cast<int>(t->num.size()) - 1} == order) {
      starts.push_back(*t);
    }
  }
  return starts;
}

OrderCandidate fit_one(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                       const std::vector<model::TransferFunction>& starts, model::ModelOrder order,
                       const OrderChoiceOptions& o) {
  OrderCandidate c;
  c.order = order;
  try {
    if (starts.empty()) throw std::runtime_error("no start model for this structure");
    const bool delay_free = !o.delay_s.has_value();
    double best_cost = std::numeric_limits<double>::infinity();
    for (model::TransferFunction start : starts) {
      if (o.delay_s) start.delay_s = *o.delay_s;
      const OutputErrorFit fit = refine_output_error(u, y, dt_s, start, delay_free);
      if (fit.cost < best_cost && fit.model.is_stable()) best_cost = fit.cost, c.model = fit.model;
    }
    if (!std::isfinite(best_cost)) throw std::runtime_error("no stable model");
    const int hw = std::clamp(static_cast<int>(u.size() / kSpectrumRecordShare),
                              o.min_spectrum_half_width, o.max_spectrum_half_width);
    const InputNoiseSpectra s =
        input_noise_spectra(u, y, dt_s, c.model, hw, std::max(1024, 4 * hw));
    c.covariance = asymptotic_covariance(c.model, s, static_cast<double>(u.size()), delay_free);
    c.band = frf_uncertainty(c.model, c.covariance, o.compare_freqs_hz, delay_free);
    c.band_factor = simultaneous_factor95(c.model, c.covariance, o.compare_freqs_hz, delay_free);
    c.width = worst_band95(c.band, c.band_factor);
    c.cost = best_cost;
    c.fit_pct = model::fit_percent(y, model::simulate(c.model, u, dt_s));
    c.ok = std::isfinite(c.width.db) && std::isfinite(c.width.deg);
    if (!c.ok) c.error = "the data do not determine this structure";
  } catch (const std::exception& e) {
    c.ok = false;
    c.error = e.what();
  }
  return c;
}

}  // namespace

double score(const BandWidth95& w) { return w.db + w.deg / kDegPerDb; }

int best_bound(const std::vector<OrderCandidate>& cands) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& c : cands) {
    if (c.ok) lowest = std::min(lowest, score(c.width));
  }
  if (!std::isfinite(lowest)) return -1;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    if (cands[i].ok && score(cands[i].width) <= kSimplerTolerance * lowest) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

// The bound of candidate i: its own band, or wider when the tightest richer candidate's
// band plus the distance to it is wider (see the header).
BandWidth95 widened(const std::vector<OrderCandidate>& cands, std::size_t i) {
  const OrderCandidate& best = cands[i];
  std::optional<BandWidth95> tightest;
  for (const auto& c : cands) {
    if (!c.ok || parameter_count(c.order) <= parameter_count(best.order)) continue;
    BandWidth95 w;
    for (std::size_t k = 0; k < best.band.size() && k < c.band.size(); ++k) {
      const auto& b = best.band[k];
      const auto& r = c.band[k];
      w.db = std::max(w.db, std::abs(b.mag_db - r.mag_db) + c.band_factor * r.sd_db);
      w.deg = std::max(w.deg, std::abs(std::remainder(b.phase_deg - r.phase_deg, 360.0)) +
                                  c.band_factor * r.sd_deg);
    }
    if (!tightest || score(w) < score(*tightest)) tightest = w;
  }
  BandWidth95 out = best.width;
  if (tightest) {
    out.db = std::max(out.db, tightest->db);
    out.deg = std::max(out.deg, tightest->deg);
  }
  return out;
}

OrderChoice choose_order(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                         const signal::Correlation& ruu, const signal::Correlation& ryu,
                         const OrderChoiceOptions& options,
                         const std::vector<OrderCandidate>& warm) {
  if (u.size() != y.size()) throw std::invalid_argument("choose_order: u and y lengths differ");
  if (options.orders.empty() || options.compare_freqs_hz.empty()) {
    throw std::invalid_argument("choose_order: no candidate orders or no compare frequencies");
  }
  OrderChoice out;
  for (const model::ModelOrder& order : options.orders) {
    const auto starts = start_models(ruu, ryu, order, options, warm, out.candidates);
    out.candidates.push_back(fit_one(u, y, dt_s, starts, order, options));
  }
  std::vector<BandWidth95> bounds;
  for (std::size_t i = 0; i < out.candidates.size(); ++i) {
    bounds.push_back(out.candidates[i].ok ? widened(out.candidates, i) : BandWidth95{});
  }
  for (std::size_t i = 0; i < out.candidates.size(); ++i) out.candidates[i].width = bounds[i];
  out.chosen = best_bound(out.candidates);
  return out;
}

}  // namespace rig::ident
