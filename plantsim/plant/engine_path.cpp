#include "plantsim/plant/engine_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plantsim {
namespace {

// A corner within this fraction of a tick of the last knot is that knot (round-off of
// t_newest - i dt + Td against a knot time computed the same way).
constexpr double kSameCornerTicks = 1e-9;
// Round-off of times far from zero (a day of plant time is 8.6e4 s): the tolerance of a
// corner's tick count grows with the time's magnitude, this many ulps of it.
constexpr double kRoundOffUlps = 64.0;
// Knots dropped by prune() are erased once this many have piled up (no per-tick moves).
constexpr std::size_t kCompactAfterKnots = 256;

// y(tau) for T y' = c f - y with f = f0 + s tau and y(0) = y0 (see the header), with the
// decay e^{-tau/T} given.
double lag(double y0, double c, double f0, double s, double t_s, double tau_s, double decay) {
  const double forced = c * (f0 + s * tau_s) - c * t_s * s;
  return forced + (y0 - c * f0 + c * t_s * s) * decay;
}

double lag(double y0, double c, double f0, double s, double t_s, double tau_s) {
  return lag(y0, c, f0, s, t_s, tau_s, std::exp(-tau_s / t_s));
}

}  // namespace

bool EnginePath::usable(const Params& p, double dt_s) { return dead_time_s(p) >= dt_s; }

bool EnginePath::anchor(const Params& p, double t_s, State s, const FuelDelayLine& line) {
  tc_s_ = p[P::kEngCombustionLag];
  tb_s_ = p[P::kEngBoostLag];
  c_ = cylinder_factor(p);
  td_s_ = dead_time_s(p);
  map_min_pu_ = p[P::kEngMapMin];
  map_gain_ = p[P::kEngMapGain];
  dt_s_ = line.dt_s();
  tick_decay_tc_ = std::exp(-dt_s_ / tc_s_);
  tick_decay_tb_ = std::exp(-dt_s_ / tb_s_);
  knots_.clear();
  first_ = 0;
  const double fuel = line.at(t_s - td_s_);
  knots_.push_back({t_s, fuel, s.torque_pu, s.boost_pu});
  valid_ = usable(p, line.dt_s()) && fuel >= 0.0 && headroom_pu(fuel, s.boost_pu) >= 0.0;
  return valid_ && extend(line);
}

bool EnginePath::extend(const FuelDelayLine& line) {
  const double dt = line.dt_s();
  const double tol_ticks =
      std::max(kSameCornerTicks, kRoundOffUlps * std::numeric_limits<double>::epsilon() *
                                     std::abs(line.newest_time_s()) / dt);
  long newer_than = std::numeric_limits<long>::max();
  while (valid_) {
    // The oldest sample taken after the last knot's fuel time t_last - Td. Each corner takes a
    // newer sample than the one before (a corner recomputed a round-off later is not new), so
    // the loop ends whatever the round-off at large times.
    const double ticks_back = (line.newest_time_s() - (knots_.back().t_s - td_s_)) / dt;
    const long back =
        std::min(static_cast<long>(std::ceil(ticks_back - tol_ticks)) - 1, newer_than - 1);
    if (back < 0) break;
    newer_than = back;
    const auto b = static_cast<std::size_t>(back);
    const double t_corner = line.newest_time_s() - static_cast<double>(back) * dt + td_s_;
    if (!push_corner(t_corner, line.sample(b))) break;
  }
  return valid_;
}

// Appends the knot at t_s with fuel f_b, after checking the clamps over the segment: fuel is
// linear, so f >= 0 at both ends suffices; the MAP headroom F0 + Fb boost - f is linear plus
// Fb A e^{-tau/Tb}, which departs from its chord by at most Fb |A| h^2 / (8 Tb^2).
bool EnginePath::push_corner(double t_s, double fuel_pu) {
  const Knot& a = knots_.back();
  const double h = t_s - a.t_s;
  const double slope = (fuel_pu - a.fuel_pu) / h;
  // Knots lie a tick apart but for the first after an anchor: reuse the tick's decays.
  const bool tick = std::abs(h - dt_s_) <= kSameCornerTicks * dt_s_;
  const double tau = tick ? dt_s_ : h;
  const double decay_tc = tick ? tick_decay_tc_ : std::exp(-h / tc_s_);
  const double decay_tb = tick ? tick_decay_tb_ : std::exp(-h / tb_s_);
  const Knot k{t_s, fuel_pu, lag(a.torque_pu, c_, a.fuel_pu, slope, tc_s_, tau, decay_tc),
               lag(a.boost_pu, c_, a.fuel_pu, slope, tb_s_, tau, decay_tb)};
  const double amp = a.boost_pu - c_ * a.fuel_pu + c_ * tb_s_ * slope;
  const double bow_pu = map_gain_ * std::abs(amp) * h * h / (8.0 * tb_s_ * tb_s_);
  if (fuel_pu < 0.0 || headroom_pu(fuel_pu, k.boost_pu) < bow_pu ||
      headroom_pu(a.fuel_pu, a.boost_pu) < bow_pu) {
    valid_ = false;
    return false;
  }
  knots_.push_back(k);
  return true;
}

void EnginePath::prune(double t_s) {
  while (first_ + 1 < knots_.size() && knots_[first_ + 1].t_s <= t_s) ++first_;
  if (first_ >= kCompactAfterKnots) {
    knots_.erase(knots_.begin(), knots_.begin() + static_cast<std::ptrdiff_t>(first_));
    first_ = 0;
  }
}

const EnginePath::Knot& EnginePath::knot_before(double t_s) const {
  const auto begin = knots_.begin() + static_cast<std::ptrdiff_t>(first_);
  auto it =
      std::upper_bound(begin, knots_.end(), t_s, [](double t, const Knot& k) { return t < k.t_s; });
  return it == begin ? *begin : *(it - 1);
}

double EnginePath::slope_after(const Knot& k) const {
  if (&k == &knots_.back()) return 0.0;  // past the newest corner the fuel holds its value
  const Knot& next = *(&k + 1);
  return (next.fuel_pu - k.fuel_pu) / (next.t_s - k.t_s);
}

double EnginePath::torque_at(double t_s) const {
  const Knot& k = knot_before(t_s);
  return lag(k.torque_pu, c_, k.fuel_pu, slope_after(k), tc_s_, t_s - k.t_s);
}

EnginePath::State EnginePath::at(double t_s) const {
  const Knot& k = knot_before(t_s);
  const double slope = slope_after(k);
  return {lag(k.torque_pu, c_, k.fuel_pu, slope, tc_s_, t_s - k.t_s),
          lag(k.boost_pu, c_, k.fuel_pu, slope, tb_s_, t_s - k.t_s)};
}

double EnginePath::headroom_pu(double fuel_pu, double boost_pu) const {
  return map_min_pu_ + map_gain_ * boost_pu - fuel_pu;
}

}  // namespace plantsim
