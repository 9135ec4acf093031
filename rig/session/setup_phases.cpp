// The phases before any excitation: the steady-state check (nothing is written to the
// governor) and the activation with the bias acknowledgement (DESIGN.md section 8, layer 0).
#include <fmt/format.h>

#include <cmath>

#include "rig/session/phase.hpp"
#include "rig/session/steady_state.hpp"

namespace rig::session {
namespace {

class SteadyStatePhase final : public SessionPhase {
 public:
  const char* name() const override { return "steady"; }

  bool run(RunContext& ctx) override {
    const TestConfig& c = ctx.config;
    ctx.loop.set_phase(Phase::kSteady);
    const auto n = static_cast<long>(std::ceil(c.steady_state.duration_s * c.link.sample_rate_hz));
    for (long k = 0; k < n; ++k) {
      if (!observe(ctx, k)) return false;
    }
    const SteadyStateResult s = check_steady_state(
        t_, p_,
        {c.steady_state.max_noise_pct, c.steady_state.max_drift_pct, c.steady_state.min_power_kw});
    ctx.data.steady = s;
    if (!s.ok) {
      ctx.fail(kExitLinkFault, "steady-state check failed, test not started: " + s.reason);
      return false;
    }
    ctx.p0_kw = s.p0_kw;
    ctx.loop.set_p0(s.p0_kw);
    // A reading the governor gave all through the steady state must not drop to 0 later.
    ctx.plausible.speed = saw_speed_;
    ctx.plausible.freq = saw_freq_;
    ctx.view.message(
        fmt::format("steady state: P0 {:.1f} kW, noise {:.3f} %, drift {:.3f} % over {:.0f} s",
                    s.p0_kw, s.noise_pct, s.drift_pct, s.duration_s));
    return true;
  }

 private:
  bool observe(RunContext& ctx, long k) {
    if (ctx.loop.abort_requested()) {
      ctx.fail(kExitSafety, "operator abort during the steady-state check (nothing was written)");
      return false;
    }
    const TickResult r = ctx.loop.observe();
    if (!ctx.loop.rig_failure().empty()) {
      ctx.fail(kExitSafety, ctx.loop.rig_failure() + " (steady-state check, nothing was written)");
      return false;
    }
    if (!r.sample) {
      ctx.fail(kExitLinkFault,
               "link fault during the steady-state check: " + ctx.loop.last_link_error());
      return false;
    }
    if (k == 0 && (r.sample->status & drivers::kRunning) == 0) {
      ctx.fail(kExitLinkFault, "the governor reports the set is not running (status bit 0 clear)");
      return false;
    }
    saw_speed_ = saw_speed_ && r.sample->speed_rpm > 0.0;
    saw_freq_ = saw_freq_ && r.sample->freq_hz > 0.0;
    t_.push_back(r.t_s);
    p_.push_back(r.sample->power_kw);
    return true;
  }

  std::vector<double> t_, p_;
  bool saw_speed_ = true, saw_freq_ = true;
};

// Enables the external bias, then writes the baseline until the governor reports the bias
// active (status bit 2) with a live heartbeat, at most safety.activation_timeout_s.
class ActivatePhase final : public SessionPhase {
 public:
  const char* name() const override { return "activate"; }

  bool run(RunContext& ctx) override {
    const TestConfig& c = ctx.config;
    ctx.activated = true;  // from here on the ramp-down clears the enable, whatever happens
    if (auto a = ctx.link.activate(); !a) {
      ctx.fail(kExitLinkFault, "cannot enable the external bias: " + a.error().message());
      return false;
    }
    ActivationResult& result = ctx.data.activation.emplace();
    const auto n =
        static_cast<long>(std::ceil(c.safety.activation_timeout_s * c.link.sample_rate_hz));
    bool read_any = false;
    for (long k = 0; k < n; ++k) {
      const TickResult r = ctx.loop.prime();
      result.waited_s = static_cast<double>(k + 1) * ctx.dt_s();
      if (!r.sample) continue;
      read_any = true;
      result.status = r.sample->status;
      const bool active = (result.status & drivers::kBiasActive) != 0;
      const bool heartbeat = (result.status & drivers::kHeartbeatLost) == 0;
      if (active && heartbeat && k >= 2) {
        result.acknowledged = ctx.acknowledged = true;
        return true;
      }
    }
    refuse(ctx, read_any, result.status);
    return false;
  }

 private:
  static void refuse(RunContext& ctx, bool read_any, std::uint16_t status) {
    const double timeout_s = ctx.config.safety.activation_timeout_s;
    if (!read_any) {
      ctx.fail(kExitLinkFault,
               "link fault after enabling the external bias: " + ctx.loop.last_link_error());
    } else if ((status & drivers::kBiasActive) == 0) {
      ctx.fail(kExitLinkFault,
               fmt::format("the governor did not report the external bias active (status bit 2) "
                           "within {:g} s of enabling it (status 0x{:04x}): it does not accept "
                           "the bias",
                           timeout_s, status));
    } else {
      ctx.fail(kExitLinkFault, fmt::format("the governor still reports the heartbeat lost {:g} s "
                                           "after activation (status 0x{:04x})",
                                           timeout_s, status));
    }
  }
};

}  // namespace

std::unique_ptr<SessionPhase> make_steady_state_phase() {
  return std::make_unique<SteadyStatePhase>();
}
std::unique_ptr<SessionPhase> make_activate_phase() { return std::make_unique<ActivatePhase>(); }

}  // namespace rig::session
