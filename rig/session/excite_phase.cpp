// The excitation with online MMFM (DESIGN.md section 2): the planned excitation until the
// stopping rule or the maximum duration, faded out over kFadeOutS; then the analysis of
// excitation_analysis.hpp off the loop thread, and no model when the data do not support one.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/session/excitation_analysis.hpp"
#include "rig/session/live_messages.hpp"
#include "rig/session/online_mmfm.hpp"
#include "rig/session/phase.hpp"

namespace rig::session {
namespace {

signal::CorrelatorKind correlator_kind(const std::string& name) {
  if (name == "fft") return signal::CorrelatorKind::kFft;
  if (name == "relay") return signal::CorrelatorKind::kRelay;
  if (name == "polarity") return signal::CorrelatorKind::kPolarity;
  return signal::CorrelatorKind::kDirect;
}

OnlineMmfmOptions online_options(const TestConfig& c) {
  OnlineMmfmOptions o;
  o.order = {c.mmfm.order_n, c.mmfm.order_m};
  o.delay_s = c.mmfm.delay_s;
  o.correlator.lags = c.mmfm.lags;
  o.correlator.skip = c.mmfm.skip;
  o.correlator.kind = correlator_kind(c.mmfm.correlator);
  o.correlator.dt_s = 1.0 / c.link.sample_rate_hz;
  o.block_samples = c.mmfm.block_size;
  o.exponential = c.mmfm.averaging == "exponential";
  o.weight = c.mmfm.averaging_w;
  o.ac_coupling_rc_s = c.excitation.ac_coupling_rc_s;
  if (c.mmfm.auto_order) o.orders = kAutoOrders;
  o.compare_freqs_hz =
      ident::log_frequencies_hz(c.compare.from_hz, c.compare.to_hz, kCompareFrequencies);
  o.target_db = c.mmfm.target_db;
  o.target_deg = c.mmfm.target_deg;
  // Realtime: a block estimate (tens of ms) must not delay the next exchange, so it runs on a
  // worker and the stopping rule sees it a few ticks later. Lockstep keeps it inside the tick
  // so that a seed gives the same recording.
  o.asynchronous = c.link.lockstep_ticks == 0;
  return o;
}

// The dominant mode for the supervisor and the sweep: the chosen model's second-order
// figures, or the second-order candidate's when a richer structure was chosen; 0 if neither.
double dominant_mode_hz(const ExcitationResult& x) {
  if (x.mmfm && x.mmfm->derived.valid) return x.mmfm->derived.fn_hz;
  if (!x.order_choice) return 0.0;
  for (const auto& c : x.order_choice->candidates) {
    if (!c.ok || !(c.order == model::ModelOrder{2, 0})) continue;
    const ident::DerivedFigures d = ident::derived_figures(c.model, Eigen::MatrixXd());
    if (d.valid) return d.fn_hz;
  }
  return 0.0;
}

class ExcitePhase final : public SupervisedPhase {
 public:
  const char* name() const override { return "excite"; }

 protected:
  Phase code() const override { return Phase::kExcite; }
  double peak_to_rms() const override { return peak_to_rms_; }

  bool prepare(RunContext& ctx) override {
    const TestConfig& c = ctx.config;
    const double rate = c.link.sample_rate_hz;
    OnlineMmfmOptions oo = online_options(c);
    if (ctx.shaped) oo.prior = ctx.shaped->pilot_model;
    online_.emplace(oo);
    max_n_ = std::lround(c.mmfm.max_duration_s * rate);
    online_->reserve(max_n_ + std::lround(kFadeOutS * rate));
    min_n_ = std::lround(c.mmfm.min_duration_s * rate);
    fade_n_ = std::lround(kFadeOutS * rate);
    k_stop_ = max_n_;
    if (ctx.shaped) {
      e_ = repeat_period(ctx.shaped->period_pct, max_n_ + fade_n_);
      // The supervisor's statistical cap with the output's own crest factor.
      peak_to_rms_ = kShapedGainMargin * ctx.shaped->output_crest;
    } else {
      e_ = test_excitation(c, max_n_ + fade_n_, ctx.data.excitation.planned_std_pct,
                           c.excitation.seed);
    }
    ctx.data.excitation.stop_reason = "maximum duration reached";
    record_.dt_s = ctx.dt_s();
    record_.timing_correction_s = ctx.timing_correction_s();
    return true;
  }

  std::optional<double> request(RunContext& ctx, long k) override {
    if (stop_) k_stop_ = std::min(k_stop_, k);
    ctx.loop.status().eta_s =
        static_cast<double>(std::min(max_n_, k_stop_) + fade_n_ - k) * ctx.dt_s();
    if (k >= k_stop_ + fade_n_) return std::nullopt;
    return e_(k) * (k < k_stop_ ? 1.0 : fade_out(k - k_stop_, fade_n_));
  }

  void consume(RunContext& ctx, const TickResult& r, long k) override {
    const double u = r.out.excitation_pct;
    const double y = r.sample->power_kw - ctx.p0_kw;
    record_.u_pct.push_back(u);
    record_.y_kw.push_back(y);
    if (auto est = online_->push(u, y)) {
      show_estimate(ctx, *est);
      if (!stop_ && online_->converged() && k >= min_n_) {
        stop_ = true;
        ctx.data.excitation.stop_reason = fmt::format(
            "the model's 95 % band is within +-{:g} dB and +-{:g} deg over {:g}-{:g} Hz",
            ctx.config.mmfm.target_db, ctx.config.mmfm.target_deg, ctx.config.compare.from_hz,
            ctx.config.compare.to_hz);
      }
    }
  }

  bool conclude(RunContext& ctx, bool completed) override {
    ctx.loop.status().estimates.clear();
    ExcitationResult& x = ctx.data.excitation;
    ctx.off_loop([&] { analyse_excitation(*online_, record_, ctx.config, x); });
    if (!x.mmfm_error.empty()) ctx.loop.event("warning", "MMFM estimate failed: " + x.mmfm_error);
    if (const double fn = dominant_mode_hz(x); fn > 0.0) ctx.resonance_hz = fn;
    if (!completed) return false;
    ctx.view.message(
        fmt::format("excitation: {:.0f} s, applied std {:.3f} % of {:.3f} % planned, "
                    "stopped: {}",
                    x.duration_s, x.applied_std_pct, x.planned_std_pct, x.stop_reason));
    const std::string why = why_no_model(x, ctx.config);
    if (why.empty()) return true;
    ctx.data.model_rejected = why;
    ctx.fail(kExitAcceptance, "no model: " + why);
    return false;
  }

 private:
  void show_estimate(RunContext& ctx, const BlockEstimate& e) const {
    publish_estimate(ctx, e);
    auto& est = ctx.loop.status().estimates;
    est.clear();
    if (!e.ok) {
      ctx.loop.status().flags = {"estimate failed"};
      return;
    }
    ctx.loop.status().flags.clear();
    if (e.derived.valid) {
      est.push_back({"K", e.derived.gain, e.derived.gain_std});
      est.push_back({"fn", e.derived.fn_hz, e.derived.fn_hz_std});
      est.push_back({"zeta", e.derived.zeta, e.derived.zeta_std});
    } else {
      for (const auto& p : e.parameters) est.push_back({p.name, p.value, p.std_error});
    }
    est.push_back({"Td", plant_delay_s(e.delay_s, record_.timing_correction_s),
                   e.parameters.empty() ? 0.0 : e.parameters.back().std_error});
    est.push_back({"order", static_cast<double>(e.order.n), 0.0});
    if (std::isfinite(e.band_db95)) est.push_back({"+-dB", e.band_db95, 0.0});
    if (std::isfinite(e.band_deg95)) est.push_back({"+-deg", e.band_deg95, 0.0});
  }

  // The live feed: every block estimate, and the Bode plot of each usable model over the
  // swept-sine range (the page draws the sweep's points on it as they arrive).
  void publish_estimate(RunContext& ctx, const BlockEstimate& e) const {
    const LivePublisher& live = ctx.loop.live();
    if (!live.on()) return;
    const double c = record_.timing_correction_s;
    nlohmann::json message = estimate_message(e, c);
    message["excitation_t_s"] = e.t_s;  // the block's end in excitation time
    message["t_s"] = ctx.loop.t_s();    // test time, like every other message
    live.publish(live::kind::kEstimate, message);
    const SweepSettings& range = ctx.config.sweep;
    if (e.ok) {
      live.publish(live::kind::kBode,
                   bode_message(e.model, range.from_hz, range.to_hz, c, ctx.loop.t_s()));
    }
  }

  std::optional<OnlineMmfm> online_;
  ExcitationRecord record_;
  Eigen::VectorXd e_;
  long max_n_ = 0, min_n_ = 0, fade_n_ = 0, k_stop_ = 0;
  double peak_to_rms_ = kPeakFactor;
  bool stop_ = false;
};

}  // namespace

std::unique_ptr<SessionPhase> make_excite_phase() { return std::make_unique<ExcitePhase>(); }

}  // namespace rig::session
