// The phases of a commissioning test, run over one link and one recording (see session.hpp).
// Internal to rig/session: the CLI calls run_commission().
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <vector>

#include "drivers/governor_link.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/session.hpp"
#include "rig/session/tick_loop.hpp"

namespace rig::session {

class Sequencer {
 public:
  Sequencer(SessionData& data, drivers::GovernorLink& link, io::RecordingWriter& recorder,
            LiveView& view, const SessionOptions& options);

  // Each returns false when the test must stop (data.exit_code and outcome are set).
  bool steady_state();
  bool activate();
  bool pilot();
  bool excite();
  bool sweep();
  void compare();
  void finish();  // deactivate (ramp to zero) and close the link

  TickLoop& loop() { return loop_; }

 private:
  // Runs phase-change work (estimates, plans) off the loop thread in real time, holding the
  // baseline with a write and a read every period meanwhile, so that neither the heartbeat
  // nor the sample stream stalls; inline in lockstep (a seed gives the same recording).
  template <class Fn>
  auto off_loop(Fn fn) -> decltype(fn()) {
    if (data_.config.link.lockstep_ticks > 0) return fn();
    auto done = std::async(std::launch::async, std::move(fn));
    while (done.wait_for(std::chrono::seconds(0)) != std::future_status::ready) loop_.prime();
    return done.get();
  }
  // Excitation over: final estimate, H1, the applied level and the data-quality checks.
  void analyse_excitation(OnlineMmfm& online);
  // False (exit 1, outcome set) when the applied excitation or the data do not support a model.
  bool excitation_supports_model();
  void check_excitation_quality(const Eigen::VectorXd& u, const Eigen::VectorXd& y);
  // peak_to_rms: 4 for noise excitation, 2 for a sine (supervisor.hpp).
  SupervisorConfig supervisor_config(double peak_to_rms = 4.0) const;
  // Runs a supervised phase: request(k) for k < samples (nullopt ends early), then the
  // ramp-down. consume(tick) sees every tick with a sample. False when it tripped.
  using Request = std::function<std::optional<double>(long k)>;
  using Consume = std::function<void(const TickResult& tick)>;
  bool supervised_phase(Phase phase, const Request& request, const Consume& consume,
                        double peak_to_rms = 4.0);
  bool tripped(const Supervisor& sup);
  void fail(int code, const std::string& outcome);
  void show_estimate(const BlockEstimate& e);

  SessionData& data_;
  drivers::GovernorLink& link_;
  LiveView& view_;
  TickLoop loop_;
  double p0_kw_ = 0.0;
  bool activated_ = false;          // enable was written (finish() must clear it)
  bool bias_acknowledged_ = false;  // the governor reported the bias active (layer 0 on)
  PlausibilityCheck plausible_;
  double resonance_hz_ = 2.0;          // dominant mode, updated from the MMFM model
  std::vector<double> exc_u_, exc_y_;  // excitation phase: applied u and P - P0
  std::vector<double> pilot_u_, pilot_y_;
  ident::TransferFunction prior_from_pilot();
  // Sample timing of the pairs (u_k, y_k): the bias is held for one sample (zero-order hold,
  // centred half a sample after the write) and the power is read `read_lag` after the write
  // (one sample in lockstep, ~0 in realtime). The pairs therefore see the plant delayed by
  // dt/2 - read_lag:  H_pairs(f) = H(f) e^{-j 2 pi f (dt/2 - read_lag)} (sinc(f dt) ~ 1).
  // The correction c = read_lag - dt/2 is added to the estimated delay and removed from the
  // measured phases (phase -= 360 f c), so that models and FRFs describe the plant itself.
  double timing_correction_s() const;
  void correct_timing(std::vector<fra::FrfPoint>& frf) const;
  double step_safe_amplitude_pct(const ident::TransferFunction& prior,
                                 const ident::DerivedFigures& derived) const;
};

}  // namespace rig::session
