#include "rig/session/session.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/can/can_link.hpp"
#include "drivers/open_link.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/phase.hpp"
#include "rig/session/session_outputs.hpp"

namespace rig::session {
namespace {

io::Sidecar recording_sidecar(const SessionData& d) {
  io::Sidecar s;
  s.present = true;
  s.sample_rate_hz = d.config.link.sample_rate_hz;
  s.units = {{"t", "s"},          {"u", "%"},
             {"y", "kW"},         {"speed_rpm", "rpm"},
             {"freq_hz", "Hz"},   {"status", "bits"},
             {"phase", "code"},   {"request", "%"},
             {"bias_echo", "%"},  {"plant_time_s", "s"},
             {"counter", "ticks"}};
  if (d.config.excitation.ac_coupling_rc_s > 0.0) {
    // The recorded u and y are raw; the rig applies this matched coupling to both.
    s.coupling_rc_s = d.config.excitation.ac_coupling_rc_s;
  }
  s.link = d.link_uri;
  s.preset = d.preset;
  s.seed = d.plant_seed;
  s.raw["phase_codes"] = {{"0", "steady"}, {"1", "pilot"}, {"2", "excite"}, {"3", "sweep"}};
  s.raw["rated_power_kw"] = d.config.plant.rated_power_kw;
  // When each row's y was sampled, after the row's u was written: in lockstep the rig writes
  // u and the plant answers after advancing one sample period with it; in real time the rig
  // reads the latest sample, taken before the write took effect. A model of the plant's
  // physics is aligned with the rows by this (rig diagnose; docs/decisions.md).
  s.y_sampled_after_s = d.config.link.lockstep_ticks > 0 ? 1.0 / d.config.link.sample_rate_hz : 0.0;
  return s;
}

// The phases of the test in order; `rig sweep` has no excitation and no comparison.
std::vector<std::unique_ptr<SessionPhase>> test_phases(bool sweep_only) {
  std::vector<std::unique_ptr<SessionPhase>> phases;
  phases.push_back(make_steady_state_phase());
  phases.push_back(make_activate_phase());
  phases.push_back(make_pilot_phase());
  if (!sweep_only) phases.push_back(make_excite_phase());
  phases.push_back(make_sweep_phase());
  return phases;
}

// The one loop: the phases until one stops the test, then always the ramp-down; the
// comparison only after a complete commissioning test.
void drive(RunContext& ctx, bool sweep_only) {
  bool complete = true;
  for (auto& phase : test_phases(sweep_only)) {
    if (!phase->run(ctx)) {
      complete = false;
      break;
    }
  }
  make_deactivate_phase()->run(ctx);
  if (complete && !sweep_only) make_compare_phase()->run(ctx);
}

// The loop's record, for the report.
void collect(SessionData& data, const TickLoop& loop) {
  data.events = loop.events();
  data.trace = loop.trace();
  data.max_abs_deviation_pct = loop.max_abs_deviation_pct();
  data.test_time_s = loop.t_s();
  data.loop_timing = loop.timing().summary();
  if (data.outcome.empty()) {
    data.outcome = data.command == "sweep" ? std::string("swept sine complete")
                   : data.compare_sweep    ? data.compare_sweep->summary
                                           : std::string("test complete (no swept-sine check)");
  }
}

SessionData new_session_data(const TestConfig& config, const SessionOptions& options) {
  SessionData data;
  data.config = config;
  data.command = options.command;
  data.link_uri = options.link_uri.empty() ? config.link.uri : options.link_uri;
  data.preset = options.preset.empty() ? config.plant.preset : options.preset;
  data.plant_seed = options.plant_seed;
  return data;
}

// Outputs of a run; a report that cannot be written is a failure of the rig (exit 4).
void finish_outputs(SessionData& data, const std::filesystem::path& out) {
  if (!write_outputs(data, out) && data.exit_code != kExitSafety) {
    data.exit_code = kExitSafety;
    data.outcome = "rig failure: the report could not be written into " + out.string();
  }
}

}  // namespace

SessionData run_commission(const TestConfig& config, const SessionOptions& options) {
  SessionData data = new_session_data(config, options);
  drivers::LinkOptions lo;
  lo.response_timeout = std::chrono::milliseconds(static_cast<long>(config.link.timeout_s * 1000));
  lo.lockstep = config.link.lockstep_ticks > 0;
  lo.ramp_rate_pct_per_s = config.safety.ramp_pct_per_s;
  auto opened = drivers::open_link(data.link_uri, lo);
  if (!opened) {
    const bool config_error = opened.error().kind == drivers::LinkErrorKind::kConfig;
    data.exit_code = config_error ? kExitUsage : kExitLinkFault;
    data.outcome = "cannot open the link: " + opened.error().message();
    finish_outputs(data, options.out_dir);
    return data;
  }
  return run_commission(config, options, *opened.value());
}

SessionData run_commission(const TestConfig& config, const SessionOptions& options,
                           drivers::GovernorLink& link) {
  const auto wall_start = std::chrono::steady_clock::now();
  SessionData data = new_session_data(config, options);
  if (data.link_uri.empty()) data.link_uri = link.uri();
  if (auto c = link.configure(); !c) {
    data.exit_code = kExitLinkFault;
    data.outcome = "cannot configure the link: " + c.error().message();
    finish_outputs(data, options.out_dir);
    return data;
  }
  io::RecordingWriterOptions wo;
  wo.flush_period =
      std::chrono::milliseconds(static_cast<long>(config.output.flush_interval_s * 1000));
  wo.sync_to_disk = false;  // flushed to the kernel: survives a kill -9 of the rig
  std::optional<io::RecordingWriter> recorder;
  try {
    recorder.emplace(options.out_dir / "recording.csv", recording_columns(),
                     recording_sidecar(data), wo);
  } catch (const std::exception& e) {  // nothing was written to the governor yet
    link.close();
    data.exit_code = kExitSafety;
    data.outcome = std::string("rig failure: cannot create the recording: ") + e.what();
    finish_outputs(data, options.out_dir);
    return data;
  }
  // At most 10 refreshes (terminal) or one plain line per wall-clock second.
  const bool tty = LiveView::is_terminal(options.live_out);
  LiveView view(options.live_out, tty, config.output.live_interval_s, tty ? 0.1 : 1.0);
  RunContext ctx(data, link, *recorder, view, options);
  for (const auto& w : drivers::link_warnings(link)) ctx.loop.event("warning", w);
  drive(ctx, options.command == "sweep");
  view.finish();
  try {
    recorder->close();
  } catch (const std::exception& e) {
    if (data.exit_code != kExitSafety) {
      data.exit_code = kExitSafety;
      data.outcome = std::string("rig failure: cannot write the recording: ") + e.what();
    }
    // Found only by the last write (an emulated test can outrun the recorder's flusher, or a
    // disk stall hold it): the rig failure a mid-test write trips on, the bias already back
    // at its baseline. The report names it as that trip.
    if (!data.trip)
      data.trip = TripRecord{TripCause::kRigFailure,
                             std::string("cannot write the recording (found when it was closed "
                                         "at the end of the test): ") +
                                 e.what(),
                             static_cast<std::uint64_t>(
                                 std::llround(ctx.loop.t_s() * data.config.link.sample_rate_hz))};
  }
  collect(data, ctx.loop);
  data.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  finish_outputs(data, options.out_dir);
  return data;
}

}  // namespace rig::session
