#include "plantsim/plant/genset_plant.hpp"

#include <fmt/format.h>

#include <cmath>

namespace plantsim {
namespace {

constexpr double kMaxDeadTimeS = 1.0;  // engine.dead_time_s upper bound; sizes the history

SolverOptions solver_options(const Params& p) {
  SolverOptions o;
  o.rtol = p[P::kSolverRtol];
  o.atol = p[P::kSolverAtol];
  return o;
}

}  // namespace

GensetPlant::GensetPlant(const Params& params, std::vector<TimedChange> changes,
                         std::uint64_t seed, std::chrono::nanoseconds tick)
    : model_(params),
      tick_(tick),
      dt_s_(std::chrono::duration<double>(tick).count()),
      chain_(seed, dt_s_),
      changes_(std::move(changes)) {
  if (!(dt_s_ > 0.0 && dt_s_ <= 0.1)) {
    throw ConfigError(fmt::format("tick: {} s, expected 0 < tick <= 0.1 s", dt_s_));
  }
  double rack0 = 0.0;
  const Eigen::VectorXd x0 = model_.steady_state(&rack0);
  delay_ = std::make_unique<FuelDelayLine>(dt_s_, kMaxDeadTimeS + dt_s_, rack0);
  backlash_.reset(rack0);
  model_.set_delay_line(delay_.get());
  solver_ = std::make_unique<CvodeSolver>(model_, 0.0, x0, solver_options(params));
  reconfigure();
  while (next_change_ < changes_.size() && changes_[next_change_].time_s <= 0.0) {
    apply(changes_[next_change_++]);
  }
  update_measurement();
}

void GensetPlant::reconfigure() {
  const Eigen::VectorXd& x = solver_->state();
  ripple_.configure(model_.params(), [&](std::complex<double> s) {
    return model_.torque_to_measured_power(x.data(), s);
  });
}

void GensetPlant::apply(const TimedChange& change) {
  model_.mutable_params().set(change.param, change.value, "--fault '" + change.text + "'");
  reconfigure();
  // A parameter step makes the right-hand side discontinuous: restart the multistep history.
  solver_->reinit(solver_->time(), solver_->state());
}

void GensetPlant::step() {
  if (last_.fault) return;  // a failed solver stays failed; the servers report it
  const double t_end = static_cast<double>(ticks_ + 1) * dt_s_;
  model_.set_bias_pu(bias_pct_ / 100.0);
  try {
    while (next_change_ < changes_.size() && changes_[next_change_].time_s <= t_end) {
      solver_->advance_to(changes_[next_change_].time_s);
      apply(changes_[next_change_++]);
    }
    solver_->advance_to(t_end);
  } catch (const SolverError& e) {
    error_ = e.what();
    last_.fault = true;
    return;
  }
  ++ticks_;
  const Eigen::VectorXd& x = solver_->state();
  const Params& p = model_.params();
  const double rack = backlash_.update(Degov1::actuator_pu(x.data() + GensetModel::kGov),
                                       p[P::kGovBacklash]);
  delay_->push(t_end, rack);
  const double w = 1.0 + x[GensetModel::kAlt + Alternator::kDw];
  ripple_pu_ = ripple_.advance(dt_s_, w, Engine::torque_pu(x.data() + GensetModel::kEng));
  update_measurement();
}

double GensetPlant::electrical_power_kw() const {
  return model_.electrical_power_pu(solver_->state().data()) * model_.params()[P::kRatedKw];
}

void GensetPlant::update_measurement() {
  const Eigen::VectorXd& x = solver_->state();
  const Params& p = model_.params();
  const double t = static_cast<double>(ticks_) * dt_s_;
  const double dw = x[GensetModel::kAlt + Alternator::kDw];
  last_.time_s = t;
  last_.power_w = 1e3 * chain_.sample_kw(p, t, x[GensetModel::kMeas], ripple_pu_);
  last_.speed_rpm = p[P::kEngRpm] * (1.0 + dw);
  last_.freq_hz = p[P::kFreqHz] * (1.0 + dw);
  last_.voltage_v = model_.terminal_voltage_pu(x.data()) * p[P::kRatedVoltageV];
  last_.bias_applied_pct = bias_pct_;
  last_.running = true;
  last_.breaker_closed = p[P::kGridConnected] > 0.5;
  last_.fault = false;
}

std::unique_ptr<Plant> make_plant(const PlantOptions& options) {
  ResolvedConfig config = resolve(options);
  return std::make_unique<GensetPlant>(config.params, std::move(config.changes), options.seed,
                                       options.tick);
}

}  // namespace plantsim
