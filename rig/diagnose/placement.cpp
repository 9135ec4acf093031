#include "rig/diagnose/placement.hpp"

#include <cmath>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {

namespace {

struct PlaceWords {
  Place place;
  const char* name;    // report.json
  const char* suffix;  // after the effect's word in report.html
  const char* acts;    // augmented_model.json
};

constexpr PlaceWords kPlaceWords[] = {
    {Place::kInput, "input", "", "input, before the tf"},
    {Place::kInLoop, "in_loop", " (in the loop)",
     "in the loop: after 1/(1 + s front_lag_s), before the tf times (1 + s front_lag_s)"},
    {Place::kOutput, "output", " (at the output)",
     "output: on the tf's output over its static gain"},
    {Place::kFeedback, "feedback", " (in an output feedback)",
     "feedback: u - feedback_gain (y' - N(y')) into the tf, y' = its output over its static gain"},
    {Place::kError, "error", " (on the loop's error)",
     "error: on e = u - y / G0 of a unity-feedback loop whose closed loop is the tf: "
     "y = tf (u - (e - N(e)))"},
    {Place::kPiLoop, "pi_loop", " (after the governor's PI, in its loop)",
     "after the PI and output filter of a unity-feedback loop whose closed loop is the tf: "
     "e = u - y / G0, a = k C e, C = (1 + 1 / (s integral_time_s)) / (1 + s filter_lag_s), "
     "y = tf (u - C^-1 (a - N(a)) / k), k from the linear loop's a in the bias's rms"},
    {Place::kGovernorError, "governor_error", " (on the governor's error, its feedback fitted)",
     "error: on e = u - h(y / G0) of a loop whose closed loop is the tf, h = (loop_static_share "
     "+ loop_derivative_s s) / (1 + s loop_filter_s): y = tf (u - (e - N(e)))"},
    {Place::kGovernorPi, "governor_pi",
     " (after the governor's PI, in its loop, its feedback fitted)",
     "after the PI and output filter of a loop whose closed loop is the tf: e = u - h(y / G0), "
     "h = (loop_static_share + loop_derivative_s s) / (1 + s loop_filter_s), "
     "a = k C e, C = (1 + 1 / (s integral_time_s)) / (1 + s filter_lag_s), "
     "y = tf (u - C^-1 (a - N(a)) / k), k from the linear loop's a in the bias's rms"},
    {Place::kGovernorLoop, "governor_loop", " (inside the governor's loop)",
     "inside a loop whose closed loop is the tf (its dead time outside), forward part "
     "P = G' / (1 - G' h), G' = tf / G0, feedback h = (loop_static_share + loop_derivative_s s) / "
     "(1 + s loop_filter_s): tf F / (1 - G' h (1 - F))"},
};

const PlaceWords& words(Place place) {
  for (const auto& w : kPlaceWords)
    if (w.place == place) return w;
  return kPlaceWords[0];
}

}  // namespace

const char* to_string(Place place) { return words(place).name; }
const char* place_suffix(Place place) { return words(place).suffix; }
const char* place_acts(Place place) { return words(place).acts; }

std::vector<ParamSpec> place_specs(Place place, const DataScales& s) {
  if (place == Place::kFeedback)
    return {{"feedback_gain", -thresholds::kFeedbackGainMax, thresholds::kFeedbackGainMax, false}};
  std::vector<ParamSpec> out;
  if (after_pi(place))
    out = {{"integral_time_s", thresholds::kPiIntegralMinS, thresholds::kPiIntegralMaxS, true},
           {"filter_lag_s", thresholds::kPiFilterMinS, thresholds::kPiFilterMaxS, true}};
  if (feedback_fitted(place)) {
    out.push_back({"loop_static_share", thresholds::kLoopStaticMin, thresholds::kLoopStaticMax});
    out.push_back({"loop_derivative_s", 0.0, thresholds::kLoopDerivativeMaxS});
    out.push_back(
        {"loop_filter_s", thresholds::kLoopFilterMinS, thresholds::kLoopFilterMaxS, true});
  }
  if (!out.empty()) return out;
  if (place != Place::kInLoop) return {};
  return {{"front_lag_s", std::max(s.dt_s, thresholds::kFrontLagMinS), thresholds::kFrontLagMaxS,
           true}};
}

bool in_loop_possible(const model::TransferFunction& tf) {
  return tf.numerator_order() < tf.order();
}

Eigen::VectorXd front_signal(const Eigen::VectorXd& v, double front_lag_s, double dt_s) {
  model::TransferFunction lag;
  lag.num = Eigen::VectorXd::Ones(1);
  lag.den = Eigen::Vector2d(front_lag_s, 1.0);
  return model::simulate(lag, v, dt_s);
}

double in_loop_scale(const Problem& pr, const Eigen::VectorXd& w) {
  const double sw = std::sqrt((w.array() - w.mean()).square().mean());
  return sw > 0.0 ? pr.scales.u_std / sw : 1.0;
}

namespace {
// The rms ratio of u to w.
double rms_ratio(const Eigen::VectorXd& u, const Eigen::VectorXd& w) {
  const auto rms = [](const Eigen::VectorXd& x) {
    return std::sqrt((x.array() - x.mean()).square().mean());
  };
  const double sw = rms(w);
  return sw > 0.0 ? rms(u) / sw : 1.0;
}
}  // namespace

Eigen::VectorXd linear_error(const Problem& pr, const LoopFeedback* feedback) {
  const Eigen::VectorXd y = pr.baseline_z / pr.scales.dc_gain;
  return feedback ? Eigen::VectorXd(pr.u - feed_back(*feedback, y, pr.dt_s))
                  : Eigen::VectorXd(pr.u - y);
}

PiSignal pi_signal(const Problem& pr, const PiGovernor& gov, const LoopFeedback* feedback) {
  const Eigen::VectorXd e = linear_error(pr, feedback);
  PiSignal out{Eigen::VectorXd(e.size()), 1.0};
  const double r = pr.dt_s / gov.integral_time_s, p = pi_filter_pole(gov.filter_lag_s, pr.dt_s);
  double sum = 0.0, f = 0.0;
  for (Eigen::Index i = 0; i < e.size(); ++i)
    out.a(i) = f = p * f + (1.0 - p) * (e(i) + r * (sum += e(i)));
  // The bias-% equivalent above the integrator's wander (thresholds.hpp).
  const double hp = thresholds::kPiScaleHighPassS;
  out.k = rms_ratio(signal::ac_couple(pr.u, pr.dt_s, hp), signal::ac_couple(out.a, pr.dt_s, hp));
  out.a *= out.k;
  return out;
}

PiGovernor pi_governor(std::span<const double> place_params) {
  return {place_params[0], place_params.size() > 1 ? place_params[1] : 0.0};
}

model::TransferFunction rest_after_front(const model::TransferFunction& tf, double front_lag_s) {
  model::TransferFunction out = tf;
  out.num = poly_multiply(tf.num, Eigen::Vector2d(front_lag_s, 1.0));
  return out;
}

Problem problem_at(const Problem& pr, Place place, std::span<const double> place_params) {
  const double place_param = place_params.empty() ? 0.0 : place_params[0];
  Problem at = pr;
  if (place == Place::kInLoop) {
    const Eigen::VectorXd w = front_signal(pr.u, place_param, pr.dt_s);
    at.u = in_loop_scale(pr, w) * w;
  } else if (place == Place::kOutput || place == Place::kFeedback) {
    at.u = pr.baseline_z / pr.scales.dc_gain;
  } else if (on_error(place)) {
    const LoopFeedback h = feedback_fitted(place) ? loop_feedback(place_params) : LoopFeedback{};
    at.u = linear_error(pr, feedback_fitted(place) ? &h : nullptr);
  } else if (after_pi(place)) {
    const LoopFeedback h = feedback_fitted(place) ? loop_feedback(place_params) : LoopFeedback{};
    at.u = pi_signal(pr, pi_governor(place_params), feedback_fitted(place) ? &h : nullptr).a;
  } else {
    return at;
  }
  finish_problem(at);
  return at;
}

std::vector<std::vector<AppliedEffect>> placed_starts(Effect effect, Place place, const Problem& pr,
                                                      const Location& loc) {
  std::vector<std::vector<AppliedEffect>> out;
  if (place == Place::kFeedback) {
    const Problem at = problem_at(pr, place, {});
    for (auto& p : seeds_for(effect, at, loc))
      for (const double c : thresholds::kFeedbackGainSeeds)
        out.push_back({AppliedEffect{effect, p, place, {c}}});
    return out;
  }
  // The fitted feedback of the error-loop places starts from a speed loop (a unity one is
  // the error and pi_loop places' own).
  const auto& speed = thresholds::kLoopSeeds[thresholds::kSpeedLoopSeed];
  if (after_pi(place)) {
    for (const double ti_s : thresholds::kPiIntegralSeedsS) {
      std::vector<double> gov{ti_s, thresholds::kPiFilterSeedS};
      if (feedback_fitted(place)) gov.insert(gov.end(), {speed[0], speed[1], speed[2]});
      const Problem at = problem_at(pr, place, gov);
      for (auto& p : seeds_for(effect, at, loc))
        out.push_back({AppliedEffect{effect, p, place, gov}});
    }
    return out;
  }
  if (place == Place::kGovernorError) {
    const std::vector<double> h{speed[0], speed[1], speed[2]};
    const Problem at = problem_at(pr, place, h);
    for (auto& p : seeds_for(effect, at, loc)) out.push_back({AppliedEffect{effect, p, place, h}});
    return out;
  }
  if (place == Place::kGovernorLoop) {  // a linear effect: its seeds at the input's scales
    for (auto& p : seeds_for(effect, pr, loc))
      for (const auto& h : thresholds::kLoopSeeds)
        out.push_back({AppliedEffect{effect, p, place, {h[0], h[1], h[2]}}});
    return out;
  }
  if (place != Place::kInLoop) {
    const Problem at = problem_at(pr, place, {});
    for (auto& p : seeds_for(effect, at, loc)) out.push_back({AppliedEffect{effect, p, place, {}}});
    return out;
  }
  for (const double lag_s : thresholds::kFrontLagSeedsS) {
    const Problem at = problem_at(pr, place, std::vector<double>{lag_s});
    for (auto& p : seeds_for(effect, at, loc))
      out.push_back({AppliedEffect{effect, p, place, {lag_s}}});
  }
  return out;
}

bool place_credible(const AppliedEffect& e) {
  if (e.place_params.empty()) return true;
  if (e.place == Place::kInLoop)
    return e.place_params[0] < thresholds::kFrontLagAtBound * thresholds::kFrontLagMaxS;
  if (after_pi(e.place)) {
    const auto& p = e.place_params;
    // A fitted feedback may carry a governor with no integrator (a droop governor's
    // proportional action): its integral time may stop at the upper bound.
    const bool integral_ok = feedback_fitted(e.place) ||
                             p[0] < thresholds::kFrontLagAtBound * thresholds::kPiIntegralMaxS;
    if (!integral_ok || p[0] * thresholds::kFrontLagAtBound <= thresholds::kPiIntegralMinS ||
        p.at(1) >= thresholds::kFrontLagAtBound * thresholds::kPiFilterMaxS)
      return false;
  }
  if (feedback_fitted(e.place)) {
    const LoopFeedback h = loop_feedback(e.place_params);
    const double at = thresholds::kLoopAtBound;
    return h.static_share < at * thresholds::kLoopStaticMax &&
           h.static_share > at * thresholds::kLoopStaticMin &&
           h.derivative_s < at * thresholds::kLoopDerivativeMaxS &&
           h.filter_s < at * thresholds::kLoopFilterMaxS;  // at the lower bound: no filter
  }
  return true;
}

}  // namespace rig::diagnose
