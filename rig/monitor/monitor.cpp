#include "rig/monitor/monitor.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rig::monitor {
namespace {

// Standardised values kept for the evidence of an alarm (the longest averaging window).
constexpr std::size_t kRecentBlocks = 15;

}  // namespace

Monitor::Monitor(const model::TransferFunction& baseline, const MonitorSettings& s)
    : s_(s),
      cu_(s.dt_s, s.coupling_rc_s),
      cy_(s.dt_s, s.coupling_rc_s),
      mmfm_(s.dt_s, s.block_samples, baseline.delay_s) {
  models_.push_back(baseline);
  const bool has_pair = dominant_pair(baseline) >= 0;
  for (const TrackedParameter& p : tracked_parameters()) {
    if (!has_pair && (p.name == "damping" || p.name == "frequency")) continue;
    params_.push_back(&p);
    models_.push_back(p.deform(baseline, p.probe));
    probes_.push_back(p.probe);
    names_.push_back(p.name);
  }
  for (const auto& n : names_) stats_.push_back(Statistic{n});
  stats_.push_back(Statistic{"residual"});
  stats_.push_back(Statistic{"line"});
  const double block_s = static_cast<double>(s.block_samples) * s.dt_s;
  // One more test: the level.
  design_ = design_cusum(s.false_alarms_per_month, block_s, static_cast<int>(stats_.size()) + 1,
                         s.cusum_k);
  for (auto& st : stats_) st.cusum = Cusum(design_);
  level_.cusum = Cusum(design_);
  u_hist_ = Eigen::VectorXd::Zero(s.warmup_samples + s.block_samples);
  y_blk_ = Eigen::VectorXd::Zero(s.block_samples);
  const auto p = static_cast<Eigen::Index>(names_.size());
  track_a_ = Eigen::MatrixXd::Zero(p, p);
  track_b_ = Eigen::VectorXd::Zero(p);
  mean_dev_.assign(names_.size(), 0.0);
  dev_sum_.assign(names_.size(), 0.0);
  dev_weight_.assign(names_.size(), 0.0);
  raw_dev_.resize(names_.size());
  raw_se_.resize(names_.size());
  ring_.assign(static_cast<std::size_t>((s.event_pre_s + s.event_post_s + 5.0) / s.dt_s), 0.0);
  ring_u_.assign(ring_.size(), 0.0);
}

std::optional<BlockReport> Monitor::push(double t_s, double u_pct, double y_kw, double speed) {
  const bool was_pending = pending_.has_value();
  observe(t_s, u_pct, y_kw);
  // A level event in progress spoils the block: it is dropped, and the coupling restarts
  // once the event has been judged (or after the new baseline).
  if (pending_ || rebaseline_) {
    restart_block();
    return std::nullopt;
  }
  if (was_pending) restart_block();
  if (!coupler_primed_) {
    cu_.reset(u_pct);
    cy_.reset(y_kw);
    coupler_primed_ = true;
  }
  const double uc = cu_.step(u_pct);
  const double yc = cy_.step(y_kw);
  u_hist_(s_.warmup_samples + in_block_) = uc;
  y_blk_(in_block_) = yc;
  mmfm_.push(uc, yc);
  if (speed > 0.0 && std::isfinite(speed)) {
    speed_sum_ += speed;
    ++speed_n_;
    speed_rpm_ = speed;
  }
  if (++in_block_ < s_.block_samples) return std::nullopt;
  BlockReport report;
  report.t_s = t_s;
  end_block(t_s, report);
  u_hist_.head(s_.warmup_samples) = u_hist_.tail(s_.warmup_samples).eval();
  in_block_ = 0;
  speed_sum_ = 0.0;
  speed_n_ = 0;
  return report;
}

void Monitor::restart_block() {
  if (in_block_ > 0 || coupler_primed_) mmfm_.reset();
  coupler_primed_ = false;
  in_block_ = 0;
  u_hist_.setZero();
  speed_sum_ = 0.0;
  speed_n_ = 0;
}

void Monitor::observe(double t_s, double u_pct, double y_kw) {
  const auto slot = static_cast<std::size_t>(sample_ % static_cast<long>(ring_.size()));
  ring_[slot] = y_kw;
  ring_u_[slot] = u_pct;
  ++sample_;
  if (pending_) {
    const long post = std::lround((s_.event_post_s + 1.0) / s_.dt_s);
    if (sample_ - pending_->detect_sample >= post) judge_event(t_s);
  } else {
    level_check(t_s, y_kw);
  }
}

std::vector<double> Monitor::block_statistics(const BlockFit& f) {
  std::vector<double> x;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    x.push_back(f.joint_se(k) > 0.0 ? (f.joint(k) - mean_dev_[i]) / f.joint_se(k) : 0.0);
  }
  x.push_back(std::log(std::max(f.fit_residual_rms_kw, 1e-9)));
  x.push_back(f.line_log_ratio);
  return x;
}

void Monitor::end_block(double t_s, BlockReport& report) {
  const double speed = speed_n_ > 0 ? speed_sum_ / static_cast<double>(speed_n_) : 0.0;
  BlockFit f;
  try {
    f = analyse_block(models_, probes_, u_hist_, y_blk_, s_.dt_s, speed);
  } catch (const std::exception& e) {
    events_.push_back({t_s, "warning", std::string("block analysis failed: ") + e.what()});
    return;
  }
  last_fit_ = f;
  const std::vector<double> x = block_statistics(f);
  report.learning = !learnt_ || recentre_left_ > 0;
  if (!learnt_ || recentre_left_ > 0) {
    learn(f, x, t_s);
  } else {
    watch(x, f, t_s);
  }
  tracked_values(f, report);
  if (const auto m = mmfm_.estimate()) {
    report.values.push_back({"mmfm_gain_kw_per_pct", m->gain, std::nullopt, std::nullopt});
    report.values.push_back({"mmfm_fn_hz", m->fn_hz, std::nullopt, std::nullopt});
    report.values.push_back({"mmfm_zeta", m->zeta, std::nullopt, std::nullopt});
  }
  level_drift(x, t_s);
  if (learnt_ && recentre_left_ == 0) sensor_block(f, t_s);
}

void Monitor::learn(const BlockFit& f, const std::vector<double>& x, double t_s) {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    dev_sum_[i] += f.joint(static_cast<Eigen::Index>(i)) /
                   std::pow(f.joint_se(static_cast<Eigen::Index>(i)), 2);
    dev_weight_[i] += 1.0 / std::pow(f.joint_se(static_cast<Eigen::Index>(i)), 2);
    raw_dev_[i].push_back(f.joint(static_cast<Eigen::Index>(i)));
    raw_se_[i].push_back(f.joint_se(static_cast<Eigen::Index>(i)));
  }
  for (std::size_t j = names_.size(); j < stats_.size(); ++j) {
    if (std::isfinite(x[j])) stats_[j].learn.push_back(x[j]);
  }
  const double block_s = static_cast<double>(s_.block_samples) * s_.dt_s;
  if (recentre_left_ > 0) {
    if (--recentre_left_ == 0) finish_learning(t_s, false);
    return;
  }
  if (static_cast<double>(++learn_blocks_) * block_s >= s_.learn_s) finish_learning(t_s, true);
}

// A mean learnt from n blocks is itself uncertain by sigma / sqrt(n): the CUSUM's reference
// value is raised by two of these standard errors, so that the designed false-alarm rate holds
// for any error of the mean within its 95 % range (h stays designed for k).
double reference_for(const CusumDesign& d, std::size_t n) {
  return d.k + 2.0 / std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1)));
}

void Monitor::finish_learning(double t_s, bool spreads) {
  centred_p0_kw_ = s_.p0_kw;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (dev_weight_[i] > 0.0) mean_dev_[i] = dev_sum_[i] / dev_weight_[i];
    stats_[i].cusum.set_reference(reference_for(design_, raw_dev_[i].size()));
    if (spreads) {
      std::vector<double> t;
      for (std::size_t k = 0; k < raw_dev_[i].size(); ++k) {
        t.push_back((raw_dev_[i][k] - mean_dev_[i]) / raw_se_[i][k]);
      }
      stats_[i].spread = learn_spread(t);
    }
    dev_sum_[i] = dev_weight_[i] = 0.0;
    raw_dev_[i].clear();
    raw_se_[i].clear();
  }
  for (std::size_t j = names_.size(); j < stats_.size(); ++j) {
    Statistic& st = stats_[j];
    // The residual and the line do not move with the operating point: after a load change
    // their means stay (only an alarm's new state re-centres them).
    if (spreads) {
      st.spread = learn_spread(st.learn);
      st.cusum.set_reference(reference_for(design_, st.learn.size()));
    } else if (!st.learn.empty() && recentre_all_) {
      double m = 0.0;
      for (double v : st.learn) m += v;
      st.spread.mean = m / static_cast<double>(st.learn.size());
      st.cusum.set_reference(reference_for(design_, st.learn.size()));
    }
    st.learn.clear();
  }
  for (auto& st : stats_) {
    st.cusum.reset();
    st.recent_z.clear();
  }
  if (spreads) {
    level_.spread = learn_spread(level_.learn);
    level_.cusum.set_reference(reference_for(design_, level_.learn.size()));
    level_.learn.clear();
    learnt_ = true;
    sec_sigma_ = learn_spread(sec_learn_).raw_sigma;
    sec_learn_.clear();
    events_.push_back({t_s, "learnt", learnt_text()});
  } else {
    events_.push_back({t_s, "re-centred", "the means now follow the new state"});
  }
}

std::string Monitor::learnt_text() const {
  std::string text = fmt::format(
      "baseline spread learnt over {} blocks; CUSUM k {:.2f} h {:.2f}: designed {:.2g} false "
      "alarms per month over {} statistics",
      learn_blocks_, design_.k, design_.h, design_.false_alarms_per_month, stats_.size() + 1);
  for (const auto& st : stats_) {
    text += fmt::format("; {} sigma {:.3g} (rho {:.2f})", st.name, st.spread.sigma, st.spread.rho);
  }
  text +=
      fmt::format("; level sigma {:.3g} kW (rho {:.2f})", level_.spread.sigma, level_.spread.rho);
  return text;
}

void Monitor::watch(const std::vector<double>& x, const BlockFit& f, double t_s) {
  std::string fired;
  int onset_blocks = 1;
  for (std::size_t j = 0; j < stats_.size(); ++j) {
    Statistic& st = stats_[j];
    const double z = std::isfinite(x[j]) && st.spread.sigma > 0.0 && std::isfinite(st.spread.sigma)
                         ? (x[j] - st.spread.mean) / st.spread.sigma
                         : std::numeric_limits<double>::quiet_NaN();
    st.recent_z.push_back(z);
    if (st.recent_z.size() > kRecentBlocks) st.recent_z.pop_front();
    if (st.cusum.update(z) != 0 && fired.empty()) {
      fired = st.name;
      onset_blocks = std::max(1, st.cusum.run_length());
    }
  }
  recent_explained_.push_back(f.explained);
  if (recent_explained_.size() > kRecentBlocks) recent_explained_.pop_front();
  if (sensor_) {  // the sensor test names what moved the level
    deferred_.reset();
    return;
  }
  if (amplitude_block(f, t_s)) return;
  if (decide_in_ > 0) {
    deferred_.reset();
    if (--decide_in_ == 0) alarm(t_s, s_.decision_blocks, "the level event's evidence");
    return;
  }
  // A crossing is confirmed one block later: a level step that has just happened shows in the
  // statistics before its event is recognised, and its event then decides instead.
  if (deferred_) {
    const auto [trigger, blocks] = *deferred_;
    deferred_.reset();
    alarm(t_s, blocks + 1, trigger);
  } else if (!fired.empty()) {
    deferred_ = std::make_pair("the CUSUM of " + fired, onset_blocks);
  }
}

}  // namespace rig::monitor
