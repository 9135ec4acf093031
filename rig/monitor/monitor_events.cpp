// The monitor's events (level steps, trips), alarms and reported values (monitor.hpp).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "rig/monitor/monitor.hpp"

namespace rig::monitor {
namespace {

// Load changes that have moved P0 by more than this share since the means were last centred
// re-centre them: the thresholds are conditioned on the operating point (the swing mode's
// frequency moves with the load angle: about 0.5 % for a 4 % load change on Stornoway, many
// block sigmas).
constexpr double kOperatingPointShare = 0.01;
constexpr int kSecondsKept = 60;      // 1 s means forming the recent range
constexpr int kSecondsExcluded = 3;   // the newest ones are judged, not the range
constexpr int kLevelHits = 2;         // consecutive seconds beyond the range
constexpr double kTrackSigmas = 4.0;  // trend thresholds: 4 sigma of the estimate

std::string series_name(const TrackedParameter& p) {
  std::string unit = p.unit == "%" ? "pct" : p.unit;
  std::transform(unit.begin(), unit.end(), unit.begin(), ::tolower);
  return p.name + "_" + unit;
}

}  // namespace

std::vector<double> Monitor::ring_copy(const std::vector<double>& ring) const {
  const long n = static_cast<long>(ring.size());
  const long len = std::min(sample_, n);
  std::vector<double> x(static_cast<std::size_t>(len));
  for (long i = 0; i < len; ++i) {
    x[static_cast<std::size_t>(i)] = ring[static_cast<std::size_t>((sample_ - len + i) % n)];
  }
  return x;
}

std::vector<double> Monitor::event_record() const {
  std::vector<double> y = ring_copy(ring_);
  const std::vector<double> u = ring_copy(ring_u_);
  if (y.empty()) return y;
  const Eigen::VectorXd response = model::simulate(
      models_[0], Eigen::Map<const Eigen::VectorXd>(u.data(), static_cast<Eigen::Index>(u.size())),
      s_.dt_s);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] -= response(static_cast<Eigen::Index>(i));
  return y;
}

void Monitor::level_check(double t_s, double y_kw) {
  sec_sum_ += y_kw;
  if (++sec_n_ < std::lround(1.0 / s_.dt_s)) return;
  const double m = sec_sum_ / static_cast<double>(sec_n_);
  sec_sum_ = 0.0;
  sec_n_ = 0;
  if (static_cast<int>(sec_means_.size()) >= kSecondsKept) {
    double ref = 0.0;
    const int k = kSecondsKept - kSecondsExcluded;
    for (int i = 0; i < k; ++i) ref += sec_means_[static_cast<std::size_t>(i)];
    ref /= k;
    const double dev = m - ref;
    if (!learnt_) {
      sec_learn_.push_back(dev);
    } else {
      const double thr =
          std::max(s_.level_sigmas * sec_sigma_, s_.min_level_pct / 100.0 * s_.p0_kw);
      level_hits_ = std::abs(dev) > thr ? level_hits_ + 1 : 0;
      if (level_hits_ >= kLevelHits) {
        pending_ = Pending{sample_, t_s, false};
        forget_recent_block();
        events_.push_back(
            {t_s, "level", fmt::format("measured power left its recent range by {:+.1f} kW", dev)});
        level_hits_ = 0;
      }
    }
    sec_means_.pop_front();
  }
  sec_means_.push_back(m);
}

void Monitor::trip(double t_s) {
  pending_ = Pending{sample_, t_s, true};
  level_hits_ = 0;
  forget_recent_block();
}

// The block that ended just before an event was recognised may hold its start: its
// standardised values are dropped and the sums restart, so only the event decides.
void Monitor::forget_recent_block() {
  deferred_.reset();
  for (auto& st : stats_) {
    st.cusum.reset();
    if (!st.recent_z.empty()) st.recent_z.pop_back();
  }
  if (!recent_explained_.empty()) recent_explained_.pop_back();
}

void Monitor::judge_event(double t_s) {
  const Pending p = *pending_;
  pending_.reset();
  const std::vector<double> raw = event_record();
  const long base = sample_ - static_cast<long>(raw.size());
  const long det = p.detect_sample - base;
  auto n = [this](double s) { return std::lround(s / s_.dt_s); };
  ShapeThresholds th;
  th.min_change_kw = 0.5 * s_.min_level_pct / 100.0 * s_.p0_kw;
  // One engine cycle (two revolutions) averaged out: a missing cylinder's ripple would
  // otherwise dominate every feature; the jump then needs the cycle to show.
  const double cycle_s = speed_rpm_ > 0.0 ? 120.0 / speed_rpm_ : 0.0;
  const std::vector<double> x = cycle_average(raw, n(cycle_s));
  th.jump_s += cycle_s;
  event_line_z_ = event_line_z(raw);
  // A trip follows its onset within seconds; a level event is recognised kLevelHits + 1 s
  // after it at most.
  const EventShape e =
      classify_shape(x, s_.dt_s, det - n(p.trip ? 6.0 : kLevelHits + 2.0), det + n(0.5), th);
  const std::string sizes =
      fmt::format("jump {:+.1f} kW in 0.1 s, extreme {:+.1f} kW, final {:+.1f} kW", e.jump_kw,
                  e.extreme_kw, e.final_kw);
  const double onset_t = t_s - static_cast<double>(x.size() - 1 - e.onset) * s_.dt_s;
  rebaseline_ = p.trip;
  switch (e.kind) {
    case ShapeKind::kLevelChange:
      events_.push_back({onset_t, "load change",
                         "the level moved through the plant's dynamics "
                         "and stayed: a load change, " +
                             sizes});
      rebaseline_ = true;
      load_changed_ = true;
      last_load_event_s_ = onset_t;
      break;
    case ShapeKind::kSensorStep:
    case ShapeKind::kPowerLossRecovered: {
      shape_ = e;
      const double before = s_.p0_kw;
      shape_level_ratio_ = before > 0.0 ? e.final_kw / before : 0.0;
      if (e.kind == ShapeKind::kSensorStep) {
        sensor_.emplace(before, s_.decision_blocks);  // the level before the step
      } else {
        decide_in_ = s_.decision_blocks;
      }
      rebaseline_ = rebaseline_ || e.kind == ShapeKind::kSensorStep;
      events_.push_back({onset_t, e.kind == ShapeKind::kSensorStep ? "sensor step" : "power loss",
                         std::string(to_string(e.kind)) + ": " + sizes});
      // A recovered power loss with the half-order line is named at once: no block of
      // excitation is needed (nor possible while the ripple keeps the power out of band).
      if (learnt_ && e.kind == ShapeKind::kPowerLossRecovered && event_line_z_ >= kSignificantZ) {
        alarm(t_s, 1, "the event's shape and the engine-order line");
      }
      break;
    }
    case ShapeKind::kSlowDrift:  // not a shape of an event record
    case ShapeKind::kUnclear:
      events_.push_back({onset_t, "unclear event", "no clear shape: " + sizes});
      break;
  }
}

void Monitor::resume(double p0_kw) {
  s_.p0_kw = p0_kw;
  restart_block();
  rebaseline_ = false;
  level_ref_kw_ = p0_kw;
  level_.cusum.reset();
  sec_means_.clear();
  sec_sum_ = 0.0;
  sec_n_ = 0;
  level_hits_ = 0;
  if (load_changed_ && learnt_ &&
      std::abs(p0_kw - centred_p0_kw_) > kOperatingPointShare * centred_p0_kw_) {
    recentre_left_ = s_.recentre_blocks;  // thresholds conditioned on the new operating point
    recentre_all_ = false;
  }
  load_changed_ = false;
}

std::vector<AlarmRecord> Monitor::take_alarms() {
  std::vector<AlarmRecord> out;
  out.swap(alarms_);
  return out;
}

std::vector<MonitorEvent> Monitor::take_events() {
  std::vector<MonitorEvent> out;
  out.swap(events_);
  return out;
}

Evidence Monitor::evidence(int blocks) const {
  Evidence ev;
  const auto m = static_cast<std::size_t>(std::clamp(blocks, 1, 15));
  auto mean_z = [m](const std::deque<double>& z) {
    double s = 0.0;
    int c = 0;
    for (std::size_t i = z.size() > m ? z.size() - m : 0; i < z.size(); ++i) {
      if (std::isfinite(z[i])) {
        s += z[i];
        ++c;
      }
    }
    return c > 0 ? s / std::sqrt(static_cast<double>(c)) : 0.0;
  };
  for (std::size_t i = 0; i < names_.size(); ++i) ev.z[names_[i]] = mean_z(stats_[i].recent_z);
  ev.z_residual = mean_z(stats_[names_.size()].recent_z);
  ev.z_line = mean_z(stats_[names_.size() + 1].recent_z);
  if (!recent_explained_.empty()) {
    Eigen::VectorXd share = Eigen::VectorXd::Zero(recent_explained_.back().size());
    const std::size_t from = recent_explained_.size() > m ? recent_explained_.size() - m : 0;
    for (std::size_t i = from; i < recent_explained_.size(); ++i) share += recent_explained_[i];
    Eigen::Index best = 0;
    share.maxCoeff(&best);
    ev.isolated = names_[static_cast<std::size_t>(best)];
  }
  for (std::size_t i = 0; i < names_.size(); ++i) ev.deviation[names_[i]] = tracked_display_[i];
  ev.shape = shape_;
  ev.level_ratio = shape_level_ratio_;
  ev.sensor_z_gain = sensor_z_gain_;
  ev.sensor_z_offset = sensor_z_offset_;
  ev.amplitude_z = amp_z_;
  if (shape_) ev.z_line = std::max(ev.z_line, event_line_z_);
  return ev;
}

std::string evidence_json(const Evidence& ev, const Diagnosis& d, const std::string& trigger) {
  nlohmann::json j;
  j["trigger"] = trigger;
  j["z"] = ev.z;
  j["deviation"] = ev.deviation;
  j["isolated"] = ev.isolated;
  j["z_residual"] = ev.z_residual;
  j["z_line"] = ev.z_line;
  if (ev.shape) {
    j["event"] = {{"shape", to_string(ev.shape->kind)},
                  {"jump_kw", ev.shape->jump_kw},
                  {"extreme_kw", ev.shape->extreme_kw},
                  {"final_kw", ev.shape->final_kw},
                  {"level_ratio", ev.level_ratio}};
  }
  for (const auto& [cause, score] : d.scores) j["scores"][cause] = score;
  return j.dump();
}

// Causes a phase lag may stand for; the amplitude test tells them apart before naming.
bool lag_cause(const std::string& cause) {
  return cause == "actuator wear (backlash)" || cause == "fuel dead time or combustion lag change";
}

// One block of a running amplitude test; true while it runs (the block is its own).
bool Monitor::amplitude_block(const BlockFit& f, double t_s) {
  if (!amp_) return false;
  deferred_.reset();
  const auto it = std::find(names_.begin(), names_.end(), "gain");
  if (it == names_.end()) {
    amp_.reset();
    return false;
  }
  const auto i = static_cast<std::size_t>(it - names_.begin());
  const auto k = static_cast<Eigen::Index>(i);
  const double c = std::isfinite(stats_[i].spread.sigma) ? stats_[i].spread.sigma : 1.0;
  amp_->add(f.joint(k) - mean_dev_[i], c * f.joint_se(k));
  if (!amp_->done()) return true;
  amp_z_ = amp_->z();
  events_.push_back(
      {t_s, "amplitude test",
       fmt::format("gain deviation {:+.2f} % at {:g} x the excitation, {:+.2f} % "
                   "at full: z {:.1f} ({})",
                   1e2 * amp_->low(), AmplitudeTest::kLowScale, 1e2 * amp_->high(), amp_z_,
                   amp_z_ >= AmplitudeTest::kPlayZ ? "amplitude-dependent: play"
                                                   : "independent of amplitude")});
  const AmplitudeTest done = *amp_;
  amp_.reset();
  alarm(t_s, done.onset_blocks(), done.trigger() + " and the amplitude test");
  return true;
}

void Monitor::alarm(double t_s, int blocks, const std::string& trigger) {
  const Evidence ev = evidence(blocks);
  Diagnosis d = diagnose(ev);
  if (lag_cause(d.cause) && !std::isfinite(amp_z_) && latched_.count(d.cause) == 0) {
    amp_.emplace(trigger, blocks);  // named once the amplitude test has run
    return;
  }
  if (d.cause.empty()) {
    d.cause = "unnamed change";
    d.fault_class = "unknown";
    d.check = "the statistic that moved (evidence) against recent maintenance or operation";
  }
  const double block_s = static_cast<double>(s_.block_samples) * s_.dt_s;
  if (latched_.count(d.cause) == 0) {
    AlarmRecord a;
    a.t_s = t_s;
    a.cause = d.cause;
    a.fault_class = d.fault_class;
    a.confidence = d.confidence;
    a.onset_s = t_s - blocks * block_s;
    a.check = d.check;
    a.evidence_json = evidence_json(ev, d, trigger);
    alarms_.push_back(a);
    latched_.insert(d.cause);
    ++alarm_count_;
  } else {
    events_.push_back({t_s, "still", d.cause + " (already alarmed; " + trigger + ")"});
  }
  // The new state becomes the reference for further changes.
  recentre_left_ = s_.recentre_blocks;
  recentre_all_ = true;
  shape_.reset();
  shape_level_ratio_ = 0.0;
  decide_in_ = -1;
  sensor_.reset();
  sensor_z_gain_ = sensor_z_offset_ = NAN;
  amp_z_ = NAN;
  for (auto& st : stats_) st.cusum.reset();
  level_.cusum.reset();
}

void Monitor::tracked_values(const BlockFit& f, BlockReport& report) {
  const double lambda = s_.tracking_forgetting;
  track_a_ = lambda * track_a_ + f.normal;
  track_b_ = lambda * track_b_ + f.rhs;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(track_a_);
  const Eigen::VectorXd d = ldlt.solve(track_b_);
  const Eigen::VectorXd var =
      ldlt.solve(Eigen::MatrixXd::Identity(track_a_.rows(), track_a_.cols())).diagonal();
  tracked_display_.resize(names_.size());
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    const TrackedParameter& p = *params_[i];
    const double dev = d(k) - mean_dev_[i];
    tracked_display_[i] = p.display(dev);
    SeriesValue v{series_name(p), p.display(dev), std::nullopt, std::nullopt};
    if (learnt_ && std::isfinite(stats_[i].spread.sigma)) {
      const double thr = kTrackSigmas * stats_[i].spread.sigma * f.fit_residual_rms_kw *
                         std::sqrt(std::max(0.0, var(k)));
      v.lo = p.display(-thr);
      v.hi = p.display(thr);
    }
    report.values.push_back(v);
  }
  double cusum = 0.0;
  for (const auto& st : stats_) cusum = std::max(cusum, st.cusum.level());
  report.values.push_back({"residual_kw", f.fit_residual_rms_kw, std::nullopt, std::nullopt});
  report.values.push_back({"response_kw", f.response_rms_kw, std::nullopt, std::nullopt});
  report.values.push_back({"line_ratio_db", 10.0 * f.line_log_ratio, std::nullopt, std::nullopt});
  report.values.push_back({"cusum_max", cusum, std::nullopt, design_.h});
  const std::vector<double> x = ring_copy(ring_);
  const std::size_t n = std::min<std::size_t>(x.size(), static_cast<std::size_t>(s_.block_samples));
  double level = 0.0;
  for (std::size_t i = x.size() - n; i < x.size(); ++i) level += x[i];
  block_level_kw_ = n > 0 ? level / static_cast<double>(n) : 0.0;
  report.values.push_back({"level_kw", block_level_kw_, std::nullopt, std::nullopt});
}

// The sensor test's block: the gain's joint deviation against the learnt mean, its standard
// error calibrated by the learnt spread, and the block's level.
void Monitor::sensor_block(const BlockFit& f, double t_s) {
  if (!sensor_ || names_.empty() || names_[0] != "gain") return;
  const double c = std::isfinite(stats_[0].spread.sigma) ? stats_[0].spread.sigma : 1.0;
  sensor_->add(block_level_kw_, f.joint(0) - mean_dev_[0], c * f.joint_se(0));
  if (!sensor_->decided()) return;
  sensor_z_gain_ = sensor_->z_gain();
  sensor_z_offset_ = sensor_->z_offset();
  events_.push_back({t_s, "sensor test",
                     fmt::format("level moved {:+.2f} %, gain {:+.2f} % over {} blocks: "
                                 "P(gain error) {:.2f}",
                                 100.0 * sensor_->ratio(), 100.0 * sensor_->gain(),
                                 sensor_->blocks(), sensor_->p_gain())});
  const int blocks = sensor_->blocks();
  alarm(t_s, blocks, "the sensor test");
  rebaseline_ = true;  // the level moved: a new P0 for the band
}

double Monitor::event_line_z(const std::vector<double>& record) const {
  const Statistic& line = stats_.back();
  const auto n = static_cast<std::size_t>(s_.block_samples);
  if (!learnt_ || speed_rpm_ <= 0.0 || record.size() < n || !(line.spread.sigma > 0.0)) {
    return 0.0;
  }
  const Eigen::Map<const Eigen::VectorXd> tail(record.data() + record.size() - n,
                                               static_cast<Eigen::Index>(n));
  const double r = line_log_ratio(tail, s_.dt_s, speed_rpm_ / 120.0);
  return std::isfinite(r) ? (r - line.spread.mean) / line.spread.sigma : 0.0;
}

// The level CUSUM on block means against the baseline's level: a drift with no load event
// in memory is a sensor's (named with the transfer function's evidence); with one, the load's.
void Monitor::level_drift(const std::vector<double>& /*x*/, double t_s) {
  const double dev = block_level_kw_ - level_ref_kw_;
  if (!learnt_) {
    level_.learn.push_back(dev);
    return;
  }
  if (recentre_left_ > 0 || decide_in_ > 0 || sensor_ || pending_ || rebaseline_) return;
  const double z = (dev - level_.spread.mean) / level_.spread.sigma;
  if (!std::isfinite(z) || level_.cusum.update(z) == 0) return;
  if (t_s - last_load_event_s_ < s_.load_event_memory_s) {
    events_.push_back({t_s, "load change",
                       fmt::format("the level drifted by {:+.1f} kW after a "
                                   "load change: a slow load move",
                                   dev)});
    last_load_event_s_ = t_s;
    load_changed_ = true;
  } else {
    EventShape e;
    e.kind = ShapeKind::kSlowDrift;
    e.final_kw = dev;
    shape_ = e;
    shape_level_ratio_ = level_ref_kw_ > 0.0 ? dev / level_ref_kw_ : 0.0;
    events_.push_back({t_s, "drift",
                       fmt::format("the measured level drifted by {:+.1f} kW with "
                                   "no load event",
                                   dev)});
    // Named by the sensor test once the transfer function's gain tells gain from offset.
    sensor_.emplace(level_ref_kw_, s_.decision_blocks);
    return;
  }
  rebaseline_ = true;
}

}  // namespace rig::monitor
