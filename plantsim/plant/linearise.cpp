#include "plantsim/plant/linearise.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <vector>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/engine.hpp"
#include "plantsim/plant/model.hpp"

namespace plantsim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kFitLoHz = 0.002;
constexpr double kFitHiHz = 20.0;
constexpr double kTolDb = 0.02;  // rational part vs exact response over the fit band
constexpr double kTolDeg = 0.15;

// Central differences of rhs(x, u, f): columns of A, then b (per pu bias) and b_f.
void jacobians(const GensetModel& model, const Eigen::VectorXd& x0, double f0, LinearModel* lm) {
  const int n = model.size();
  lm->a.resize(n, n);
  Eigen::VectorXd dp(n), dm(n);
  Eigen::VectorXd x = x0;
  for (int j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x0[j]));
    x[j] = x0[j] + h;
    model.rhs(x.data(), 0.0, f0, dp.data());
    x[j] = x0[j] - h;
    model.rhs(x.data(), 0.0, f0, dm.data());
    x[j] = x0[j];
    lm->a.col(j) = (dp - dm) / (2.0 * h);
  }
  const double h = 1e-6;
  model.rhs(x0.data(), h, f0, dp.data());
  model.rhs(x0.data(), -h, f0, dm.data());
  lm->b = (dp - dm) / (2.0 * h) / 100.0;  // per % of rated power
  model.rhs(x0.data(), 0.0, f0 + h, dp.data());
  model.rhs(x0.data(), 0.0, f0 - h, dm.data());
  lm->b_fuel = (dp - dm) / (2.0 * h);
}

void fit_tf(LinearModel* lm) {
  constexpr int kPoints = 300;
  Eigen::VectorXd f(kPoints);
  Eigen::VectorXcd g(kPoints);
  for (int i = 0; i < kPoints; ++i) {
    f[i] = kFitLoHz * std::pow(kFitHiHz / kFitLoHz, i / (kPoints - 1.0));
    g[i] = lm->response(f[i]) * std::exp(std::complex<double>(0.0, kTwoPi * f[i] * lm->delay_s));
  }
  // The lowest orders (n, then m) that meet the tolerance win; otherwise the best score.
  double best = INFINITY;
  for (int n = 2; n <= 10; ++n) {
    for (int m = 0; m < n; ++m) {
      LinearModel trial = *lm;
      if (!fit_rational(f, g, n, m, &trial.tf.num, &trial.tf.den)) continue;
      double err_db = 0.0, err_deg = 0.0;
      for (int i = 0; i < kPoints; ++i) {
        const std::complex<double> e = std::log(trial.tf.response(f[i]) / lm->response(f[i]));
        err_db = std::max(err_db, std::abs(e.real()) * 20.0 / std::log(10.0));
        err_deg = std::max(err_deg, std::abs(e.imag()) * 180.0 / std::numbers::pi);
      }
      const double score = std::max(err_db / kTolDb, err_deg / kTolDeg);
      if (score < best) {
        best = score;
        lm->tf.num = trial.tf.num;
        lm->tf.den = trial.tf.den;
        lm->tf_max_error_db = err_db;
        lm->tf_max_error_deg = err_deg;
      }
      if (best <= 1.0) break;
    }
    if (best <= 1.0) break;
  }
  lm->fit_band_lo_hz = kFitLoHz;
  lm->fit_band_hi_hz = kFitHiHz;
}

// The electromechanical mode: the least damped complex pole pair of den.
void mode_of(LinearModel* lm) {
  const Eigen::VectorXcd poles = lm->tf.poles();
  lm->zeta = INFINITY;
  for (const auto& p : poles) {
    if (std::abs(p.imag()) < 1e-9) continue;
    const double z = -p.real() / std::abs(p);
    if (z < lm->zeta) {
      lm->zeta = z;
      lm->fn_hz = std::abs(p) / kTwoPi;
    }
  }
}

// States that do not move (derivative row identically zero: E' and Efd without flux decay)
// or that act on nothing else (no off-diagonal column entry and not measured: the boost with
// the MAP limiter inactive, the rotor angle when islanded) are dropped; they would only add
// cancelling or singular modes (j w I - A must be invertible at w = 0).
void drop_frozen_states(LinearModel* lm) {
  std::vector<int> keep;
  const Eigen::Index n = lm->a.rows();
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool moves =
        lm->a.row(i).cwiseAbs().maxCoeff() > 0.0 || lm->b[i] != 0.0 || lm->b_fuel[i] != 0.0;
    Eigen::VectorXd col = lm->a.col(i).cwiseAbs();
    col[i] = 0.0;
    const bool acts = col.maxCoeff() > 0.0 || lm->c[i] != 0.0 || lm->c_fuel[i] != 0.0;
    if (moves && acts) keep.push_back(static_cast<int>(i));
  }
  const auto k = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd a(k, k);
  Eigen::VectorXd b(k), bf(k);
  Eigen::RowVectorXd c(k), cf(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    for (Eigen::Index j = 0; j < k; ++j) a(i, j) = lm->a(keep[i], keep[j]);
    b[i] = lm->b[keep[i]];
    bf[i] = lm->b_fuel[keep[i]];
    c[i] = lm->c[keep[i]];
    cf[i] = lm->c_fuel[keep[i]];
  }
  lm->a = a;
  lm->b = b;
  lm->b_fuel = bf;
  lm->c = c;
  lm->c_fuel = cf;
}

}  // namespace

std::complex<double> LinearModel::response(double freq_hz) const {
  const std::complex<double> s{0.0, kTwoPi * freq_hz};
  const Eigen::MatrixXcd m =
      s * Eigen::MatrixXcd::Identity(a.rows(), a.cols()) - a.cast<std::complex<double>>() -
      std::exp(-s * delay_s) * (b_fuel * c_fuel).cast<std::complex<double>>();
  const Eigen::VectorXcd x = m.partialPivLu().solve(b.cast<std::complex<double>>());
  return (c.cast<std::complex<double>>() * x)(0);
}

LinearModel linearise(const PlantOptions& options) {
  const ResolvedConfig config = resolve(options);
  return linearise(config.params,
                   options.config ? options.config->filename().string() : options.preset);
}

LinearModel linearise(const Params& params, const std::string& name) {
  GensetModel model(params);
  double rack0 = 0.0;
  const Eigen::VectorXd x0 = model.steady_state(&rack0);
  LinearModel lm;
  lm.preset = name;
  jacobians(model, x0, rack0, &lm);
  const int n = model.size();
  lm.c = Eigen::RowVectorXd::Zero(n);
  lm.c[GensetModel::kMeas] = params[P::kRatedKw] * params[P::kMeasGain];
  lm.c_fuel = Eigen::RowVectorXd::Zero(n);
  lm.c_fuel[GensetModel::kGov + Degov1::kXf] = 1.0;  // rack = actuator (no backlash)
  drop_frozen_states(&lm);
  lm.delay_s = dead_time_s(params);
  lm.tf.delay_s = lm.delay_s;
  lm.dc_gain_kw_per_pct = lm.response(0.0).real();
  fit_tf(&lm);
  mode_of(&lm);
  lm.sopdt = fit_sopdt(lm, 0.5, 5.0);
  return lm;
}

}  // namespace plantsim
