#include "rig/session/monitor_session.hpp"

#include <fmt/format.h>

#include <cmath>
#include <deque>
#include <optional>

#include "drivers/can/can_link.hpp"
#include "drivers/open_link.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/monitor/monitor_report.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/monitor_phase.hpp"
#include "rig/session/steady_state.hpp"

namespace rig::session {
namespace {

// The excitation's predicted peak response stays within the monitoring band: peak factor of
// a Gaussian (or PRBS) response, as the supervisor's statistical cap assumes.
constexpr double kPeakFactor = 4.0;
constexpr double kPlanSamples = 16384;   // excitation simulated through the baseline to plan
constexpr double kSettleWindowS = 30.0;  // a new steady state: this much quiet power

// The excitation std (% of rated) whose response through the baseline peaks at the band.
double plan_sigma_pct(const TestConfig& c, const model::TransferFunction& g, double band_kw) {
  const Eigen::VectorXd e = test_excitation(c, static_cast<Eigen::Index>(kPlanSamples), 1.0, 7);
  const Eigen::VectorXd y = model::simulate(g, e, 1.0 / c.link.sample_rate_hz);
  const Eigen::VectorXd tail = y.tail(y.size() / 2);
  const double std_per_pct = std::sqrt((tail.array() - tail.mean()).square().mean());
  if (!(std_per_pct > 0.0)) return 0.0;
  return std::min(band_kw / (kPeakFactor * std_per_pct), c.safety.clamp_pct / kPeakFactor);
}

monitor::MonitorSettings core_settings(const TestConfig& c, const MonitorOptions& o, double p0_kw) {
  monitor::MonitorSettings s;
  s.dt_s = 1.0 / c.link.sample_rate_hz;
  s.coupling_rc_s = c.excitation.ac_coupling_rc_s > 0.0 ? c.excitation.ac_coupling_rc_s : 1.6;
  s.learn_s = o.learn_s;
  s.false_alarms_per_month = o.false_alarms_per_month;
  s.p0_kw = p0_kw;
  return s;
}

// Waits with the bias at baseline (heartbeat kept) until the event is judged and the power
// has been steady for kSettleWindowS; returns the new P0, or nullopt when the run must end
// (ctx.data holds why, or run.stop_reason for an operator stop).
std::optional<double> wait_for_steady(RunContext& ctx, MonitorRun& run) {
  const TestConfig& c = ctx.config;
  ctx.loop.set_phase(Phase::kSteady);
  ctx.loop.status().phase = "waiting for steady state";
  const long window = std::lround(kSettleWindowS * c.link.sample_rate_hz);
  const long limit = std::lround(run.options.settle_timeout_s * c.link.sample_rate_hz);
  std::deque<double> t, p;
  std::deque<double> cycle;  // the last engine cycle of power, averaged: no firing ripple
  double cycle_sum = 0.0;
  for (long k = 0; k < limit; ++k) {
    if (ctx.loop.abort_requested()) {
      run.stop_reason = "stopped by the operator while waiting for a steady state";
      return std::nullopt;
    }
    const TickResult r = ctx.loop.prime();
    if (!r.sample) {
      if (ctx.loop.link_gone()) {
        ctx.fail(kExitLinkFault,
                 "link lost while waiting for a steady state: " + ctx.loop.last_link_error());
        return std::nullopt;
      }
      continue;
    }
    run.core.observe(r.t_s, 0.0, r.sample->power_kw);
    run.publish(ctx, nullptr);
    const double speed = r.sample->speed_rpm > 0.0 ? r.sample->speed_rpm : 0.0;
    const auto cycle_n = static_cast<std::size_t>(
        std::max(1L, speed > 0.0 ? std::lround(120.0 / speed * c.link.sample_rate_hz) : 1L));
    cycle.push_back(r.sample->power_kw);
    cycle_sum += r.sample->power_kw;
    while (cycle.size() > cycle_n) {
      cycle_sum -= cycle.front();
      cycle.pop_front();
    }
    t.push_back(r.t_s);
    p.push_back(cycle_sum / static_cast<double>(cycle.size()));
    if (static_cast<long>(t.size()) > window) {
      t.pop_front();
      p.pop_front();
    }
    if (run.core.event_pending() || static_cast<long>(t.size()) < window || k % 100 != 0) continue;
    const SteadyStateResult s = check_steady_state(
        {t.begin(), t.end()}, {p.begin(), p.end()},
        {c.steady_state.max_noise_pct, c.steady_state.max_drift_pct, c.steady_state.min_power_kw});
    if (s.ok) return s.p0_kw;
  }
  ctx.fail(kExitSafety, fmt::format("no new steady state within {:g} s after the event",
                                    run.options.settle_timeout_s));
  return std::nullopt;
}

// Counts a band trip; false when too many fell within the window (the run ends, exit 4).
bool count_trip(RunContext& ctx, MonitorRun& run, std::deque<double>& trips) {
  const double now = ctx.loop.t_s();
  trips.push_back(now);
  while (!trips.empty() && trips.front() < now - run.options.trip_window_s) trips.pop_front();
  ++run.summary.trips;
  if (static_cast<int>(trips.size()) <= run.options.max_trips) return true;
  ctx.fail(kExitSafety, fmt::format("{} band trips within {:g} s: the set is not steady enough "
                                    "to monitor",
                                    trips.size(), run.options.trip_window_s));
  return false;
}

// The monitoring phases until the run ends; returns normally with ctx.data set.
void monitor_loop(RunContext& ctx, MonitorRun& run) {
  std::deque<double> trips;
  while (true) {
    ctx.data.trip.reset();
    const bool completed = make_monitor_phase(run)->run(ctx);
    if (!completed) {
      const bool band = ctx.data.trip && ctx.data.trip->cause == TripCause::kOutOfBand;
      if (!band) return;  // link, heartbeat, echo, rig failure: the run ends with its code
      ctx.data.exit_code = kExitOk;  // a band trip while monitoring is an event
      ctx.data.outcome.clear();
      run.core.trip(ctx.loop.t_s());
      run.history.add_event(run.run_id, ctx.loop.t_s(), "trip", ctx.data.trip->text);
      if (!count_trip(ctx, run, trips)) return;
    } else if (!run.stop_reason.empty()) {
      return;
    }
    const std::optional<double> p0 = wait_for_steady(ctx, run);
    if (!p0) return;
    run.history.add_event(
        run.run_id, ctx.loop.t_s(), "re-baselined",
        fmt::format("new steady state: P0 {:.1f} kW (was {:.1f} kW)", *p0, ctx.p0_kw));
    ctx.p0_kw = *p0;
    ctx.loop.set_p0(*p0);
    run.core.resume(*p0);
    run.sigma_pct =
        plan_sigma_pct(ctx.config, run.core.baseline(), run.options.band_pct / 100.0 * *p0);
  }
}

}  // namespace

namespace {

std::unique_ptr<io::RecordingWriter> open_recorder(const TestConfig& c,
                                                   const SessionOptions& options, bool keep) {
  io::RecordingWriterOptions wo;
  wo.flush_period = std::chrono::milliseconds(static_cast<long>(c.output.flush_interval_s * 1000));
  wo.sync_to_disk = false;
  wo.write_sidecar = keep;
  // Without --record the loop writes no rows; the writer only has to exist.
  const std::filesystem::path path = keep ? options.out_dir / "recording.csv" : "/dev/null";
  return std::make_unique<io::RecordingWriter>(path, recording_columns(), io::Sidecar{}, wo);
}

// Steady state, activation, the excitation plan, then the monitoring loop.
void monitor_run(RunContext& ctx, MonitorRun& run, const model::TransferFunction& pairs_model) {
  if (!make_steady_state_phase()->run(ctx)) return;
  run.history.set_run_p0(run.run_id, ctx.p0_kw);
  run.history.add_event(run.run_id, ctx.loop.t_s(), "start",
                        fmt::format("steady state P0 {:.1f} kW", ctx.p0_kw));
  if (!make_activate_phase()->run(ctx)) return;
  run.core.resume(ctx.p0_kw);
  run.sigma_pct = plan_sigma_pct(ctx.config, pairs_model, run.options.band_pct / 100.0 * ctx.p0_kw);
  run.summary.sigma_pct = run.sigma_pct;
  if (!(run.sigma_pct > 0.0)) {
    ctx.fail(kExitUsage, "the baseline model predicts no response: cannot plan the excitation");
    return;
  }
  ctx.view.message(fmt::format(
      "monitoring: excitation std {:.3f} % of rated (band +-{:g} % of P0 {:.1f} kW), learning "
      "the baseline's spread over {:g} s",
      run.sigma_pct, run.options.band_pct, ctx.p0_kw, run.options.learn_s));
  monitor_loop(ctx, run);
}

}  // namespace

MonitorSummary run_monitor(const TestConfig& config, const SessionOptions& options,
                           const MonitorOptions& mo) {
  MonitorSummary summary;
  monitor::History history = monitor::History::open(mo.history);
  SessionData data;
  data.config = config;
  data.command = "monitor";
  data.link_uri = options.link_uri.empty() ? config.link.uri : options.link_uri;
  data.preset = options.preset;
  data.plant_seed = options.plant_seed;
  monitor::RunInfo info;
  info.link = data.link_uri;
  info.baseline = mo.baseline_file;
  info.preset = data.preset;
  info.seed = options.plant_seed ? static_cast<long>(*options.plant_seed) : 0;
  const long run_id = history.begin_run(info);
  auto finish = [&](int code, const std::string& outcome) {
    summary.exit_code = code;
    summary.outcome = outcome;
    history.end_run(run_id, code, outcome);
    monitor::write_monitor_report(history, options.out_dir);
    return summary;
  };
  drivers::LinkOptions lo;
  lo.response_timeout = std::chrono::milliseconds(static_cast<long>(config.link.timeout_s * 1000));
  lo.lockstep = config.link.lockstep_ticks > 0;
  lo.ramp_rate_pct_per_s = config.safety.ramp_pct_per_s;
  auto opened = drivers::open_link(data.link_uri, lo);
  if (!opened) {
    const bool usage = opened.error().kind == drivers::LinkErrorKind::kConfig;
    return finish(usage ? kExitUsage : kExitLinkFault,
                  "cannot open the link: " + opened.error().message());
  }
  drivers::GovernorLink& link = *opened.value();
  if (auto c = link.configure(); !c) {
    return finish(kExitLinkFault, "cannot configure the link: " + c.error().message());
  }
  std::unique_ptr<io::RecordingWriter> recorder;
  try {
    recorder = open_recorder(config, options, mo.keep_recording);
  } catch (const std::exception& e) {
    link.close();
    return finish(kExitSafety,
                  std::string("rig failure: cannot create the recording: ") + e.what());
  }
  const bool tty = LiveView::is_terminal(options.live_out);
  LiveView view(options.live_out, tty, config.output.live_interval_s, tty ? 0.1 : 1.0);
  RunContext ctx(data, link, *recorder, view, options);
  ctx.loop.configure_long_run(mo.keep_recording);
  for (const auto& w : drivers::link_warnings(link)) ctx.loop.event("warning", w);
  model::TransferFunction pairs_model = mo.baseline;
  pairs_model.delay_s = std::max(0.0, mo.baseline.delay_s - ctx.timing_correction_s());
  monitor::Monitor core(pairs_model, core_settings(config, mo, 0.0));
  MonitorRun run{core, history, run_id, mo, summary};
  run.seed = config.excitation.seed;
  for (const auto& r : history.runs()) {
    if (r.id == run_id) run.history_offset_s = r.offset_s;
  }
  publish_history(ctx.loop.live(), history, run_id);
  monitor_run(ctx, run, pairs_model);
  make_deactivate_phase()->run(ctx);
  view.finish();
  try {
    recorder->close();
  } catch (const std::exception&) {  // the recording is optional here; the history is kept
  }
  summary.monitored_s = ctx.loop.t_s();
  std::string outcome = data.exit_code == kExitOk ? run.stop_reason : data.outcome;
  if (outcome.empty()) outcome = "monitoring ended";
  return finish(data.exit_code, outcome);
}

}  // namespace rig::session
