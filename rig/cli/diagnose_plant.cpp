// From diagnosed effects to plantsim parameters. The baseline transfer function is plantsim's
// linearisation: input u = setpoint bias in % of rated power P_r, output y = measured power
// in kW. In the governor (DESIGN.md 7, plantsim/plant/governor.hpp) the bias b = u/100 pu
// enters the error as e = Pref + R b - g dw - R Pe_f. Between 1/T4 and 1/T1 (where the
// excitation lives; T3 = T1 in the usual tuning) the actuator follows the bias with the gain
// R K T4 (pu of rack per pu of bias; 1 for a kW-controlled set, where r_pu k t4_s = 1 makes
// 1 % of bias 1 % of rated power). So 1 % of bias is a_r = R K T4 / 100 pu on the rack and
// its rate (0.01 / c, the static value, when T4 = 0), and R / 100 pu on the error e.
// The table (effect parameter -> plant key):
//
//   dead_time      extra_delay_s d      engine.dead_time_s = Td0 + d, Td0 the effective fuel
//                                       dead time (dead_time_s if > 0, else 30/N + 60/(n N))
//   extra_lag      time_constant_s T    engine.combustion_lag_s += T (time constants add: the
//                                       sum keeps the lag's low-frequency phase, 1st order)
//   sensor_lag     time_constant_s T    meas.transducer_lag_s += T (same approximation)
//   ac_coupling    rc_s                 meas.ac_rc_s = rc_s
//   gain_change    gain_ratio g         meas.gain *= g
//   deadband       half_width h (%)     gov.deadband_pu += R h/100 (plantsim's deadband_pu is
//                                       the half width on e: |e| <= db gives 0)
//   backlash       half_width h (%)     gov.backlash_pu += 2 h a_r (plantsim's backlash_pu is
//                                       the full play width on the rack: rack = xf -+ w/2)
//   rate_limit     rate_limit_per_s r   gov.rate_limit_pu_s = r a_r (on the actuator rate)
//   (recovery_s of the in-loop limiters is the plant loop's own restoring time: not mapped)
//   saturation     upper, lower (%)     gov.tmax_pu = rack0 + (u0 + upper) a_r,
//                                       gov.tmin_pu = rack0 + (u0 - lower) a_r, rack0 = the
//                                       steady rack (P0/P_r)/c at zero bias, c = mean injector
//                                       health, u0 the recording's mean bias; a limit outside
//                                       the recorded excursion is not identified: unchanged
//   load_damping   zeta z               alt.d_pu *= z / zeta0 (swing-mode damping ratio is
//                                       about proportional to D; zeta0 of the baseline's least
//                                       damped pole pair)
//   periodic_      freq_hz, amplitude   meas.pickup_hz, meas.pickup_kw (the fitted peak
//   disturbance                         amplitude; plantsim's pick-up is A sin(2 pi f t))
//   drift          time_constant_s      meas.drift_tau_s, meas.drift_kw = the fitted drift rms
//                                       (the smoother's time scale approximates the drift's)
//   resonance, static_nonlinearity, nonlinear_stiffness, coulomb_friction: no plant
//   parameter; the plant is left as it was (augmented_model.json carries them).
// Every value is clamped to the range plantsim lists for the key (a note says so).
#include "rig/cli/diagnose_plant.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/io/input_error.hpp"

namespace rig::cli {
namespace {

using diagnose::Effect;

double round6(double v) { return std::stod(fmt::format("{:.6g}", v)); }

double derived_value(const diagnose::HypothesisFit& h, const std::string& key, double fallback) {
  for (const auto& [k, v] : h.derived)
    if (k == key && std::isfinite(v)) return v;
  return fallback;
}

class Mapper {
 public:
  Mapper(const PlantModel& plant, PlantMapping* out) : plant_(plant), out_(out) {}

  // Sets key to value (clamped to plantsim's range); reason names the conversion.
  void set(const std::string& key, double value, const std::string& effect,
           const std::string& reason) {
    const double old = current(key);
    double v = value;
    const auto r = plant_.ranges.find(key);
    if (r != plant_.ranges.end() && (v < r->second.first || v > r->second.second)) {
      v = std::clamp(v, r->second.first, r->second.second);
      out_->notes.push_back(fmt::format("{}: {:.6g} clamped to plantsim's range {:.6g} .. {:.6g}",
                                        key, value, r->second.first, r->second.second));
    }
    v = round6(v);
    for (auto& c : out_->changes)
      if (c.key == key) {
        c.new_value = v, c.effect += "+" + effect, c.reason += "; " + reason;
        return;
      }
    out_->changes.push_back({key, old, v, effect, reason});
  }
  // The value as changed so far, else the plant's.
  double current(const std::string& key) const {
    for (const auto& c : out_->changes)
      if (c.key == key) return c.new_value;
    return plant_.param(key);
  }
  void note(const std::string& text) { out_->notes.push_back(text); }

 private:
  const PlantModel& plant_;
  PlantMapping* out_;
};

double effective_dead_time_s(const PlantModel& p) {
  const double td = p.param("engine.dead_time_s");
  if (td > 0.0) return td;
  const double n = p.param("engine.rpm");
  return 30.0 / n + 60.0 / (p.param("engine.cylinders") * n);
}

// c = mean injector health (cylinders 1..injectors_out cut): torque = c x rack.
double cylinder_factor(const PlantModel& p) {
  const int n = static_cast<int>(std::lround(p.param("engine.cylinders")));
  const int out = static_cast<int>(std::lround(p.param("engine.injectors_out")));
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    sum += k < out ? 0.0 : p.param(fmt::format("engine.injector_{}", k + 1));
  return std::max(sum / n, 1e-9);
}

// The steady rack position: at rest torque = electrical power (no losses modelled).
double steady_rack_pu(const PlantModel& p) {
  return p.param("op.power_kw") / p.param("op.rated_kw") / cylinder_factor(p);
}

// Rack (pu) per % of bias at the excitation's frequencies: R K T4 / 100 (see the top).
double rack_pu_per_pct(const PlantModel& p) {
  const double t4 = p.param("gov.t4_s");
  if (t4 > 0.0) return p.param("gov.r_pu") * p.param("gov.k") * t4 / 100.0;
  return 0.01 / cylinder_factor(p);  // static: 1 % of rated power needs 0.01/c of rack
}

// Limits about the recording's mean input u0 (the operating point diagnose removes): the
// rack there is rack0 + u0 a_r. A limit beyond the recorded excursion never acted, so the
// fit did not identify it: that side is left as it was.
void map_saturation(const std::vector<double>& p, const PlantModel& plant, const Eigen::VectorXd& u,
                    Mapper& m) {
  const double u0 = u.size() ? u.mean() : 0.0;
  const double up = u.size() ? u.maxCoeff() - u0 : INFINITY;
  const double down = u.size() ? u0 - u.minCoeff() : INFINITY;
  const double a_r = rack_pu_per_pct(plant);
  const double rack = steady_rack_pu(plant) + u0 * a_r;
  const std::pair<const char*, double> sides[] = {{"upper_limit", p[0]},
                                                  {"lower_limit_magnitude", p[1]}};
  for (const auto& [word, lim] : sides) {
    const bool upper = std::string(word) == "upper_limit";
    const char* key = upper ? "gov.tmax_pu" : "gov.tmin_pu";
    if (lim >= (upper ? up : down)) {
      m.note(
          fmt::format("saturation: {} {:.4g} % lies beyond the recorded input ({:.4g} %); "
                      "{} left unchanged",
                      word, lim, upper ? up : down, key));
      continue;
    }
    m.set(key, rack + (upper ? lim : -lim) * a_r, "saturation",
          fmt::format("rack at the mean bias {:.4g} pu {} {} {:.4g} % x {:.4g} pu/%", rack,
                      upper ? "+" : "-", word, lim, a_r));
  }
}

// The input nonlinearities act at the governor: on e (deadband) or the rack (the rest).
void map_governor_effect(const diagnose::AppliedEffect& e, const PlantModel& plant,
                         const Eigen::VectorXd& u, Mapper& m) {
  const std::string name = diagnose::to_string(e.effect);
  const auto& p = e.params;
  const double a_r = rack_pu_per_pct(plant);
  switch (e.effect) {
    case Effect::kDeadband: {
      const double r = plant.param("gov.r_pu");
      m.set("gov.deadband_pu", m.current("gov.deadband_pu") + r * p[0] / 100.0, name,
            fmt::format("half_width {:.4g} % of bias x R {:.4g} / 100 on the error e", p[0], r));
      break;
    }
    case Effect::kBacklash:
      m.set("gov.backlash_pu", m.current("gov.backlash_pu") + 2.0 * p[0] * a_r, name,
            fmt::format("play width 2 x half_width {:.4g} % x {:.4g} pu/% on the rack", p[0], a_r));
      break;
    case Effect::kRateLimit:
      m.set("gov.rate_limit_pu_s", p[0] * a_r, name,
            fmt::format("rate_limit_per_s {:.4g} %/s x {:.4g} pu/% on the actuator", p[0], a_r));
      break;
    case Effect::kSaturation:
      map_saturation(p, plant, u, m);
      break;
    default:
      break;
  }
}

void map_effect(const diagnose::AppliedEffect& e, const diagnose::HypothesisFit& h,
                const PlantModel& plant, const model::TransferFunction& baseline,
                const Eigen::VectorXd& u, Mapper& m) {
  const std::string name = diagnose::to_string(e.effect);
  const auto& p = e.params;
  switch (e.effect) {
    case Effect::kDeadTime: {
      const double td0 = effective_dead_time_s(plant);
      m.set("engine.dead_time_s", std::max(td0 + p[0], 1e-4), name,
            fmt::format("fuel dead time {:.4g} s + extra_delay_s {:.4g} s", td0, p[0]));
      break;
    }
    case Effect::kExtraLag:
      m.set("engine.combustion_lag_s", m.current("engine.combustion_lag_s") + p[0], name,
            fmt::format("combustion lag + time_constant_s {:.4g} s (lags add)", p[0]));
      break;
    case Effect::kSensorLag:
      m.set("meas.transducer_lag_s", m.current("meas.transducer_lag_s") + p[0], name,
            fmt::format("transducer lag + time_constant_s {:.4g} s (lags add)", p[0]));
      break;
    case Effect::kAcCoupling:
      m.set("meas.ac_rc_s", p[0], name, fmt::format("rc_s {:.4g} s", p[0]));
      break;
    case Effect::kGainChange:
      m.set("meas.gain", m.current("meas.gain") * p[0], name,
            fmt::format("transducer gain x gain_ratio {:.4g}", p[0]));
      break;
    case Effect::kDeadband:
    case Effect::kBacklash:
    case Effect::kRateLimit:
    case Effect::kSaturation:
      map_governor_effect(e, plant, u, m);
      break;
    case Effect::kLoadDamping: {
      const auto mode = diagnose::dominant_mode(baseline);
      if (!mode || !(mode->second > 0.0)) {
        m.note("load_damping: the baseline has no damped pole pair; alt.d_pu left unchanged");
        break;
      }
      m.set("alt.d_pu", m.current("alt.d_pu") * p[0] / mode->second, name,
            fmt::format("D x zeta {:.4g} / baseline zeta {:.4g} ({:.3g} Hz mode)", p[0],
                        mode->second, mode->first));
      break;
    }
    case Effect::kPeriodicDisturbance: {
      const double a = derived_value(h, "amplitude", m.current("meas.pickup_kw"));
      m.set("meas.pickup_hz", p[0], name, fmt::format("freq_hz {:.6g}", p[0]));
      m.set("meas.pickup_kw", a, name, fmt::format("fitted amplitude {:.4g} kW", a));
      break;
    }
    case Effect::kDrift: {
      m.set("meas.drift_tau_s", p[0], name, fmt::format("time_constant_s {:.4g}", p[0]));
      const double rms = derived_value(h, "drift_rms", m.current("meas.drift_kw"));
      m.set("meas.drift_kw", rms, name, fmt::format("fitted drift rms {:.4g} kW", rms));
      break;
    }
    case Effect::kResonance:
    case Effect::kStaticNonlinearity:
    case Effect::kNonlinearStiffness:
    case Effect::kCoulombFriction:
      m.note(fmt::format("{}: no plant parameter expresses it; see augmented_model.json", name));
      break;
  }
}

}  // namespace

double PlantModel::param(const std::string& key) const {
  const auto it = params.find(key);
  if (it == params.end())
    throw io::InputError(toml.string(), 0, key, "plantsim --list-params did not list this key");
  return it->second;
}

PlantMapping plant_changes(const diagnose::HypothesisFit& hypothesis, const PlantModel& plant,
                           const model::TransferFunction& baseline, const Eigen::VectorXd& u) {
  PlantMapping out;
  Mapper m(plant, &out);
  for (const auto& e : hypothesis.effects) map_effect(e, hypothesis, plant, baseline, u, m);
  return out;
}

std::string augmented_plant_toml(const std::filesystem::path& input, const PlantMapping& mapping,
                                 const std::vector<std::string>& summary) {
  toml::table root;
  try {
    root = toml::parse_file(input.string());
  } catch (const toml::parse_error& e) {
    throw io::InputError(input.string(), static_cast<long>(e.source().begin.line), "",
                         std::string("malformed TOML: ") + std::string(e.description()));
  }
  std::ostringstream text;
  text << "# Plant written by `rig diagnose` from " << input.filename().string() << ".\n";
  for (const auto& s : summary) text << "# " << s << "\n";
  if (mapping.changes.empty()) text << "# No plant parameter changed.\n";
  for (const auto& c : mapping.changes) {
    const auto dot = c.key.find('.');
    const std::string block = c.key.substr(0, dot), name = c.key.substr(dot + 1);
    if (!root.contains(block)) root.insert(block, toml::table{});
    root[block].as_table()->insert_or_assign(name, c.new_value);
    text << fmt::format("# Changed {}: {:.6g} -> {:.6g} ({}: {}).\n", c.key, c.old_value,
                        c.new_value, c.effect, c.reason);
  }
  for (const auto& n : mapping.notes) text << "# Note: " << n << "\n";
  text << "# The original file's comments are not kept; `plantsim --list-params` describes\n"
          "# every key.\n\n";
  // Shortest round-trip floats (0.05, not 0.050000000000000003).
  text << toml::toml_formatter{root, toml::toml_formatter::default_flags |
                                         toml::format_flags::relaxed_float_precision}
       << "\n";
  return text.str();
}

}  // namespace rig::cli
