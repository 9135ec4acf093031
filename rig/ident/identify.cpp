#include "rig/ident/identify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "rig/ident/srivc.hpp"

namespace rig::ident {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Fit {
  model::TransferFunction model;
  double delay_std_s = kNaN;
  Eigen::MatrixXd covariance;  // theta layout [a_n..a_0, b_m..b_0]
  double condition_number = kNaN;
  MmfmSettings settings;
};

signal::CorrelatorOptions correlator_for(const IdentifyOptions& opt, double dt_s) {
  signal::CorrelatorOptions c = opt.correlator;
  c.dt_s = dt_s;
  return c;
}

Fit fit_segment(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                model::ModelOrder order, const IdentifyOptions& opt, const MmfmOptions* fixed) {
  Fit fit;
  if (opt.method == IdentMethod::kSrivc) {
    SrivcOptions so;
    so.order = order;
    so.delay_s = opt.delay_s;
    if (opt.max_delay_s > 0) so.max_delay_s = opt.max_delay_s;
    const SrivcResult r = estimate_srivc(u, y, dt_s, so);
    fit.model = r.model;
    fit.delay_std_s = r.delay_std_s;
    const Eigen::Index p = order.n + order.m + 2;
    fit.covariance = Eigen::MatrixXd::Zero(p, p);
    fit.covariance.bottomRightCorner(p - 1, p - 1) = r.covariance.topLeftCorner(p - 1, p - 1);
    return fit;
  }
  const signal::CorrelatorOptions co = correlator_for(opt, dt_s);
  const signal::Correlation ruu = signal::auto_correlation(u, co);
  const signal::Correlation ryu = signal::cross_correlation(y, u, co);
  MmfmOptions mo = fixed ? *fixed : opt.mmfm;
  mo.order = order;
  mo.delay_s = opt.delay_s;
  mo.max_delay_s = opt.max_delay_s;
  const MmfmResult r = estimate_mmfm(ruu, ryu, mo);
  fit.model = r.model;
  fit.delay_std_s = r.delay_std_s;
  fit.covariance = r.covariance;
  fit.condition_number = r.condition_number;
  fit.settings = r.settings;
  return fit;
}

std::vector<OrderScore> score_orders(const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                     double dt_s, const std::vector<model::ModelOrder>& candidates,
                                     const IdentifyOptions& opt) {
  const Eigen::Index n_est = static_cast<Eigen::Index>(opt.estimation_fraction * u.size());
  const Eigen::Index n_val = u.size() - n_est;
  std::vector<OrderScore> table;
  for (const model::ModelOrder& order : candidates) {
    OrderScore s{order, kNaN, kNaN, -std::numeric_limits<double>::infinity(), kNaN};
    try {
      const Fit f = fit_segment(u.head(n_est), y.head(n_est), dt_s, order, opt, nullptr);
      // Simulate over the whole input so the validation part starts in the right state.
      const Eigen::VectorXd y_hat = simulate(f.model, u, dt_s);
      s.fit_pct = model::fit_percent(y.head(n_est), y_hat.head(n_est));
      s.validation_fit_pct = model::fit_percent(y.tail(n_val), y_hat.tail(n_val));
      s.delay_s = f.model.delay_s;
      const int params = order.n + order.m + 1 + (opt.delay_s ? 0 : 1);
      if (std::isfinite(s.validation_fit_pct) && f.model.is_stable()) {
        s.score = s.validation_fit_pct - opt.penalty_pct_per_parameter * params;
      } else {
        s.fit_pct = s.validation_fit_pct = kNaN;  // unstable: the fits mean nothing
      }
    } catch (const std::invalid_argument&) {
      // An order whose functions do not fit the window stays in the table, unscored.
    }
    table.push_back(s);
  }
  return table;
}

// Batch means: estimates on consecutive blocks, std / sqrt(blocks) for every parameter,
// the delay and the derived figures.
void block_std_errors(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                      model::ModelOrder order, const IdentifyOptions& opt, const MmfmOptions& fixed,
                      IdentifyResult& res) {
  const int b = opt.blocks;
  const Eigen::Index len = u.size() / b;
  std::vector<Eigen::VectorXd> thetas;
  std::vector<double> delays, gains, fns, zetas;
  for (int i = 0; i < b; ++i) {
    try {
      Fit f =
          fit_segment(u.segment(i * len, len), y.segment(i * len, len), dt_s, order, opt, &fixed);
      const model::TransferFunction t = normalise(f.model, opt.mmfm.normalisation);
      thetas.push_back(pack_parameters(t));
      delays.push_back(t.delay_s);
      const DerivedFigures d = derived_figures(t, Eigen::MatrixXd());
      gains.push_back(d.gain), fns.push_back(d.fn_hz), zetas.push_back(d.zeta);
    } catch (const std::invalid_argument&) {
    }
  }
  const double k = static_cast<double>(thetas.size());
  if (k < 3) return;
  auto sem = [k](const std::vector<double>& v) {
    double mean = 0, ss = 0;
    for (double x : v) mean += x / k;
    for (double x : v) ss += (x - mean) * (x - mean);
    return std::sqrt(ss / (k - 1.0) / k);
  };
  for (size_t p = 0; p + 1 < res.parameters.size(); ++p) {
    std::vector<double> v;
    for (const auto& t : thetas) v.push_back(t(static_cast<Eigen::Index>(p)));
    res.parameters[p].std_error = sem(v);
  }
  res.delay_std_s = opt.delay_s ? 0.0 : sem(delays);
  res.parameters.back().std_error = res.delay_std_s;
  if (res.derived.valid) {
    res.derived.gain_std = sem(gains), res.derived.fn_hz_std = sem(fns);
    res.derived.zeta_std = sem(zetas);
  }
  res.std_error_method = "block spread (" + std::to_string(thetas.size()) + " blocks)";
}

void check_inputs(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                  const IdentifyOptions& opt) {
  if (u.size() != y.size())
    throw std::invalid_argument("identify: u has " + std::to_string(u.size()) +
                                " samples but y has " + std::to_string(y.size()));
  if (!(dt_s > 0.0)) throw std::invalid_argument("identify: dt_s must be > 0");
  if (!(opt.estimation_fraction > 0.1 && opt.estimation_fraction < 0.9))
    throw std::invalid_argument("identify: estimation_fraction must lie in (0.1, 0.9)");
  if (u.size() < 4 * opt.correlator.lags)
    throw std::invalid_argument("identify: record of " + std::to_string(u.size()) +
                                " samples is shorter than 4 correlation windows");
  if (opt.order && (opt.order->n < 1 || opt.order->m < 0 || opt.order->m > opt.order->n))
    throw std::invalid_argument("identify: order must satisfy n >= 1 and 0 <= m <= n");
}

}  // namespace

const char* to_string(IdentMethod method) {
  return method == IdentMethod::kMmfm ? "mmfm" : "srivc";
}

IdentifyResult identify(const Eigen::VectorXd& u_raw, const Eigen::VectorXd& y_raw, double dt_s,
                        const IdentifyOptions& opt) {
  check_inputs(u_raw, y_raw, dt_s, opt);
  const Eigen::VectorXd u = u_raw.array() - u_raw.mean();
  const Eigen::VectorXd y = y_raw.array() - y_raw.mean();
  IdentifyResult res;
  res.method = opt.method;
  const std::vector<model::ModelOrder> candidates =
      opt.order ? std::vector<model::ModelOrder>{*opt.order} : opt.candidates;
  res.order_table = score_orders(u, y, dt_s, candidates, opt);
  const auto best =
      std::max_element(res.order_table.begin(), res.order_table.end(),
                       [](const OrderScore& a, const OrderScore& b) { return a.score < b.score; });
  if (!std::isfinite(best->score))
    throw std::invalid_argument("identify: no candidate order gave a stable model");
  res.order = best->order;
  res.validation_fit_pct = best->validation_fit_pct;
  // Final model from the whole record.
  const Fit fit = fit_segment(u, y, dt_s, res.order, opt, nullptr);
  Eigen::MatrixXd cov = fit.covariance;
  res.model = normalise(fit.model, opt.mmfm.normalisation, &cov);
  res.delay_s = res.model.delay_s;
  res.delay_std_s = fit.delay_std_s;
  res.parameters = parameter_table(res.model, cov, res.delay_std_s);
  res.derived = derived_figures(res.model, cov);
  res.condition_number = fit.condition_number;
  res.mmfm_settings = fit.settings;
  res.std_error_method = "analytic";
  const signal::CorrelatorOptions co = correlator_for(opt, dt_s);
  res.ruu = signal::auto_correlation(u, co);
  res.ryu = signal::cross_correlation(y, u, co);
  res.model_ryu = model_cross_correlation(res.model, res.ruu, res.ryu);
  if (opt.method == IdentMethod::kMmfm && opt.blocks >= 3 &&
      u.size() / opt.blocks >= 4 * opt.correlator.lags) {
    MmfmOptions fixed = opt.mmfm;
    fixed.scale_s = fit.settings.scale_s;
    block_std_errors(u, y, dt_s, res.order, opt, fixed, res);
  }
  std::ostringstream s;
  s << to_string(opt.method) << ", order " << res.order.n << "/" << res.order.m
    << (opt.order ? " (given)" : " (selected)") << ", delay "
    << (opt.delay_s ? "given" : "estimated") << ", normalisation "
    << to_string(opt.mmfm.normalisation) << ", estimation fraction " << opt.estimation_fraction
    << ", lags " << co.lags << ", zero index " << res.ruu.zero_index;
  if (opt.method == IdentMethod::kMmfm)
    s << ", " << to_string(fit.settings.family) << " functions " << fit.settings.functions << " x "
      << fit.settings.centres_s.size() << " centres, S " << fit.settings.scale_s << " s, "
      << fit.settings.extra_bands.size() + 1 << " scale bands, " << to_string(fit.settings.solver)
      << (opt.mmfm.refine ? ", refined by correlation-domain output error" : "");
  s << ", std errors " << res.std_error_method;
  res.settings = s.str();
  return res;
}

}  // namespace rig::ident
