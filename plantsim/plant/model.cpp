#include "plantsim/plant/model.hpp"

#include <fmt/format.h>

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

void GensetModel::set_frozen(const Eigen::VectorXd& full) {
  full_x_ = full;
  active_ = active_size(p_);
}

bool GensetModel::derivatives(double t, const double* x, double* dx) {
  const double fuel = delay_->at(t - dead_time_s(p_));
  full_x_.head(active_) = Eigen::Map<const Eigen::VectorXd>(x, active_);
  if (split_) {
    rhs(full_x_.data(), 0.0, fuel, full_dx_.data(), false);
  } else {
    rhs(full_x_.data(), bias_pu_, fuel, full_dx_.data());
  }
  Eigen::Map<Eigen::VectorXd>(dx, active_) = full_dx_.head(active_);
  return full_dx_.head(active_).allFinite();
}

std::complex<double> GensetModel::torque_to_measured_power(const double* x,
                                                           std::complex<double> s) const {
  return alt_.torque_to_power(x + kAlt, s) / (1.0 + s * p_[P::kMeasLag]);
}

}  // namespace plantsim
