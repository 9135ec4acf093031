// The pilot (DESIGN.md section 8, layer 1): a short excitation at the test file's amplitude
// measures the gain that plans the main excitation's amplitude (pilot.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/session/phase.hpp"
#include "rig/session/pilot.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::session {

Eigen::VectorXd test_excitation(const TestConfig& c, Eigen::Index n, double sigma_pct,
                                std::uint64_t seed) {
  if (c.excitation.type == ExcitationType::kPrbs) {
    signal::PrbsOptions p;
    p.n = n;
    p.register_length = c.excitation.prbs_register_length;
    p.clock_divider = c.excitation.prbs_clock_divider;
    p.amplitude = sigma_pct;
    p.seed = seed;
    return signal::prbs_excitation(p);
  }
  signal::GaussianOptions g;
  g.n = n;
  g.dt_s = 1.0 / c.link.sample_rate_hz;
  g.bandwidth_hz = c.excitation.bandwidth_hz;
  g.sigma = sigma_pct;
  g.clip_sigma = kExcitationClipSigma;
  g.seed = seed;
  return signal::gaussian_excitation(g);
}

namespace {

// The pilot's own noise sequence, distinct from the main excitation's.
constexpr std::uint64_t kPilotSeedOffset = 7919;
// The shaped excitation's lines cover the compare band with room on both sides.
constexpr double kShapedLowFraction = 0.5;
constexpr double kShapedHighFactor = 1.2;

class PilotPhase final : public SupervisedPhase {
 public:
  const char* name() const override { return "pilot"; }

 protected:
  Phase code() const override { return Phase::kPilot; }

  bool prepare(RunContext& ctx) override {
    const TestConfig& c = ctx.config;
    soft_ = soft_start_samples(ctx);
    n_ = soft_ + std::lround(c.pilot.duration_s * c.link.sample_rate_hz);
    fade_n_ = std::lround(kFadeOutS * c.link.sample_rate_hz);
    e_ = test_excitation(c, n_ + fade_n_, c.pilot.amplitude_pct,
                         c.excitation.seed + kPilotSeedOffset);
    return true;
  }

  std::optional<double> request(RunContext& ctx, long k) override {
    ctx.loop.status().eta_s = static_cast<double>(n_ + fade_n_ - k) * ctx.dt_s();
    if (k >= n_ + fade_n_) return std::nullopt;
    // Faded out, so that the mode is not left swinging into the next phase (where the swing
    // would inflate the gain the supervisor's cap learns at its soft start).
    return e_(k) * (k < n_ ? 1.0 : fade_out(k - n_, fade_n_));
  }

  void consume(RunContext& ctx, const TickResult& r, long k) override {
    if (k < soft_ || k >= n_) return;  // scale still rising, or fading out
    ctx.pilot_u.push_back(r.out.excitation_pct);
    ctx.pilot_y.push_back(r.sample->power_kw - ctx.p0_kw);
  }

  bool conclude(RunContext& ctx, bool completed) override {
    if (!completed) return false;
    const TestConfig& c = ctx.config;
    PilotPlanLimits limits;
    limits.band_kw = ctx.band_kw();
    limits.plan_fraction = c.safety.plan_fraction;
    limits.clamp_pct = c.safety.clamp_pct;
    limits.noise_std_kw = ctx.noise_kw();
    limits.input_crest = c.excitation.type == ExcitationType::kPrbs ? 1.0 : kExcitationClipSigma;
    const PilotResult& p = ctx.data.pilot.emplace(
        ctx.off_loop([&] { return analyse_pilot(ctx.pilot_u, ctx.pilot_y, limits); }));
    if (!p.ok) {
      ctx.fail(kExitLinkFault, p.reason);
      return false;
    }
    ctx.data.excitation.planned_std_pct = p.planned_std_pct;
    ctx.view.message(fmt::format(
        "pilot: gain {:.1f} kW/%, planned excitation std {:.3f} % (predicted peak {:.1f} of "
        "{:.1f} kW){}",
        p.gain_kw_per_pct, p.planned_std_pct, p.predicted_peak_kw, limits.band_kw,
        p.limited_by_clamp ? ", limited by the clamp" : ""));
    ctx.data.excitation.type = to_string(c.excitation.type);
    if (c.excitation.type == ExcitationType::kShaped) plan_shaped(ctx);
    return true;
  }

 private:
  // The shaped excitation from the pilot's model; on failure the test goes on with the
  // Gaussian plan above, with a warning.
  static void plan_shaped(RunContext& ctx) {
    const TestConfig& c = ctx.config;
    ShapedLimits l;
    l.dt_s = ctx.dt_s();
    l.band_kw = ctx.band_kw();
    l.noise_std_kw = ctx.noise_kw();
    l.clamp_pct = c.safety.clamp_pct;
    l.f_lo_hz = kShapedLowFraction * c.compare.from_hz;
    l.f_hi_hz = std::min(kShapedHighFactor * c.compare.to_hz, 0.4 * c.link.sample_rate_hz);
    l.ac_coupling_rc_s = c.excitation.ac_coupling_rc_s;
    l.seed = c.excitation.seed;
    ShapedDesign d =
        ctx.off_loop([&] { return design_shaped_excitation(ctx.pilot_u, ctx.pilot_y, l); });
    if (!d.ok) {
      ctx.loop.event("warning", "shaped excitation not designed (" + d.reason +
                                    "); the Gaussian plan is used");
      ctx.data.excitation.type = to_string(ExcitationType::kGaussian);
      return;
    }
    ctx.data.excitation.planned_std_pct = d.std_pct;
    ctx.view.message(fmt::format(
        "shaped excitation: {} lines {:.2f}-{:.2f} Hz, std {:.3f} %, crest factor input {:.2f} "
        "output {:.2f}, predicted peak {:.1f} of {:.1f} kW{}",
        d.lines, d.f_lo_hz, d.f_hi_hz, d.std_pct, d.input_crest, d.output_crest,
        d.predicted_peak_kw, l.band_kw, d.limited_by_clamp ? ", limited by the clamp" : ""));
    ctx.data.excitation.shaped = d;
    ctx.shaped = std::move(d);
  }

  long soft_ = 0, n_ = 0, fade_n_ = 0;
  Eigen::VectorXd e_;
};

}  // namespace

std::unique_ptr<SessionPhase> make_pilot_phase() { return std::make_unique<PilotPhase>(); }

}  // namespace rig::session
