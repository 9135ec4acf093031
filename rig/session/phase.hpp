// The commissioning test as a list of small phase objects driven by one loop (DESIGN.md
// sections 2 and 8). Each phase keeps its own state and writes its own result into
// SessionData; what the phases share is the RunContext: the link, the tick loop, the live view,
// the settings and the few facts measured on the way (P0, the dominant mode, whether the
// governor acknowledged the bias). The supervisor stays pure (supervisor.hpp).
//
//   steady_state -> activate -> pilot -> excite -> sweep        (rig sweep: no excite)
//   then, whatever happened: deactivate (ramp-down from what the governor applies, enable
//   cleared, reconnecting when the link dropped) -> compare (nothing written meanwhile).
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <future>
#include <optional>
#include <string>
#include <vector>

#include "drivers/governor_link.hpp"
#include "rig/fra/frf.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/session.hpp"
#include "rig/session/shaped_excitation.hpp"
#include "rig/session/supervisor.hpp"
#include "rig/session/thread_priority.hpp"
#include "rig/session/tick_loop.hpp"

namespace rig::session {

// The supervisor settings a test file states (band, clamp, ramp, back-off, bias echo in ticks
// at its sample rate); the rest keeps SupervisorConfig's defaults. RunContext adds what the
// run measures (P0, noise, mode, acknowledgement). A test file without [safety] gives
// SupervisorConfig{} (both take their defaults from safety_defaults.hpp).
SupervisorConfig supervisor_config_from(const TestConfig& config);

class RunContext {
 public:
  RunContext(SessionData& data, drivers::GovernorLink& link, io::RecordingWriter& recorder,
             LiveView& view, const SessionOptions& options);

  SessionData& data;
  const TestConfig& config;
  drivers::GovernorLink& link;
  LiveView& view;
  TickLoop loop;

  // Facts measured on the way.
  double p0_kw = 0.0;
  PlausibilityCheck plausible;           // readings the steady state saw non-zero
  bool activated = false;                // enable was written (deactivate must clear it)
  bool acknowledged = false;             // the governor reported the bias active (layer 0 on)
  double resonance_hz = 2.0;             // dominant mode, from the MMFM model once known
  std::vector<double> pilot_u, pilot_y;  // the pilot record (prior for a sweep-only test)
  std::optional<ShapedDesign> shaped;    // the shaped excitation designed after the pilot

  double dt_s() const { return loop.dt_s(); }
  bool lockstep() const { return config.link.lockstep_ticks > 0; }
  double noise_kw() const;  // power noise std of the steady-state check
  double band_kw() const { return config.safety.band_pct / 100.0 * p0_kw; }
  // The test stops: exit code and one-line outcome, recorded as an event.
  void fail(int code, const std::string& outcome);
  // peak_to_rms: 4 for noise excitation, 0 (cap off) for a sine (supervisor.hpp).
  SupervisorConfig supervisor_config(double peak_to_rms = 4.0) const;
  // Records a supervisor trip as the test's outcome; true when it had tripped.
  bool record_trip(const Supervisor& sup);
  // Sample timing of the pairs (u_k, y_k): the bias is held for one sample (centred half a
  // sample after the write) and the power is read `read_lag` after the write (one sample in
  // lockstep, ~0 in realtime), so the pairs see the plant delayed by dt/2 - read_lag. The
  // correction c = read_lag - dt/2 is added to estimated delays and removed from measured
  // phases (phase -= 360 f c), so that models and FRFs describe the plant itself.
  double timing_correction_s() const;
  void correct_timing(std::vector<model::FrfPoint>& frf) const;

  // Phase-change work (estimates, plans) runs off the loop thread in real time; meanwhile the
  // loop writes the baseline and reads every period, so neither the heartbeat nor the sample
  // stream stalls. Inline in lockstep (a seed gives the same recording).
  template <class Fn>
  auto off_loop(Fn fn) -> decltype(fn()) {
    if (lockstep()) return fn();
    auto done = std::async(std::launch::async, [work = std::move(fn)]() mutable {
      use_normal_priority();  // started by the realtime loop's thread
      return work();
    });
    while (done.wait_for(std::chrono::seconds(0)) != std::future_status::ready) loop.prime();
    return done.get();
  }
};

class SessionPhase {
 public:
  virtual ~SessionPhase() = default;
  virtual const char* name() const = 0;
  // False when the test must stop (ctx.data.exit_code and outcome are set).
  virtual bool run(RunContext& ctx) = 0;
};

// A phase that writes the bias: one Supervisor for the phase; request() every tick until it
// returns nullopt, then the supervisor's ramp back to baseline; consume() sees every tick that
// read a sample while the excitation is on. The one loop that drives every excitation.
class SupervisedPhase : public SessionPhase {
 public:
  bool run(RunContext& ctx) final;

 protected:
  virtual Phase code() const = 0;                             // the recording's phase column
  virtual bool prepare(RunContext& /*ctx*/) { return true; }  // false: skip, test goes on
  virtual std::optional<double> request(RunContext& ctx, long k) = 0;
  virtual void consume(RunContext& /*ctx*/, const TickResult& /*tick*/, long /*k*/) {}
  // Every tick that consume() does not see (ramp-down, after a trip), sample or not.
  virtual void observe(RunContext& /*ctx*/, const TickResult& /*tick*/) {}
  // After the ramp-down; completed is false after a trip. Returns whether the test goes on.
  virtual bool conclude(RunContext& /*ctx*/, bool completed) { return completed; }
  virtual double peak_to_rms() const { return 4.0; }
  // Samples the supervisor's soft start takes to reach full scale.
  static long soft_start_samples(const RunContext& ctx);
};

std::unique_ptr<SessionPhase> make_steady_state_phase();
std::unique_ptr<SessionPhase> make_activate_phase();
std::unique_ptr<SessionPhase> make_pilot_phase();
std::unique_ptr<SessionPhase> make_excite_phase();
std::unique_ptr<SessionPhase> make_sweep_phase();
std::unique_ptr<SessionPhase> make_deactivate_phase();
std::unique_ptr<SessionPhase> make_compare_phase();

// The test's excitation (Gaussian clipped at 3 sigma, or PRBS) of n samples at sigma_pct.
Eigen::VectorXd test_excitation(const TestConfig& c, Eigen::Index n, double sigma_pct,
                                std::uint64_t seed);

// Raised-cosine fade from 1 to 0 over n samples: an excitation ends without a step, which a
// lightly damped mode would answer with an overshoot.
double fade_out(long j, long n);
inline constexpr double kFadeOutS = 2.0;

}  // namespace rig::session
