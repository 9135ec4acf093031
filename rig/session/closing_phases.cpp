// The phases after the excitation: the ramp-down (always, whatever happened before) and the
// comparison of the MMFM model with the swept sine and H1 (nothing is written meanwhile).
#include <fmt/format.h>

#include <chrono>
#include <thread>

#include "rig/fra/compare.hpp"
#include "rig/session/phase.hpp"

namespace rig::session {
namespace {

// Bounded: the governor's heartbeat rule has dropped the bias within 0.5 s anyway; these tries
// clear the enable and the held bias so that no later heartbeat writer re-applies them.
constexpr int kRampDownReconnects = 5;
constexpr auto kReconnectWait = std::chrono::milliseconds(400);

// deactivate() ramps from the bias the governor applies now (read back) and clears the enable;
// after a dropped link it reconnects to do so (DESIGN.md section 8, layer 3).
class DeactivatePhase final : public SessionPhase {
 public:
  const char* name() const override { return "deactivate"; }

  bool run(RunContext& ctx) override {
    RampDownResult& rd = ctx.data.ramp_down;
    if (!ctx.activated) {  // nothing was ever enabled
      ctx.link.close();
      return true;
    }
    rd.attempted = true;
    drivers::LinkResult<void> d = ctx.link.deactivate();
    for (int attempt = 1; !d && attempt <= kRampDownReconnects; ++attempt) {
      ctx.loop.event("link", fmt::format("ramp-down failed ({}); reconnecting, try {} of {}",
                                         d.error().message(), attempt, kRampDownReconnects));
      if (!ctx.lockstep()) std::this_thread::sleep_for(kReconnectWait);
      if (auto c = ctx.link.configure(); !c) {
        d = c.error();
        continue;
      }
      ++rd.reconnects;
      d = ctx.link.deactivate();
    }
    rd.cleared = d.has_value();
    if (!rd.cleared) {
      rd.error = d.error().message();
      ctx.loop.event("link", "could not ramp down and clear the enable: " + rd.error +
                                 " (the governor's heartbeat rule removes the bias)");
    } else if (rd.reconnects > 0) {
      ctx.loop.event("link", fmt::format("reconnected ({}x), bias ramped to baseline and enable "
                                         "cleared",
                                         rd.reconnects));
    }
    ctx.link.close();
    return rd.cleared;
  }
};

class ComparePhase final : public SessionPhase {
 public:
  const char* name() const override { return "compare"; }

  bool run(RunContext& ctx) override {
    const TestConfig& c = ctx.config;
    SessionData& d = ctx.data;
    if (!d.excitation.mmfm) return true;
    const auto& model = d.excitation.mmfm->model;
    fra::CompareTolerances tol;
    tol.mag_db = c.compare.mag_tol_db;
    tol.phase_deg = c.compare.phase_tol_deg;
    tol.f_lo_hz = c.compare.from_hz;
    tol.f_hi_hz = c.compare.to_hz;
    tol.min_coherence = c.compare.min_coherence;
    if (!d.sweep.empty()) d.compare_sweep = fra::compare(model, d.sweep, tol);
    if (!d.excitation.h1.empty()) d.compare_h1 = fra::compare(model, d.excitation.h1, tol);
    if (d.exit_code != kExitOk || !c.sweep.enabled) return true;
    if (!d.compare_sweep || d.compare_sweep->verdict != fra::Verdict::kPass) {
      d.exit_code = kExitAcceptance;
      d.outcome = "acceptance check failed: " +
                  (d.compare_sweep ? d.compare_sweep->summary
                                   : std::string("no swept-sine response to compare"));
      return false;
    }
    return true;
  }
};

}  // namespace

std::unique_ptr<SessionPhase> make_deactivate_phase() {
  return std::make_unique<DeactivatePhase>();
}
std::unique_ptr<SessionPhase> make_compare_phase() { return std::make_unique<ComparePhase>(); }

}  // namespace rig::session
