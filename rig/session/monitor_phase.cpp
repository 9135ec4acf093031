#include "rig/session/monitor_phase.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

namespace rig::session {
namespace {

constexpr long kChunkSamples = 6000;  // excitation generated a minute at a time (bounded)

void print_alarm(std::FILE* out, const monitor::AlarmRecord& a) {
  if (out == nullptr) return;
  nlohmann::json j = {{"type", "alarm"},  {"t_s", a.t_s},           {"onset_s", a.onset_s},
                      {"cause", a.cause}, {"class", a.fault_class}, {"confidence", a.confidence},
                      {"check", a.check}};
  j["evidence"] = nlohmann::json::parse(a.evidence_json, nullptr, false);
  std::fprintf(out, "%s\n", j.dump().c_str());
  std::fflush(out);
}

void show_values(RunContext& ctx, const monitor::BlockReport& r, long alarms) {
  auto& est = ctx.loop.status().estimates;
  est.clear();
  for (const auto& v : r.values) {
    if (v.name == "gain_db" || v.name == "damping_pct" || v.name == "delay_ms") {
      est.push_back({v.name, v.value, 0.0});
    }
  }
  ctx.loop.status().flags.clear();
  if (r.learning) ctx.loop.status().flags.push_back("learning");
  if (alarms > 0) ctx.loop.status().flags.push_back(fmt::format("{} alarm(s)", alarms));
}

class MonitorPhase final : public SupervisedPhase {
 public:
  explicit MonitorPhase(MonitorRun& run) : run_(run) {}
  const char* name() const override { return "monitor"; }

 protected:
  Phase code() const override { return Phase::kMonitor; }

  std::optional<double> request(RunContext& ctx, long k) override {
    if (ctx.loop.abort_requested()) {
      run_.stop_reason = "stopped by the operator";
      return std::nullopt;
    }
    const double duration = run_.options.duration_s;
    if (duration > 0.0 && ctx.loop.t_s() >= duration) {
      run_.stop_reason = fmt::format("monitored for the requested {:g} s", duration);
      return std::nullopt;
    }
    if (run_.core.wants_rebaseline()) return std::nullopt;
    const long j = k % kChunkSamples;
    if (j == 0 || e_.size() == 0) {
      e_ = test_excitation(ctx.config, kChunkSamples, run_.sigma_pct, run_.seed + run_.chunk++);
    }
    return e_(j) * run_.core.excitation_scale();
  }

  void consume(RunContext& ctx, const TickResult& r, long /*k*/) override {
    const drivers::Sample& s = *r.sample;
    const auto report = run_.core.push(r.t_s, r.out.excitation_pct, s.power_kw, s.speed_rpm);
    run_.publish(ctx, report ? &*report : nullptr);
  }

  void observe(RunContext& /*ctx*/, const TickResult& r) override {
    if (r.sample) run_.core.observe(r.t_s, r.out.excitation_pct, r.sample->power_kw);
  }

  bool conclude(RunContext& /*ctx*/, bool completed) override { return completed; }

 private:
  MonitorRun& run_;
  Eigen::VectorXd e_;
};

}  // namespace

void MonitorRun::publish(RunContext& ctx, const monitor::BlockReport* report) {
  if (report != nullptr) {
    history.add_values(run_id, report->t_s, report->values);
    show_values(ctx, *report, summary.alarms);
  }
  for (const auto& a : core.take_alarms()) {
    history.add_alarm(run_id, a);
    ++summary.alarms;
    print_alarm(options.alarms_out, a);
    ctx.loop.event("alarm", fmt::format("{} ({}, confidence {:.2f}): check {}", a.cause,
                                        a.fault_class, a.confidence, a.check));
    ctx.view.message(fmt::format("ALARM at {:.0f} s: {} ({})", a.t_s, a.cause, a.fault_class));
  }
  for (const auto& e : core.take_events()) {
    history.add_event(run_id, e.t_s, e.kind, e.text);
    ++summary.events;
    if (e.kind != "still") ctx.view.message(fmt::format("{:.0f} s {}: {}", e.t_s, e.kind, e.text));
  }
}

std::unique_ptr<SessionPhase> make_monitor_phase(MonitorRun& run) {
  return std::make_unique<MonitorPhase>(run);
}

}  // namespace rig::session
