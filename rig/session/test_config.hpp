// The commissioning test file (docs/test-file.md): one TOML document with every setting of a
// test, each with a documented default. Parsing is strict: an unknown key, a wrong type or an
// unsafe value is one ConfigError naming the file, the key and what was expected, raised
// before anything is written to the governor (DESIGN.md section 4: exit code 2).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "rig/session/safety_defaults.hpp"

namespace rig::session {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct LinkSettings {
  std::string uri;  // e.g. modbus+tcp://127.0.0.1:1502?unit=1
  double sample_rate_hz = safety_defaults::kSampleRateHz;  // one write/read exchange per sample
  int lockstep_ticks = 0;  // > 0: simulated plant advanced this many ticks per sample
  double timeout_s = 0.5;  // response timeout per request
};

struct PlantSettings {
  double rated_power_kw = 4600.0;  // bias is in % of this
  std::string preset;              // emulated plant preset (recorded only)
};

// Defaults from rig/session/safety_defaults.hpp, shared with SupervisorConfig.
struct SafetySettings {
  double band_pct = safety_defaults::kBandPct;  // |P - P0| <= band_pct % of P0
  bool allow_band_above_3pct = false;           // required for band_pct > 3 (in the report)
  double plan_fraction = safety_defaults::kPlanFraction;        // planned peak, share of the band
  double backoff_fraction = safety_defaults::kBackoffFraction;  // scale 0 at this share
  double clamp_pct = safety_defaults::kClampPct;          // |bias| never exceeds this (% of rated)
  double ramp_pct_per_s = safety_defaults::kRampPctPerS;  // bias ramp at start-up and ramp-down
  // Bias acknowledgement (DESIGN.md section 8, layer 0).
  double activation_timeout_s = safety_defaults::kActivationTimeoutS;  // "bias active" within
  double echo_tolerance_pct = safety_defaults::kEchoTolerancePct;      // plus 10 % of |command|
  double echo_delay_s = safety_defaults::kEchoDelayS;     // the echo may lag the command this long
  double echo_max_bad_s = safety_defaults::kEchoMaxBadS;  // a longer mismatch trips
};

struct SteadyStateSettings {
  double duration_s = 10.0;    // length of the steady-state record
  double max_noise_pct = 0.5;  // std(P - trend) limit, % of P0
  double max_drift_pct = 0.5;  // |trend slope| * duration limit, % of P0
  double min_power_kw = 1.0;   // the set must be loaded (P0 above this)
};

struct PilotSettings {
  double amplitude_pct = 0.3;  // excitation std during the pilot, % of rated power
  double duration_s = 20.0;
};

// Shaped: a multisine designed from the pilot's model (shaped_excitation.hpp); its pilot is
// Gaussian.
enum class ExcitationType { kGaussian, kPrbs, kShaped };

struct ExcitationSettings {
  ExcitationType type = ExcitationType::kShaped;  // docs/excitation.md
  // Covers the compare band (to 5 Hz) with room: at 4 Hz (twice the mode, the thesis's
  // rule) the response above 4 Hz is too poorly known for the stopping rule (docs/decisions.md).
  double bandwidth_hz = 6.0;
  std::uint64_t seed = 1;
  double ac_coupling_rc_s = 1.6;  // matched high-pass RC on excitation and response; 0 = off
  int prbs_register_length = 10;
  int prbs_clock_divider = 2;
};

// The [mmfm] table: the online MMFM of a test (the estimator's modulating-function settings
// are rig::ident::MmfmSettings).
struct MmfmTestSettings {
  int order_n = 2;                       // denominator order
  int order_m = 0;                       // numerator order
  std::optional<double> delay_s;         // nullopt: estimated
  int lags = 256;                        // correlation window (samples)
  bool auto_order = true;                // choose among kAutoOrders (else order_n/order_m)
  int block_size = 1024;                 // samples per correlator block / live estimate
  int skip = 1;                          // Fell's skip
  std::string correlator = "direct";     // direct | fft | relay | polarity
  std::string averaging = "cumulative";  // cumulative | exponential (weight averaging_w)
  int averaging_w = 8;                   // exponential averaging weight (blocks)
  // Stop when the model's 95 % band over the compare band is within +-target_db and
  // +-target_deg (the estimator's asymptotic covariance, rig/ident/frf_uncertainty.hpp).
  double target_db = 0.5;
  double target_deg = 3.0;
  double min_duration_s = 30.0;   // never stop before this much excitation
  double max_duration_s = 600.0;  // stop regardless
  // The applied excitation (std of u, after the supervisor) must reach this share of the
  // planned std, or the data do not support a model (exit 1, no model.json).
  double min_applied_fraction = 0.5;
};

struct SweepSettings {
  bool enabled = true;
  double from_hz = 0.3;
  double to_hz = 6.0;
  int points = 16;                     // log-spaced
  double settle_cycles = 3.0;          // at least this many cycles settle after each change
  double integrate_cycles = 8.0;       // at least this many whole cycles are integrated
  double settle_time_constants = 8.0;  // and settle this many slowest time constants
  double min_integrate_s = 10.0;       // and integrate at least this long (noise, drift)
};

struct CompareSettings {
  double from_hz = 0.5;
  double to_hz = 5.0;
  double mag_tol_db = 1.0;
  double phase_tol_deg = 5.0;
  double min_coherence = 0.8;  // sweep points below this are excluded from the check
};

struct OutputSettings {
  double flush_interval_s = 0.5;  // recording flushed at least this often
  double live_interval_s = 1.0;   // live-view refresh (plain lines when not a TTY)
};

struct TestConfig {
  std::string source;  // file name the settings came from ("<defaults>" otherwise)
  LinkSettings link;
  PlantSettings plant;
  SafetySettings safety;
  SteadyStateSettings steady_state;
  PilotSettings pilot;
  ExcitationSettings excitation;
  MmfmTestSettings mmfm;
  SweepSettings sweep;
  CompareSettings compare;
  OutputSettings output;
};

// Parses and validates a test file. Throws ConfigError (one line) on any problem.
TestConfig load_test_file(const std::filesystem::path& path);
// Same, from text; `source` names the document in error messages.
TestConfig parse_test_toml(const std::string& text, const std::string& source);
// Checks cross-field rules (band override, Nyquist, ranges). Throws ConfigError.
void validate(const TestConfig& config);

const char* to_string(ExcitationType type);

}  // namespace rig::session
