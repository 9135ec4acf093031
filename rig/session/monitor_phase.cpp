#include "rig/session/monitor_phase.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

namespace rig::session {
namespace {

constexpr long kChunkSamples = 6000;  // excitation generated a minute at a time (bounded)

nlohmann::json alarm_json(const monitor::AlarmRecord& a) {
  nlohmann::json j = {{"type", "alarm"},  {"t_s", a.t_s},           {"onset_s", a.onset_s},
                      {"cause", a.cause}, {"class", a.fault_class}, {"confidence", a.confidence},
                      {"check", a.check}};
  j["evidence"] = nlohmann::json::parse(a.evidence_json, nullptr, false);
  return j;
}

void print_alarm(std::FILE* out, const nlohmann::json& alarm) {
  if (out == nullptr) return;
  std::fprintf(out, "%s\n", alarm.dump().c_str());
  std::fflush(out);
}

// One block's tracked values with their alarm thresholds, on the history's time axis.
nlohmann::json trend_json(const monitor::BlockReport& r, double history_offset_s) {
  nlohmann::json values = nlohmann::json::array();
  for (const auto& v : r.values) {
    values.push_back(
        {{"name", v.name},
         {"value", std::isfinite(v.value) ? nlohmann::json(v.value) : nlohmann::json()},
         {"lo", v.lo ? nlohmann::json(*v.lo) : nlohmann::json()},
         {"hi", v.hi ? nlohmann::json(*v.hi) : nlohmann::json()}});
  }
  return {{"t_s", r.t_s},
          {"history_s", history_offset_s + r.t_s},
          {"learning", r.learning},
          {"values", values}};
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
    ctx.loop.live().publish(live::kind::kTrend, trend_json(*report, history_offset_s));
  }
  for (const auto& a : core.take_alarms()) {
    history.add_alarm(run_id, a);
    ++summary.alarms;
    const nlohmann::json alarm = alarm_json(a);
    print_alarm(options.alarms_out, alarm);
    ctx.loop.live().publish(live::kind::kAlarm, alarm);
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

void publish_history(const LivePublisher& live, const monitor::History& history, long run_id) {
  if (!live.on()) return;
  constexpr std::size_t kPointsPerSeries = 2000;  // a page draws months of history quickly
  for (const auto& name : history.series_names()) {
    nlohmann::json x = nlohmann::json::array(), v = nlohmann::json::array(),
                   lo = nlohmann::json::array(), hi = nlohmann::json::array();
    for (const auto& p : history.series(name, kPointsPerSeries)) {
      if (p.run_id == run_id) continue;
      x.push_back(p.history_s);
      v.push_back(std::isfinite(p.value) ? nlohmann::json(p.value) : nlohmann::json());
      lo.push_back(p.lo ? nlohmann::json(*p.lo) : nlohmann::json());
      hi.push_back(p.hi ? nlohmann::json(*p.hi) : nlohmann::json());
    }
    if (x.empty()) continue;
    live.publish(live::kind::kTrendHistory,
                 {{"name", name}, {"history_s", x}, {"value", v}, {"lo", lo}, {"hi", hi}});
  }
  for (const auto& a : history.alarms()) {
    if (a.run_id == run_id) continue;
    nlohmann::json j = alarm_json(a.alarm);
    j["history_s"] = a.history_s;
    j["earlier_run"] = a.run_id;
    live.publish(live::kind::kAlarmHistory, j);  // not new: the fleet feed leaves it out
  }
}

std::unique_ptr<SessionPhase> make_monitor_phase(MonitorRun& run) {
  return std::make_unique<MonitorPhase>(run);
}

}  // namespace rig::session
