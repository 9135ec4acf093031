#include "rig/session/session.hpp"

#include <fmt/format.h>

#include <chrono>

#include "drivers/open_link.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/sequencer.hpp"
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
  s.raw["y_sampled_after_s"] =
      d.config.link.lockstep_ticks > 0 ? 1.0 / d.config.link.sample_rate_hz : 0.0;
  return s;
}

// Phases in order; each returns false when the test must stop.
void run_phases(Sequencer& seq, bool sweep_only) {
  if (!seq.steady_state() || !seq.activate()) return;
  if (!seq.pilot()) return;
  if (sweep_only) {
    seq.sweep();
    return;
  }
  if (!seq.excite()) return;
  if (!seq.sweep()) return;
  seq.compare();
}

}  // namespace

SessionData run_commission(const TestConfig& config, const SessionOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  SessionData data;
  data.config = config;
  data.command = options.command;
  data.link_uri = options.link_uri.empty() ? config.link.uri : options.link_uri;
  data.preset = options.preset.empty() ? config.plant.preset : options.preset;
  data.plant_seed = options.plant_seed;
  std::filesystem::create_directories(options.out_dir);

  drivers::LinkOptions lo;
  lo.response_timeout = std::chrono::milliseconds(static_cast<long>(config.link.timeout_s * 1000));
  lo.lockstep = config.link.lockstep_ticks > 0;
  lo.ramp_rate_pct_per_s = config.safety.ramp_pct_per_s;
  auto opened = drivers::open_link(data.link_uri, lo);
  if (!opened) {
    const bool config_error = opened.error().kind == drivers::LinkErrorKind::kConfig;
    data.exit_code = config_error ? kExitConfig : kExitFault;
    data.outcome = "cannot open the link: " + opened.error().message();
    write_outputs(data, options.out_dir);
    return data;
  }
  std::unique_ptr<drivers::GovernorLink> link = std::move(opened.value());
  if (auto c = link->configure(); !c) {
    data.exit_code = kExitFault;
    data.outcome = "cannot configure the link: " + c.error().message();
    write_outputs(data, options.out_dir);
    return data;
  }
  io::RecordingWriterOptions wo;
  wo.flush_period =
      std::chrono::milliseconds(static_cast<long>(config.output.flush_interval_s * 1000));
  wo.sync_to_disk = false;  // flushed to the kernel: survives a kill -9 of the rig
  io::RecordingWriter recorder(options.out_dir / "recording.csv", recording_columns(),
                               recording_sidecar(data), wo);
  // At most 10 refreshes (terminal) or one plain line per wall-clock second.
  const bool tty = LiveView::is_terminal(options.live_out);
  LiveView view(options.live_out, tty, config.output.live_interval_s, tty ? 0.1 : 1.0);
  Sequencer seq(data, *link, recorder, view, options);
  run_phases(seq, options.command == "sweep");
  seq.finish();
  view.finish();
  recorder.close();
  data.events = seq.loop().events();
  data.trace = seq.loop().trace();
  data.max_abs_deviation_pct = seq.loop().max_abs_deviation_pct();
  data.test_time_s = seq.loop().t_s();
  data.loop_timing = seq.loop().timing().summary();
  data.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (data.outcome.empty()) {
    data.outcome = data.command == "sweep" ? std::string("swept sine complete")
                   : data.compare_sweep    ? data.compare_sweep->summary
                                           : std::string("test complete (no swept-sine check)");
  }
  write_outputs(data, options.out_dir);
  return data;
}

}  // namespace rig::session
