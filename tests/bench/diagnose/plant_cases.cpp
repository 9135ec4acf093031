#include "plant_cases.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/linearise.hpp"
#include "plantsim/plant/model.hpp"
#include "plantsim/plant/plant.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::diagnose::bench {
namespace {

constexpr double kDt = 0.01;
constexpr double kSettleS = 40.0;    // operating point, drift and any AC coupling settle
constexpr double kBiasRms = 0.8;     // % of rated: 3 sigma = 2.4 % -> within +-3 % of power
constexpr double kCouplingRc = 5.0;  // the declared AC coupling of the ac_coupling concealment

plantsim::Params preset_params() {
  plantsim::PlantOptions po;
  return plantsim::resolve(po).params;
}

// Plant scales the truths are converted with.
struct PlantScales {
  double droop = 0.05;      // gov.r_pu: e = r * bias_pu - ..., so 1 % bias = r/100 pu of e
  double rack_per_pct = 0;  // rack position, pu, per % bias (static, from the linearisation)
  double rack0_pu = 0;      // rack at the operating point
  double dead_time_s = 0;   // effective fuel dead time
  double zeta = 0;          // the swing mode's damping ratio
};

PlantScales plant_scales() {
  static const PlantScales s = [] {
    PlantScales out;
    const plantsim::Params p = preset_params();
    out.droop = p[plantsim::P::kGovR];
    plantsim::GensetModel m(p);
    m.steady_state(&out.rack0_pu);
    const plantsim::LinearModel lm = plantsim::linearise(plantsim::PlantOptions{});
    // x' = A x + b u + b_fuel rack(t - Td), rack = c_fuel x; at rest the delay is identity.
    const Eigen::MatrixXd a_loop = lm.a + lm.b_fuel * lm.c_fuel;
    out.rack_per_pct = (lm.c_fuel * a_loop.lu().solve(-lm.b))(0);
    out.dead_time_s = lm.delay_s;
    out.zeta = lm.zeta;
    return out;
  }();
  return s;
}

// The damping ratio of the swing mode with the changes applied from the start.
double linearised_zeta(const std::vector<std::string>& faults) {
  plantsim::Params p = preset_params();
  for (const auto& f : faults) {
    const plantsim::TimedChange c = plantsim::parse_change(f);
    p.set(c.param, c.value, f);
  }
  return plantsim::linearise(p, "stornoway").zeta;
}

model::TransferFunction nominal_tf() {
  const plantsim::LinearModel lm = plantsim::linearise(plantsim::PlantOptions{});
  // The rig holds each setpoint for a sample (zero-order hold); the first-order-hold
  // simulation of the model sees that as half a sample of dead time.
  model::TransferFunction tf = lm.tf;
  tf.delay_s += 0.5 * kDt;
  return tf;
}

}  // namespace

const std::vector<PlantEffect>& plant_effects() {
  const PlantScales& s = plant_scales();
  static const std::vector<PlantEffect> effects = {
      {"none", "", 0.0, "the nominal set"},
      {"dead_time", "engine.dead_time_s", s.dead_time_s + 0.025,
       "fuel dead time 25 ms longer (injection timing)"},
      {"extra_lag", "engine.combustion_lag_s", 0.05, "combustion lag 8 -> 50 ms"},
      {"sensor_lag", "meas.transducer_lag_s", 0.04, "power transducer lag 3 -> 40 ms"},
      {"ac_coupling", "meas.ac_rc_s", 4.0, "power signal AC-coupled (RC 4 s), not declared"},
      {"deadband", "gov.deadband_pu", 1.25e-4, "governor error deadband 1.25e-4 pu"},
      {"backlash", "gov.backlash_pu", 0.004, "rack backlash 0.004 pu (actuator wear)"},
      {"rate_limit", "gov.rate_limit_pu_s", 0.3, "actuator rate limit 0.3 pu/s"},
      {"saturation", "gov.tmax_pu", s.rack0_pu + 0.01, "actuator limit 0.01 pu above the rack"},
      {"gain_change", "meas.gain", 0.93, "power transducer reads 7 % low"},
      {"load_damping", "alt.d_pu", 18.0, "alternator damping 11 -> 18 pu"},
      {"periodic_disturbance", "meas.pickup_hz", 7.3, "8 kW pick-up at 7.3 Hz"},
      {"drift", "meas.drift_kw", 30.0, "30 kW rms slow drift (load wander)"},
  };
  return effects;
}

const std::vector<std::string>& concealments() {
  static const std::vector<std::string> c = {"noise", "drift", "ac_coupling", "partial"};
  return c;
}

std::vector<std::string> concealments_for(const std::string& effect) {
  if (effect == "none") return {"noise", "ac_coupling"};
  if (effect == "ac_coupling") return {"noise", "drift"};
  // A declared coupling (RC 5 s) removes most of a 60 s drift: the effect itself.
  if (effect == "drift") return {"noise", "partial"};
  if (effect == "periodic_disturbance") return {"noise", "ac_coupling", "partial"};
  return concealments();
}

bool verdict_matches(const std::string& truth, const std::string& verdict) {
  const auto lag = [](const std::string& e) { return e == "extra_lag" || e == "sensor_lag"; };
  return truth == verdict || (lag(truth) && lag(verdict));
}

namespace {

const PlantEffect& find_effect(const std::string& word) {
  for (const auto& e : plant_effects())
    if (e.effect == word) return e;
  throw std::invalid_argument("unknown plant effect " + word +
                              " (expected none or one of plant_effects())");
}

// The effect's first diagnose parameter implied by the plant change.
double truth_of(const PlantEffect& e, const std::vector<std::string>& faults) {
  const PlantScales& s = plant_scales();
  const plantsim::Params p = preset_params();
  using plantsim::P;
  if (e.effect == "dead_time") return e.plant_value - s.dead_time_s;
  if (e.effect == "extra_lag") return e.plant_value - p[P::kEngCombustionLag];
  if (e.effect == "sensor_lag") return e.plant_value - p[P::kMeasLag];
  if (e.effect == "ac_coupling") return e.plant_value;
  // Deadband on e (half width db): e = r bias_pu + ..., so db/r pu of bias = 100 db/r %.
  if (e.effect == "deadband") return 100.0 * e.plant_value / s.droop;
  // Rack backlash of width w: half width w/2 of rack = (w/2)/rack_per_pct % of bias.
  if (e.effect == "backlash") return 0.5 * e.plant_value / s.rack_per_pct;
  if (e.effect == "rate_limit") return e.plant_value / s.rack_per_pct;
  if (e.effect == "saturation") return (e.plant_value - s.rack0_pu) / s.rack_per_pct;
  if (e.effect == "gain_change") return e.plant_value;
  if (e.effect == "load_damping") return linearised_zeta(faults);
  if (e.effect == "periodic_disturbance") return e.plant_value;
  return NAN;  // drift: the smoother's time scale is not the OU correlation time
}

}  // namespace

PlantRecord record_plant(const std::vector<std::string>& faults, std::uint64_t plant_seed,
                         std::uint64_t excitation_seed, double duration_s, double settle_s) {
  plantsim::PlantOptions po;
  po.faults = faults;
  po.seed = plant_seed;
  po.tick = std::chrono::milliseconds(10);
  auto plant = plantsim::make_plant(po);
  const auto n = static_cast<Eigen::Index>(std::llround(duration_s / kDt));
  signal::GaussianOptions go;
  go.n = n, go.dt_s = kDt, go.bandwidth_hz = 4.0, go.sigma = kBiasRms, go.clip_sigma = 3.0;
  go.seed = excitation_seed;
  PlantRecord r{signal::gaussian_excitation(go), Eigen::VectorXd(n)};
  for (int k = 0; k < static_cast<int>(std::llround(settle_s / kDt)); ++k) plant->step();
  for (Eigen::Index k = 0; k < n; ++k) {
    plant->set_bias_pct(r.u(k));
    r.y(k) = plant->measure().power_w / 1e3;
    plant->step();
  }
  return r;
}

PlantCase make_plant_case(const PlantCaseSpec& spec) {
  const PlantEffect& eff = find_effect(spec.effect);
  bool known = false;
  for (const auto& c : concealments()) known |= c == spec.concealment;
  if (!known) throw std::invalid_argument("unknown concealment " + spec.concealment);
  PlantCase pc;
  std::vector<std::string> at_start;
  if (spec.concealment == "noise") at_start.push_back("meas.noise_kw=15@t=0");
  if (spec.concealment == "drift") at_start.push_back("meas.drift_kw=20@t=0");
  if (spec.concealment == "ac_coupling")
    at_start.push_back(fmt::format("meas.ac_rc_s={}@t=0", kCouplingRc));
  if (eff.effect == "periodic_disturbance") at_start.push_back("meas.pickup_kw=8@t=0");
  const double onset_s = spec.concealment == "partial" ? kSettleS + 0.5 * spec.duration_s : 0.0;
  std::vector<std::string> effect_faults;
  if (!eff.plant_key.empty())
    effect_faults.push_back(
        fmt::format("{}={:.10g}@t={:.10g}", eff.plant_key, eff.plant_value, onset_s));
  pc.faults = at_start;
  pc.faults.insert(pc.faults.end(), effect_faults.begin(), effect_faults.end());

  PlantRecord rec =
      record_plant(pc.faults, spec.seed, spec.seed * 7919 + 17, spec.duration_s, kSettleS);
  pc.input.u = std::move(rec.u);
  pc.input.y = std::move(rec.y);
  pc.input.dt_s = kDt;
  pc.input.model = nominal_tf();
  if (spec.concealment == "ac_coupling") pc.input.output_rc_s = kCouplingRc;
  pc.truth = truth_of(eff, effect_faults);
  pc.param =
      eff.effect == "none" ? "" : parameter_specs(*effect_from_string(eff.effect), {})[0].name;
  pc.description =
      fmt::format("{} ({}), concealed by {}", eff.effect, eff.description, spec.concealment);
  return pc;
}

}  // namespace rig::diagnose::bench
