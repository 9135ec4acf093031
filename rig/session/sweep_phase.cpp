// The swept-sine check (DESIGN.md section 2): stepped sines planned from the MMFM model (or,
// for `rig sweep`, from the pilot record) so that neither a point nor its sudden stop reaches
// the supervisor's back-off threshold; the FRF with the sample-timing correction.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/fra/stepped_sine.hpp"
#include "rig/ident/identify.hpp"
#include "rig/session/live_messages.hpp"
#include "rig/session/phase.hpp"

namespace rig::session {
namespace {

// The supervisor's statistical cap holds the request's mean square for tens of seconds, so in
// a stepped sine it would mix the previous point's amplitude with this point's gain; the
// sweep's amplitudes are planned per frequency from the model instead (0 disables the cap;
// the envelope back-off and the trip stay in force).
constexpr double kSinePeakToRms = 0.0;
// Relative standard error aimed at per sweep point: 1 degree (0.0175 rad, 0.15 dB), so that
// three standard errors stay inside a +-3 deg / +-0.5 dB comparison.
constexpr double kSweepTargetRelStd = 0.0175;
constexpr double kSweepMaxIntegrateFactor = 4.0;
// Without a model: a flat prior of five times the pilot's broadband gain (the resonance peak
// of a damping ratio 0.1 mode) keeps the amplitudes conservative.
constexpr double kFlatPriorPeakFactor = 5.0;

// Sweep without an excitation phase: a second-order MMFM fit of the pilot record, else the
// flat prior.
model::TransferFunction prior_from_pilot(RunContext& ctx) {
  try {
    ident::IdentifyOptions o;
    o.order = model::ModelOrder{2, 0};
    o.correlator.lags = ctx.config.mmfm.lags;
    const auto& u = ctx.pilot_u;
    const auto& y = ctx.pilot_y;
    const auto r = ident::identify(
        Eigen::Map<const Eigen::VectorXd>(u.data(), static_cast<Eigen::Index>(u.size())),
        Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size())),
        ctx.dt_s(), o);
    if (r.model.is_stable()) return r.model;
  } catch (const std::exception& ex) {
    ctx.loop.event("warning", std::string("pilot model failed, flat prior used: ") + ex.what());
  }
  model::TransferFunction flat;
  const double g = ctx.data.pilot ? ctx.data.pilot->gain_kw_per_pct : 1.0;
  flat.num = Eigen::VectorXd::Constant(1, kFlatPriorPeakFactor * g);
  flat.den = Eigen::VectorXd::Constant(1, 1.0);
  return flat;
}

// Fraction of the band a sine point may fill: below the supervisor's back-off threshold, since
// a back-off inside a point changes the amplitude mid-integration and biases that point.
double sine_plan_fraction(const RunContext& ctx) {
  return std::min(ctx.config.safety.plan_fraction,
                  0.9 * ctx.supervisor_config().backoff.start_fraction);
}

// Largest sine amplitude whose sudden stop (a trip, or the step from one point to the next)
// stays below that fraction: a step of A gives a peak of A |K| (1 + overshoot) for a
// second-order mode, overshoot = exp(-pi zeta / sqrt(1 - zeta^2)); without a model, 1.
double step_safe_amplitude_pct(const RunContext& ctx, const model::TransferFunction& prior,
                               const ident::DerivedFigures& d) {
  const double gain = std::abs(prior.dc_gain());
  if (!(gain > 0.0) || !std::isfinite(gain)) return ctx.config.safety.clamp_pct;
  double overshoot = 1.0;
  if (d.valid && d.zeta > 0.0 && d.zeta < 1.0) {
    overshoot = std::exp(-M_PI * d.zeta / std::sqrt(1.0 - d.zeta * d.zeta));
  }
  return sine_plan_fraction(ctx) * ctx.band_kw() / (gain * (1.0 + overshoot));
}

fra::SweepPlanOptions plan_options(const RunContext& ctx, const model::TransferFunction& prior,
                                   const ident::DerivedFigures& d) {
  const TestConfig& c = ctx.config;
  fra::SweepPlanOptions p;
  p.f_start_hz = c.sweep.from_hz;
  p.f_stop_hz = c.sweep.to_hz;
  p.points = c.sweep.points;
  p.dt_s = ctx.dt_s();
  if (d.valid && d.zeta > 0.0 && d.fn_hz > 0.0) {
    p.slowest_time_constant_s = 1.0 / (d.zeta * 2.0 * M_PI * d.fn_hz);
  }
  p.settle_time_constants = c.sweep.settle_time_constants;
  p.min_settle_cycles = static_cast<int>(std::ceil(c.sweep.settle_cycles));
  p.min_integrate_cycles = static_cast<int>(std::ceil(c.sweep.integrate_cycles));
  p.min_integrate_s = c.sweep.min_integrate_s;
  // Points whose amplitude is capped far below the band (above the resonance) integrate until
  // the lock-in's relative standard error is kSweepTargetRelStd, at most
  // kSweepMaxIntegrateFactor times the minimum (stepped_sine_plan.hpp, noise rule).
  p.noise_rms_kw = ctx.noise_kw();
  p.target_rel_std = kSweepTargetRelStd;
  p.max_integrate_s = kSweepMaxIntegrateFactor * c.sweep.min_integrate_s;
  p.amplitude.band_kw = ctx.band_kw();
  p.amplitude.plan_fraction = sine_plan_fraction(ctx);
  p.amplitude.noise_peak_kw = 3.0 * ctx.noise_kw();
  p.amplitude.max_amplitude_pct =
      std::min(c.safety.clamp_pct, step_safe_amplitude_pct(ctx, prior, d));
  return p;
}

class SweepPhase final : public SupervisedPhase {
 public:
  const char* name() const override { return "sweep"; }

 protected:
  Phase code() const override { return Phase::kSweep; }
  double peak_to_rms() const override { return kSinePeakToRms; }

  bool prepare(RunContext& ctx) override {
    if (!ctx.config.sweep.enabled) return false;
    const auto& mmfm = ctx.data.excitation.mmfm;
    const model::TransferFunction prior = mmfm ? mmfm->model : prior_from_pilot(ctx);
    const auto d = mmfm ? mmfm->derived : ident::DerivedFigures{};
    const fra::SweepPlanOptions p = plan_options(ctx, prior, d);
    std::string error;
    ctx.off_loop([&] {
      try {
        plan_ = fra::make_sweep_plan(p, fra::as_response_fn(prior));
      } catch (const std::exception& ex) {
        error = ex.what();
      }
    });
    if (!error.empty()) {
      ctx.loop.event("warning", "swept sine skipped: " + error);
      return false;
    }
    analyser_.emplace(plan_);
    soft_ = soft_start_samples(ctx);
    fade_n_ = std::lround(kFadeOutS * ctx.config.link.sample_rate_hz);
    return true;
  }

  std::optional<double> request(RunContext& ctx, long k) override {
    if (k < soft_) return 0.0;
    if (analyser_->done()) return fading_last_point(ctx, k);
    const auto& pts = analyser_->plan().points;
    ctx.loop.status().phase = fmt::format("sweep {:.2f}Hz", pts[analyser_->point_index()].freq_hz);
    return analyser_->excitation_pct();
  }

  void consume(RunContext& ctx, const TickResult& r, long k) override {
    if (k < soft_ || analyser_->done()) return;
    if (auto point = analyser_->push(r.out.excitation_pct, r.sample->power_kw - ctx.p0_kw)) {
      if (!point->good) ctx.loop.status().flags = {"sweep point below quality"};
      ctx.loop.live().publish(
          live::kind::kSweepPoint,
          sweep_point_message(*point, ctx.timing_correction_s(), ctx.loop.t_s()));
    }
    ctx.loop.status().eta_s = plan_.duration_s() - static_cast<double>(k - soft_) * ctx.dt_s();
  }

  bool conclude(RunContext& ctx, bool completed) override {
    ctx.data.sweep = analyser_->frf();
    ctx.correct_timing(ctx.data.sweep);
    return completed;
  }

 private:
  // Continues the last point's sine A sin(2 pi f n dt) while fading it out.
  std::optional<double> fading_last_point(const RunContext& ctx, long k) {
    if (k_done_ < 0) k_done_ = k;
    const auto& last = plan_.points.back();
    const long j = k - k_done_;
    if (j >= fade_n_) return std::nullopt;
    const double n = static_cast<double>(last.total_samples() + j);
    return last.amplitude_pct * std::sin(2.0 * M_PI * last.freq_hz * n * ctx.dt_s()) *
           fade_out(j, fade_n_);
  }

  fra::SweepPlan plan_;
  std::optional<fra::SteppedSineAnalyser> analyser_;
  long soft_ = 0, fade_n_ = 0, k_done_ = -1;
};

}  // namespace

std::unique_ptr<SessionPhase> make_sweep_phase() { return std::make_unique<SweepPhase>(); }

}  // namespace rig::session
