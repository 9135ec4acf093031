#include "rig/monitor/signatures.hpp"

#include <algorithm>
#include <cmath>

#include "rig/monitor/amplitude_test.hpp"

namespace rig::monitor {
namespace {

double z_of(const Evidence& e, const std::string& name) {
  const auto it = e.z.find(name);
  return it == e.z.end() ? 0.0 : it->second;
}
// Evidence strength: 0 below significance, then growing slowly (a huge z is not more causes).
double strength(double z) { return z < kSignificantZ ? 0.0 : 1.0 + std::log(z / kSignificantZ); }
bool shape_is(const Evidence& e, ShapeKind k) { return e.shape && e.shape->kind == k; }
// The measured level moved without the plant's dynamics: a step or a slow drift.
bool sensor_move(const Evidence& e) {
  return shape_is(e, ShapeKind::kSensorStep) || shape_is(e, ShapeKind::kSlowDrift);
}
// Largest |z| among the tracked parameters other than `except`.
double others_max(const Evidence& e, const std::string& except) {
  double m = 0.0;
  for (const auto& [name, z] : e.z) {
    if (name != except) m = std::max(m, std::abs(z));
  }
  return m;
}

double injector_score(const Evidence& e) {
  if (sensor_move(e)) return 0.0;
  const double line = strength(e.z_line);
  const double gain_down = strength(-z_of(e, "gain"));
  const double dip = shape_is(e, ShapeKind::kPowerLossRecovered) ? 1.5 : 0.0;
  if (line == 0.0 && dip == 0.0) return 0.0;  // the gain alone could be the transducer
  return 3.0 * line + gain_down + dip;
}

// Likelihood share of the sensor test's gain-error hypothesis (0.5 when it did not run).
double p_gain_error(const Evidence& e) {
  if (!std::isfinite(e.sensor_z_gain) || !std::isfinite(e.sensor_z_offset)) return 0.5;
  const double a = std::exp(-0.5 * e.sensor_z_gain * e.sensor_z_gain);
  const double b = std::exp(-0.5 * e.sensor_z_offset * e.sensor_z_offset);
  return a + b > 0.0 ? a / (a + b) : 0.5;
}

// With the sensor test (the level moved), its verdict; otherwise the gain alone.
constexpr double kSensorScore = 3.0;

double transducer_gain_score(const Evidence& e) {
  if (sensor_move(e) && std::isfinite(e.sensor_z_gain)) return kSensorScore * p_gain_error(e);
  const double zg = z_of(e, "gain");
  if (strength(std::abs(zg)) == 0.0 || e.z_line >= kSignificantZ) return 0.0;
  if (shape_is(e, ShapeKind::kPowerLossRecovered)) return 0.0;
  double s = strength(std::abs(zg));
  if (e.isolated == "gain") s += 0.5;
  if (sensor_move(e)) {
    // The level's move must agree in sign with the gain's move.
    s += (e.level_ratio > 0.0) == (zg > 0.0) ? 1.5 : -1.0;
  }
  // A gain loss with added lag is the actuator's signature, not the transducer's.
  if (zg < 0.0 && z_of(e, "delay") >= kSignificantZ) s -= 1.0;
  return std::max(0.0, s);
}

double transducer_offset_score(const Evidence& e) {
  if (!sensor_move(e)) return 0.0;
  if (std::isfinite(e.sensor_z_gain)) return kSensorScore * (1.0 - p_gain_error(e));
  const double moved = std::max(std::abs(z_of(e, "gain")), others_max(e, "gain"));
  return moved < kSignificantZ ? 2.5 : 0.5;
}

double damping_score(const Evidence& e) {
  const double z = std::abs(z_of(e, "damping"));
  if (strength(z) == 0.0) return 0.0;
  return strength(z) + (e.isolated == "damping" ? 1.0 : 0.0) +
         (z >= others_max(e, "damping") ? 0.5 : 0.0);
}

// A longer dead time is a pure phase lag: the delay dominates, and the fit stays linear.
double delay_score(const Evidence& e) {
  const double z = z_of(e, "delay");
  if (strength(z) == 0.0) return 0.0;
  // The amplitude test decides between a dead time and play when it ran.
  if (std::isfinite(e.amplitude_z)) {
    return e.amplitude_z < AmplitudeTest::kPlayZ ? 2.0 + strength(z) : 0.0;
  }
  return strength(z) + (e.isolated == "delay" ? 1.0 : 0.0) +
         (z >= others_max(e, "delay") ? 1.0 : 0.0);
}

// A line near significance also raises the residual: no nonlinearity is read from it then.
constexpr double kLineQuietZ = 2.0;

double backlash_score(const Evidence& e) {
  if (e.z_line >= kLineQuietZ || e.shape) return 0.0;
  if (std::isfinite(e.amplitude_z) && e.amplitude_z >= AmplitudeTest::kPlayZ) {
    return 3.0 + strength(-z_of(e, "gain"));
  }
  if (std::isfinite(e.amplitude_z)) return 0.0;
  // Play in the rack: small-signal gain lost (the describing function of backlash), a phase
  // lag, and a response no linear model explains (the residual grows).
  const double loss = strength(-z_of(e, "gain"));
  const double lag = strength(z_of(e, "delay"));
  const double nonlinear = strength(e.z_residual);
  const bool gain_leads = -z_of(e, "gain") >= others_max(e, "gain");
  if (loss == 0.0 || (nonlinear == 0.0 && !gain_leads)) return 0.0;
  return loss + lag + nonlinear;
}

double frequency_score(const Evidence& e) {
  const double z = std::abs(z_of(e, "frequency"));
  if (strength(z) == 0.0) return 0.0;
  return strength(z) + (e.isolated == "frequency" ? 1.0 : 0.0) +
         (z >= others_max(e, "frequency") ? 0.5 : 0.0) - 0.5;
}

}  // namespace

const std::vector<Signature>& signature_table() {
  static const std::vector<Signature> table = {
      {"injector/cylinder loss", "multiplicative",
       "cylinder exhaust temperatures, injector and fuel pump of each cylinder, compression",
       injector_score},
      {"power transducer gain error", "multiplicative",
       "the power transducer's CT/VT ratios and calibration against a reference meter",
       transducer_gain_score},
      {"power transducer offset", "additive",
       "the power transducer's zero (no-load reading) and its wiring", transducer_offset_score},
      {"alternator damping change", "multiplicative",
       "damper windings, AVR/PSS settings and the grid connection (a changed line or transformer)",
       damping_score},
      {"fuel dead time or combustion lag change", "multiplicative",
       "injection timing, fuel quality and the governor actuator's response time", delay_score},
      {"actuator wear (backlash)", "multiplicative",
       "the fuel rack linkage and actuator for play; rack position against command",
       backlash_score},
      {"swing mode frequency change", "multiplicative",
       "the grid connection's strength (network switching) and the coupling", frequency_score},
  };
  return table;
}

Diagnosis diagnose(const Evidence& e) {
  Diagnosis d;
  double total = 0.0, best = 0.0;
  for (const Signature& s : signature_table()) {
    const double v = s.score(e);
    d.scores.emplace_back(s.cause, v);
    total += v;
    if (v > best) {
      best = v;
      d.cause = s.cause;
      d.fault_class = s.fault_class;
      d.check = s.check;
    }
  }
  d.confidence = total > 0.0 ? best / total : 0.0;
  return d;
}

}  // namespace rig::monitor
