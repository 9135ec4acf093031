#include "plantsim/plant/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "plantsim/plant/plant.hpp"

namespace plantsim {

Eigen::VectorXd GensetModel::steady_state(double* rack0_pu) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kSize);
  const double pe0 = p_[P::kPowerKw] / p_[P::kRatedKw];
  alt_.init(pe0, x.data() + kAlt);
  // Swing at rest: Tm = Pe/w with w = 1.
  const double rack0 = eng_.init(pe0, x.data() + kEng);
  if (cylinder_factor(p_) <= 0.0) {
    throw ConfigError("engine: no injector delivers fuel; expected at least one healthy cylinder");
  }
  if (rack0 > map_fuel_limit_pu(p_, pe0) || rack0 > p_[P::kGovTmax] || rack0 < p_[P::kGovTmin]) {
    throw ConfigError(fmt::format(
        "op.power_kw: {} kW needs fuel {:.3f} pu, outside gov.tmin_pu/gov.tmax_pu or the MAP "
        "limit {:.3f} pu",
        p_[P::kPowerKw], rack0, map_fuel_limit_pu(p_, pe0)));
  }
  gov_.init(pe0, rack0, x.data() + kGov);
  x[kMeas] = pe0;
  *rack0_pu = rack0;
  return x;
}

void GensetModel::rhs(const double* x, double bias_pu, double fuel_delayed_pu, double* dx,
                      bool limit_integrator) const {
  const double pe = alt_.electrical_power_pu(x + kAlt);
  const double dw = x[kAlt + Alternator::kDw];
  gov_.derivatives(x + kGov, pe, dw, bias_pu, dx + kGov, limit_integrator);
  eng_.derivatives(x + kEng, fuel_delayed_pu, dx + kEng);
  alt_.derivatives(x + kAlt, Engine::torque_pu(x + kEng), dx + kAlt);
  dx[kMeas] = (pe - x[kMeas]) / p_[P::kMeasLag];
}

Eigen::VectorXd GensetModel::atol_scale(const Params& p) {
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(active_size(p));
  scale[kGov + Degov1::kZ2] = 1.0 / p[P::kGovT2];
  scale[kGov + Degov1::kA2] = 1.0 / std::min(p[P::kGovT5], p[P::kGovT6]);
  return scale;
}

void GensetModel::set_frozen(const Eigen::VectorXd& full) {
  full_x_ = full;
  active_ = active_size(p_);
}

bool GensetModel::derivatives(double t, const double* x, double* dx) {
  apply_ramps(t);
  full_x_.head(active_) = Eigen::Map<const Eigen::VectorXd>(x, active_);
  const double bias_pu = split_ ? 0.0 : bias_pu_;
  if (engine_path_ != nullptr) {
    // Same equations as rhs() with the engine taken from the closed form.
    const double* xs = full_x_.data();
    double* dxs = full_dx_.data();
    const double torque = engine_path_->torque_at(t);
    const double pe = alt_.electrical_power_pu(xs + kAlt);
    gov_.derivatives(xs + kGov, pe, xs[kAlt + Alternator::kDw], bias_pu, dxs + kGov, !split_);
    dxs[kEng + Engine::kTorque] = 0.0;
    dxs[kEng + Engine::kBoost] = 0.0;
    alt_.derivatives(xs + kAlt, torque, dxs + kAlt);
    dxs[kMeas] = (pe - xs[kMeas]) / p_[P::kMeasLag];
  } else {
    rhs(full_x_.data(), bias_pu, delay_->at(t - dead_time_s(p_)), full_dx_.data(), !split_);
  }
  Eigen::Map<Eigen::VectorXd>(dx, active_) = full_dx_.head(active_);
  return full_dx_.head(active_).allFinite();
}

std::complex<double> GensetModel::torque_to_measured_power(const double* x,
                                                           std::complex<double> s) const {
  return alt_.torque_to_power(x + kAlt, s) / (1.0 + s * p_[P::kMeasLag]);
}

}  // namespace plantsim
