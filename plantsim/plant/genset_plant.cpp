#include "plantsim/plant/genset_plant.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace plantsim {
namespace {

constexpr double kMaxDeadTimeS = 1.0;  // engine.dead_time_s upper bound; sizes the history
constexpr double kSameTimeS = 1e-9;    // times closer than this are one (round-off)

// The exact bias path needs the setpoint path to be linear: no deadband on e, no rate limit.
bool linear_setpoint_path(const Params& p) {
  return p[P::kGovDeadband] == 0.0 && p[P::kGovRate] == 0.0;
}

// The ramp for a change, between the values in effect before and after it. A ramp of
// engine.dead_time_s runs between dead times: its 0 stands for the formula 30/N + 60/(n N),
// so from or to 0 the ramp starts or ends at the formula's value, never at no dead time.
ParamRamp ramp_for(const TimedChange& change, const Params& before, const Params& after) {
  ParamRamp r{change.param,         change.time_s, change.time_s + change.ramp_s,
              before[change.param], change.value,  change.value};
  if (change.param == P::kEngDeadTime) {
    r.from = dead_time_s(before);
    r.to = dead_time_s(after);
  }
  return r;
}

SolverOptions solver_options(const Params& p) {
  SolverOptions o;
  o.rtol = p[P::kSolverRtol];
  o.atol = p[P::kSolverAtol];
  o.atol_scale = GensetModel::atol_scale(p);
  return o;
}

}  // namespace

GensetPlant::GensetPlant(const Params& params, std::vector<TimedChange> changes, std::uint64_t seed,
                         std::chrono::nanoseconds tick)
    : model_(params),
      tick_(tick),
      dt_s_(std::chrono::duration<double>(tick).count()),
      chain_(seed, dt_s_),
      changes_(std::move(changes)),
      ripple_refresh_ticks_(std::max(1, static_cast<int>(std::lround(kRippleRefreshS / dt_s_)))) {
  if (!(dt_s_ > 0.0 && dt_s_ <= 0.1)) {
    throw ConfigError(fmt::format("tick: {} s, expected 0 < tick <= 0.1 s", dt_s_));
  }
  // The history buffer holds kMaxDeadTimeS: check the dead time now and after every change.
  Params check = params;
  for (std::size_t i = 0; i <= changes_.size(); ++i) {
    if (dead_time_s(check) > kMaxDeadTimeS) {
      throw ConfigError(fmt::format(
          "engine: fuel dead time {:.3f} s{}, expected <= {} s", dead_time_s(check),
          i == 0 ? "" : " after --fault '" + changes_[i - 1].text + "'", kMaxDeadTimeS));
    }
    if (i < changes_.size()) check.set(changes_[i].param, changes_[i].value, changes_[i].text);
  }
  double rack0 = 0.0;
  const Eigen::VectorXd x0 = model_.steady_state(&rack0);
  delay_ = std::make_unique<FuelDelayLine>(dt_s_, kMaxDeadTimeS + dt_s_, rack0);
  backlash_.reset(rack0);
  actuator_pu_ = rack0;
  transducer_.reset(x0[GensetModel::kMeas]);
  model_.set_delay_line(delay_.get());
  model_.set_ramps(&ramps_);
  model_.set_split_bias_path(linear_setpoint_path(params));
  x_ = x0;
  restart_solver(0.0);
  reconfigure();
  while (next_change_ < changes_.size() && changes_[next_change_].time_s <= 0.0) {
    apply(changes_[next_change_++]);
  }
  update_measurement();
}

void GensetPlant::restart_solver(double t_s, bool try_engine_path) {
  const EnginePath::State engine{x_[GensetModel::kEng + Engine::kTorque],
                                 x_[GensetModel::kEng + Engine::kBoost]};
  const bool path = try_engine_path && !ramps_.touches_engine() &&
                    EnginePath::usable(model_.params(), dt_s_) &&
                    engine_path_.anchor(model_.params(), t_s, engine, *delay_);
  model_.set_engine_path(path ? &engine_path_ : nullptr);
  ode_engine_ticks_ = 0;
  model_.set_frozen(x_);
  const int n = GensetModel::active_size(model_.params());
  solver_ = std::make_unique<CvodeSolver>(model_, t_s, x_.head(n), solver_options(model_.params()));
}

void GensetPlant::sync_state() {
  model_.apply_ramps(solver_->time());
  x_.head(solver_->state().size()) = solver_->state();
  if (model_.engine_path() == nullptr) return;
  const EnginePath::State e = engine_path_.at(solver_->time());
  x_[GensetModel::kEng + Engine::kTorque] = e.torque_pu;
  x_[GensetModel::kEng + Engine::kBoost] = e.boost_pu;
}

// With the engine in the ODE after a clamp acted, tries the closed form again now and then;
// only a path that holds up to the newest corner restarts the solver.
void GensetPlant::retry_engine_path() {
  if (model_.engine_path() != nullptr || ramps_.touches_engine() ||
      ++ode_engine_ticks_ < kEngineRetryTicks) {
    return;
  }
  ode_engine_ticks_ = 0;
  const EnginePath::State engine{x_[GensetModel::kEng + Engine::kTorque],
                                 x_[GensetModel::kEng + Engine::kBoost]};
  if (EnginePath::usable(model_.params(), dt_s_) &&
      engine_path_.anchor(model_.params(), solver_->time(), engine, *delay_)) {
    restart_solver(solver_->time());
  }
}

// How far CVODE may step: to the end of the tick, or with look-ahead as far as the fuel is
// known (t_now + Td; not while the dead time itself ramps), and with the engine in closed
// form no further than its newest knot.
double GensetPlant::horizon_s(double t_now, double t_end, bool look_ahead) const {
  const bool ahead = look_ahead && !ramps_.touches_dead_time();
  double h = ahead ? t_now + dead_time_s(model_.params()) : t_end;
  if (model_.engine_path() != nullptr) h = std::min(h, engine_path_.valid_until_s());
  return std::max(h, t_end);
}

// Where the closed-form engine stops holding (a clamp acts beyond it): the engine returns to
// the ODE there. Infinity while it holds or the ODE already has the engine.
double GensetPlant::engine_handback_s() const {
  if (model_.engine_path() == nullptr || engine_path_.valid()) {
    return std::numeric_limits<double>::infinity();
  }
  return engine_path_.valid_until_s();
}

void GensetPlant::reconfigure() {
  bias_path_.configure(model_.params(), dt_s_);
  configure_ripple();
}

void GensetPlant::configure_ripple() {
  const Eigen::VectorXd& x = x_;
  ripple_.configure(model_.params(), [&](std::complex<double> s) {
    return model_.torque_to_measured_power(x.data(), s);
  });
}

// While ramps run, the quantities derived from their parameters follow them: the bias path
// every tick, the firing ripple every kRippleRefreshS.
void GensetPlant::refresh_ramped() {
  if (ramps_.touches_bias_path()) bias_path_.configure(model_.params(), dt_s_);
  if (ramps_.touches_ripple() && ++ripple_ticks_ >= ripple_refresh_ticks_) {
    ripple_ticks_ = 0;
    configure_ripple();
  }
}

void GensetPlant::apply(const TimedChange& change) {
  const std::string where = "--fault '" + change.text + "'";
  Params& p = model_.mutable_params();
  if (change.ramp_s > 0.0) {
    Params check = p;
    check.set(change.param, change.value, where);
    ramps_.start(ramp_for(change, p, check));
  } else {
    ramps_.cancel(change.param);
    p.set(change.param, change.value, where);
  }
  parameters_changed();
}

void GensetPlant::finish_ramp() {
  ramps_.finish_next(&model_.mutable_params());
  parameters_changed();
}

void GensetPlant::parameters_changed() {
  // A ramp of the deadband or rate limit keeps the setpoint path nonlinear while it runs.
  const bool split = linear_setpoint_path(model_.params()) && !ramps_.touches_setpoint();
  if (model_.split_bias_path() && !split) {
    // Superposition undone: the ODE's governor states become the sums, the bias enters e.
    x_.segment<BiasPath::kStates>(GensetModel::kGov + Degov1::kZ1) += bias_path_.state();
    bias_path_.reset();
  }
  model_.set_split_bias_path(split);
  reconfigure();
  // A parameter step or the start or end of a ramp makes the right-hand side (or its slope)
  // discontinuous, and may change the active states or the tolerances: restart CVODE from
  // the state at the change.
  restart_solver(solver_->time());
}

void GensetPlant::advance_bias_path(double duration_s) {
  if (!model_.split_bias_path()) return;
  const double r_pu = model_.params()[P::kGovR] * bias_pct_ / 100.0;
  if (std::abs(duration_s - dt_s_) < 1e-12) {
    bias_path_.advance(r_pu);
  } else {
    bias_path_.advance(r_pu, duration_s);
  }
}

// Look-ahead: the plant after the rack sees the governor only through the fuel dead time, so
// CVODE may step on as far as the rack history reaches, t_k + Td, and ticks are interpolated
// from its dense output. With the exact bias path (BiasPath) a bias change never touches the
// ODE. Without it (deadband or rate limit set) the bias enters e: while the bias keeps
// changing every tick is a stop time; after a quiet spell CVODE may look ahead again, and a
// change then rolls it back to the tick (reinit from the interpolated state).
bool GensetPlant::advance_solver(double t_now, double t_end) {
  const double bias_pu = bias_pct_ / 100.0;
  const bool split = model_.split_bias_path();
  if (!split && bias_pu != model_.bias_pu()) {
    // CVODE may end a stop-time step a round-off beyond the tick; that is not look-ahead.
    if (solver_->internal_time() > t_now + 1e-9) {
      solver_->reinit(solver_->time(), solver_->state());
    }
    quiet_ticks_ = 0;
  } else if (quiet_ticks_ < kLookAheadAfterTicks) {
    ++quiet_ticks_;
  }
  model_.set_bias_pu(bias_pu);
  const bool look_ahead = split || quiet_ticks_ >= kLookAheadAfterTicks;
  constexpr double kNever = std::numeric_limits<double>::infinity();
  double t_seg = t_now;
  try {
    for (;;) {
      const bool change = next_change_ < changes_.size();
      const double t_change = change ? std::max(changes_[next_change_].time_s, t_now) : kNever;
      const double t_ramp = std::max(ramps_.next_end_s(), t_now);
      const double t_handback = engine_handback_s();
      const double t_param = std::min(t_change, t_ramp);
      double t_event = std::min(t_param, t_handback);
      if (t_event > t_end) break;
      // Within round-off of the tick's end (t_now + dt against t0 + ramp) an event happens at
      // the end: after the restart CVODE could not step that round-off (CV_TOO_CLOSE).
      if (t_event > t_end - kSameTimeS) t_event = t_end;
      solver_->advance_to(t_event, horizon_s(t_now, t_event, look_ahead));
      sync_state();
      advance_bias_path(t_event - t_seg);
      t_seg = t_event;
      if (t_handback <= t_param) {
        restart_solver(t_event, false);
      } else if (t_ramp <= t_change) {
        finish_ramp();  // before a change at the same time, which then wins
      } else {
        apply(changes_[next_change_++]);
      }
    }
    solver_->advance_to(t_end, horizon_s(t_now, t_end, look_ahead));
    sync_state();
  } catch (const SolverError& e) {
    error_ = e.what();
    return false;
  }
  advance_bias_path(t_end - t_seg);
  return true;
}

void GensetPlant::step() {
  if (last_.fault) return;  // a failed solver stays failed; the servers report it
  const double t_now = static_cast<double>(ticks_) * dt_s_;
  const double t_end = t_now + dt_s_;
  retry_engine_path();
  engine_path_.prune(t_now);
  if (!advance_solver(t_now, t_end)) {
    last_.fault = true;
    return;
  }
  ++ticks_;
  if (!ramps_.empty()) refresh_ramped();
  const Eigen::VectorXd& x = x_;
  const Params& p = model_.params();
  const double xf_ode = Degov1::actuator_pu(x.data() + GensetModel::kGov);
  actuator_pu_ = xf_ode;
  if (model_.split_bias_path()) {
    bias_path_.clamp_integrator(xf_ode, p[P::kGovTmin], p[P::kGovTmax]);
    actuator_pu_ = xf_ode + bias_path_.integrator_pu();
  }
  const double rack = backlash_.update(actuator_pu_, p[P::kGovBacklash]);
  delay_->push(t_end, rack);
  if (model_.engine_path() != nullptr) engine_path_.extend(*delay_);
  transducer_.advance(model_.electrical_power_pu(x.data()), dt_s_, p[P::kMeasLag]);
  const double w = 1.0 + x[GensetModel::kAlt + Alternator::kDw];
  ripple_pu_ = ripple_.advance(dt_s_, w, Engine::torque_pu(x.data() + GensetModel::kEng));
  update_measurement();
}

double GensetPlant::electrical_power_kw() const {
  return model_.electrical_power_pu(x_.data()) * model_.params()[P::kRatedKw];
}

void GensetPlant::update_measurement() {
  const Eigen::VectorXd& x = x_;
  const Params& p = model_.params();
  const double t = static_cast<double>(ticks_) * dt_s_;
  const double dw = x[GensetModel::kAlt + Alternator::kDw];
  last_.time_s = t;
  last_.power_w = 1e3 * chain_.sample_kw(p, t, transducer_.value(), ripple_pu_);
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
