// Every plant parameter in one table (DESIGN.md section 7): name, unit, default, valid range.
// Names are "<block>.<name>"; the plant TOML uses one table per block ([gov] r_pu = 0.05) and
// --fault uses the dotted name (or the bare name when it is unique): "engine.injector_3=0@t=20",
// optionally ramped: "engine.injectors_out=2@t=600,ramp=1800".
// Defaults are a generic 4.6 MW, 600 rpm set; presets override some of them (presets.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace plantsim {

// X(id, "block.name", "unit", default, min, max, "meaning")
#define PLANTSIM_INJECTOR(n) \
  X(kInjector##n, "engine.injector_" #n, "1", 1.0, 0.0, 1.0, "cylinder " #n " injector health")
// clang-format off
#define PLANTSIM_PARAMETERS \
  X(kRatedKw, "op.rated_kw", "kW", 4600.0, 10.0, 1e6, "rated electrical power (per-unit base)") \
  X(kPowerKw, "op.power_kw", "kW", 3500.0, 0.0, 1e6, "operating point; a later change moves the governor's load reference") \
  X(kFreqHz, "op.freq_hz", "Hz", 50.0, 40.0, 70.0, "nominal bus frequency") \
  X(kRatedVoltageV, "op.rated_voltage_v", "V", 11000.0, 100.0, 1e6, "rated terminal voltage") \
  X(kGridConnected, "op.grid_connected", "bool", 1.0, 0.0, 1.0, "1 grid, 0 islanded load") \
  X(kGovR, "gov.r_pu", "pu", 0.05, 0.001, 1.0, "power-feedback droop R") \
  X(kGovTe, "gov.te_s", "s", 5.0, 0.001, 100.0, "power feedback filter TE") \
  X(kGovSpeedGain, "gov.speed_gain", "1", 1.0, 0.0, 10.0, "weight of dw in e (1 = DEGOV1)") \
  X(kGovT1, "gov.t1_s", "s", 0.2, 0.001, 10.0, "control box T1") \
  X(kGovT2, "gov.t2_s", "s", 0.003, 0.0001, 10.0, "control box T2") \
  X(kGovT3, "gov.t3_s", "s", 0.2, 0.0, 10.0, "control box lead T3") \
  X(kGovK, "gov.k", "1/s", 4.0, 0.001, 1000.0, "actuator gain K") \
  X(kGovT4, "gov.t4_s", "s", 5.0, 0.0, 100.0, "actuator lead T4") \
  X(kGovT5, "gov.t5_s", "s", 0.004, 0.0001, 10.0, "actuator lag T5") \
  X(kGovT6, "gov.t6_s", "s", 0.002, 0.0001, 10.0, "actuator lag T6") \
  X(kGovTmin, "gov.tmin_pu", "pu", 0.0, -1.0, 1.0, "actuator lower limit TMIN") \
  X(kGovTmax, "gov.tmax_pu", "pu", 1.1, 0.1, 2.0, "actuator upper limit TMAX") \
  X(kGovRate, "gov.rate_limit_pu_s", "pu/s", 0.0, 0.0, 100.0, "actuator rate limit (0 off)") \
  X(kGovDeadband, "gov.deadband_pu", "pu", 0.0, 0.0, 0.5, "deadband on e (0 off)") \
  X(kGovBacklash, "gov.backlash_pu", "pu", 0.0, 0.0, 0.5, "rack backlash width (0 off)") \
  X(kGovExtBiasLimit, "gov.ext_bias_limit_pct", "%", 5.0, 0.0, 32.0, "clamp on the external bias (applied, echoed)") \
  X(kEngRpm, "engine.rpm", "rpm", 600.0, 60.0, 3000.0, "rated speed N") \
  X(kEngCylinders, "engine.cylinders", "1", 12.0, 1.0, 20.0, "cylinders (four-stroke)") \
  X(kEngDeadTime, "engine.dead_time_s", "s", 0.0, 0.0, 1.0, "fuel dead time; 0 = 30/N + 60/(n_cyl N)") \
  X(kEngCombustionLag, "engine.combustion_lag_s", "s", 0.008, 0.0001, 1.0, "combustion lag") \
  X(kEngBoostLag, "engine.boost_lag_s", "s", 2.0, 0.05, 60.0, "turbocharger boost lag") \
  X(kEngMapMin, "engine.map_fuel_min_pu", "pu", 0.4, 0.0, 2.0, "fuel limit at zero boost") \
  X(kEngMapGain, "engine.map_fuel_gain", "pu/pu", 0.9, 0.0, 10.0, "fuel limit per pu of boost") \
  X(kEngInjectorsOut, "engine.injectors_out", "1", 0.0, 0.0, 20.0, "cylinders 1..n without fuel (fractional n: the next loses that fraction)") \
  X(kEngPulseWidth, "engine.pulse_width_deg", "deg", 30.0, 1.0, 720.0, "torque pulse width (crank)") \
  X(kEngRipple, "engine.ripple", "bool", 1.0, 0.0, 1.0, "firing ripple in the output") \
  PLANTSIM_INJECTOR(1) \
  PLANTSIM_INJECTOR(2) \
  PLANTSIM_INJECTOR(3) \
  PLANTSIM_INJECTOR(4) \
  PLANTSIM_INJECTOR(5) \
  PLANTSIM_INJECTOR(6) \
  PLANTSIM_INJECTOR(7) \
  PLANTSIM_INJECTOR(8) \
  PLANTSIM_INJECTOR(9) \
  PLANTSIM_INJECTOR(10) \
  PLANTSIM_INJECTOR(11) \
  PLANTSIM_INJECTOR(12) \
  PLANTSIM_INJECTOR(13) \
  PLANTSIM_INJECTOR(14) \
  PLANTSIM_INJECTOR(15) \
  PLANTSIM_INJECTOR(16) \
  PLANTSIM_INJECTOR(17) \
  PLANTSIM_INJECTOR(18) \
  PLANTSIM_INJECTOR(19) \
  PLANTSIM_INJECTOR(20) \
  X( kAltH, "alt.h_s", "s", 2.0, 0.05, 30.0, "inertia constant H") \
  X(kAltD, "alt.d_pu", "pu", 11.0, 0.0, 200.0, "damping D") \
  X(kAltE, "alt.e_pu", "pu", 1.1, 0.3, 3.0, "initial internal voltage E'") \
  X( kAltXdp, "alt.xdp_pu", "pu", 0.25, 0.01, 3.0, "transient reactance xd'") \
  X(kAltXd, "alt.xd_pu", "pu", 1.8, 0.05, 5.0, "synchronous reactance xd") \
  X( kAltTdo, "alt.tdo_s", "s", 5.0, 0.1, 30.0, "open-circuit time constant Td0'") \
  X(kAltFluxDecay, "alt.flux_decay", "bool", 0.0, 0.0, 1.0, "1 = E' follows flux decay") \
  X(kAltAvr, "alt.avr", "bool", 0.0, 0.0, 1.0, "1 = simple AVR on Efd (needs flux_decay)") \
  X(kAltAvrKa, "alt.avr_ka", "pu/pu", 50.0, 0.1, 1000.0, "AVR gain Ka") \
  X(kAltAvrTa, "alt.avr_ta_s", "s", 0.05, 0.001, 10.0, "AVR time constant Ta") \
  X(kGridV, "grid.v_pu", "pu", 1.0, 0.5, 1.5, "grid voltage V") \
  X( kGridXe, "grid.xe_pu", "pu", 0.25, 0.0, 3.0, "transformer + line reactance") \
  X(kLoadD, "load.d_pu", "pu/pu", 1.0, 0.0, 20.0, "island load frequency dependence D_L") \
  X(kLoadPu, "load.step_pu", "pu", 0.0, -1.0, 1.0, "island load change from the operating point") \
  X(kMeasLag, "meas.transducer_lag_s", "s", 0.003, 0.0001, 10.0, "power transducer lag") \
  X(kMeasGain, "meas.gain", "1", 1.0, 0.0, 10.0, "transducer gain (1 = no error)") \
  X(kMeasOffset, "meas.offset_kw", "kW", 0.0, -1e5, 1e5, "transducer offset added to the measured power") \
  X(kMeasNoise, "meas.noise_kw", "kW", 0.0, 0.0, 1e5, "white noise rms") \
  X(kMeasPickup, "meas.pickup_kw", "kW", 0.0, 0.0, 1e5, "mains pick-up amplitude") \
  X(kMeasPickupHz, "meas.pickup_hz", "Hz", 50.0, 1.0, 1000.0, "mains pick-up frequency") \
  X(kMeasDrift, "meas.drift_kw", "kW", 0.0, 0.0, 1e5, "slow drift rms (Ornstein-Uhlenbeck)") \
  X(kMeasDriftTau, "meas.drift_tau_s", "s", 60.0, 0.1, 1e5, "drift correlation time") \
  X(kMeasQuant, "meas.quant_kw", "kW", 0.0, 0.0, 1e4, "quantisation step (0 off)") \
  X(kMeasAcRc, "meas.ac_rc_s", "s", 0.0, 0.0, 1e4, "AC-coupling RC (0 = DC coupled)") \
  X(kSolverRtol, "solver.rtol", "1", 1e-8, 1e-12, 1e-2, "CVODE relative tolerance") \
  X(kSolverAtol, "solver.atol", "pu", 2e-8, 1e-14, 1e-2, "CVODE absolute tolerance")
// clang-format on

enum class P : int {
#define X(id, name, unit, def, lo, hi, doc) id,
  PLANTSIM_PARAMETERS
#undef X
      kCount
};

inline constexpr std::size_t kParamCount = static_cast<std::size_t>(P::kCount);
inline constexpr int kMaxCylinders = 20;

struct ParamSpec {
  std::string_view name;
  std::string_view unit;
  double default_value;
  double min_value;
  double max_value;
  std::string_view doc;
};

const std::array<ParamSpec, kParamCount>& param_specs();
const ParamSpec& spec(P id);
// False for parameters that take abrupt changes only: switches (unit "bool"), the cylinder
// count, the initial internal voltage alt.e_pu (read at start only) and solver settings.
bool rampable(P id);
// Exact dotted name, or a bare name that matches exactly one "<block>.<name>".
std::optional<P> find_param(std::string_view name);

class Params {
 public:
  Params();  // all defaults
  double operator[](P id) const { return v_[static_cast<std::size_t>(id)]; }
  // Throws ConfigError naming `where` (file/key or fault string) when out of range.
  void set(P id, double value, const std::string& where);
  // Without the range check: for values between two checked ones (a running ramp).
  void set_unchecked(P id, double value) { v_[static_cast<std::size_t>(id)] = value; }
  // Health of a cylinder (0-based index k) with injectors_out folded in: cylinder k loses the
  // fraction clamp(injectors_out - k, 0, 1) of its fuel, so injectors_out = 1.5 cuts cylinder
  // 1 and half of cylinder 2.
  double injector(int cylinder_index) const;
  bool operator==(const Params&) const = default;

 private:
  std::array<double, kParamCount> v_{};
};

// A parameter moving linearly from `from` at t0_s to `to` at t1_s (t1_s > t0_s). At t1_s
// it takes `end`, which differs from `to` only where a value stands for another: ramped
// to engine.dead_time_s = 0 (the formula), a ramp runs to the formula's value and ends on 0.
struct ParamRamp {
  P param;
  double t0_s = 0.0;
  double t1_s = 0.0;
  double from = 0.0;
  double to = 0.0;
  double end = 0.0;
  double at(double t_s) const {
    if (t_s <= t0_s) return from;
    if (t_s >= t1_s) return to;
    return from + (to - from) * (t_s - t0_s) / (t1_s - t0_s);
  }
};

}  // namespace plantsim
