#include "rig/session/online_mmfm.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rig/session/thread_priority.hpp"

namespace rig::session {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

signal::StreamingOptions streaming(const OnlineMmfmOptions& o) {
  signal::StreamingOptions s;
  s.correlator = o.correlator;
  s.block_samples = o.block_samples;
  s.averaging = o.exponential ? signal::Averaging::kExponential : signal::Averaging::kCumulative;
  s.weight = o.weight;
  return s;
}

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// Covariance of [a_n..a_0, b_m..b_0] (a_n = 1 fixed: zero row and column) from the asymptotic
// one of [a_{n-1}..a_0, b_m..b_0 (, Td)], and the delay's standard error.
std::pair<Eigen::MatrixXd, double> parameter_covariance(const ident::OrderCandidate& c,
                                                        bool delay_estimated) {
  const Eigen::Index p = c.order.n + c.order.m + 1;
  Eigen::MatrixXd full = Eigen::MatrixXd::Zero(p + 1, p + 1);
  full.bottomRightCorner(p, p) = c.covariance.topLeftCorner(p, p);
  const double delay_sd = delay_estimated ? std::sqrt(std::max(0.0, c.covariance(p, p))) : 0.0;
  return {full, delay_sd};
}

}  // namespace

OnlineMmfm::OnlineMmfm(const OnlineMmfmOptions& options)
    : options_(options), main_(streaming(options)) {
  if (options_.orders.empty()) options_.orders = {options_.order};
  if (options_.compare_freqs_hz.empty())
    options_.compare_freqs_hz = ident::log_frequencies_hz(0.5, 5.0, 24);
  if (options.ac_coupling_rc_s > 0.0) {
    couple_u_.emplace(options.correlator.dt_s, options.ac_coupling_rc_s);
    couple_y_.emplace(options.correlator.dt_s, options.ac_coupling_rc_s);
  }
}

ident::OrderChoiceOptions OnlineMmfm::choice_options() const {
  ident::OrderChoiceOptions c;
  c.orders = options_.orders;
  c.delay_s = options_.delay_s;
  c.compare_freqs_hz = options_.compare_freqs_hz;
  c.prior = options_.prior;
  return c;
}

std::optional<BlockEstimate> OnlineMmfm::push(double u_pct, double y_kw) {
  if (couple_u_) {
    if (!coupler_primed_) {
      // Settled networks: a constant operating point gives zero output from the start.
      couple_u_->reset(u_pct);
      couple_y_->reset(y_kw);
      coupler_primed_ = true;
    }
    u_pct = couple_u_->step(u_pct);
    y_kw = couple_y_->step(y_kw);
  }
  main_.push(u_pct, y_kw);
  u_.push_back(u_pct);
  y_.push_back(y_kw);
  if (++in_block_ >= options_.block_samples) {
    in_block_ = 0;
    ++blocks_done_;
    if (options_.exponential) {
      // Keep the effective length of the exponential average, trimmed a block at a time.
      const auto keep = static_cast<std::size_t>((2.0 * options_.weight - 1.0) *
                                                 static_cast<double>(options_.block_samples));
      if (u_.size() > keep + static_cast<std::size_t>(options_.block_samples)) {
        const auto drop = static_cast<std::ptrdiff_t>(u_.size() - keep);
        u_.erase(u_.begin(), u_.begin() + drop);
        y_.erase(y_.begin(), y_.begin() + drop);
      }
    }
    pending_ = snapshot();
    if (!options_.asynchronous) {
      const Snapshot s = std::move(*pending_);
      pending_.reset();
      history_.push_back(refresh(s));
      return history_.back();
    }
  }
  if (!options_.asynchronous) return std::nullopt;
  std::optional<BlockEstimate> done;
  if (job_.valid() && job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    done = collect();
  }
  if (!job_.valid() && pending_) launch();
  return done;
}

OnlineMmfm::Snapshot OnlineMmfm::snapshot() const {
  Snapshot s;
  s.block = blocks_done_;
  s.t_s = static_cast<double>(main_.samples()) * options_.correlator.dt_s;
  s.ruu = main_.ruu();
  s.ryu = main_.ryu();
  s.u = to_vector(u_);
  s.y = to_vector(y_);
  return s;
}

void OnlineMmfm::launch() {
  job_ = std::async(std::launch::async, [this, s = std::move(*pending_)]() {
    use_normal_priority();  // started by the realtime loop's thread
    return refresh(s);
  });
  pending_.reset();
}

const BlockEstimate& OnlineMmfm::collect() {
  history_.push_back(job_.get());
  return history_.back();
}

void OnlineMmfm::finish() {
  while (job_.valid() || pending_) {
    if (!job_.valid()) launch();
    collect();
  }
  // The final estimate covers every sample, also those after the last whole block, and
  // starts cold (MMFM for every order) so that it does not depend on which blocks the
  // worker happened to see.
  if (blocks_done_ > 0) {
    warm_.clear();
    (void)refresh(snapshot());
  }
}

// Runs on the worker in asynchronous mode: touches only the snapshot, the warm-start state,
// the latest choice and the (constant) options.
BlockEstimate OnlineMmfm::refresh(const Snapshot& s) {
  BlockEstimate e;
  e.block = s.block;
  e.t_s = s.t_s;
  e.band_db95 = e.band_deg95 = e.fit_pct = kNaN;
  try {
    ident::OrderChoice choice = ident::choose_order(s.u, s.y, options_.correlator.dt_s, s.ruu,
                                                    s.ryu, choice_options(), warm_);
    for (const auto& c : choice.candidates) {
      if (!c.ok) continue;
      if (c.order == model::ModelOrder{2, 0}) {
        e.derived =
            ident::derived_figures(c.model, parameter_covariance(c, !options_.delay_s).first);
      }
    }
    warm_ = choice.candidates;
    const ident::OrderCandidate* best = choice.best();
    if (best == nullptr) {
      e.error = choice.candidates.front().error;
      last_choice_ = std::move(choice);
      return e;
    }
    const auto [cov, delay_sd] = parameter_covariance(*best, !options_.delay_s);
    e.model = best->model;
    e.order = best->order;
    e.parameters = ident::parameter_table(best->model, cov, delay_sd);
    e.delay_s = best->model.delay_s;
    e.band_db95 = best->width.db;
    e.band_deg95 = best->width.deg;
    e.fit_pct = best->fit_pct;
    e.ok = true;
    last_choice_ = std::move(choice);
  } catch (const std::exception& ex) {
    e.error = ex.what();
  }
  return e;
}

bool OnlineMmfm::converged() const {
  if (history_.empty()) return false;
  const auto& last = history_.back();
  return last.ok && last.band_db95 <= options_.target_db && last.band_deg95 <= options_.target_deg;
}

ident::MmfmResult OnlineMmfm::final_result() const {
  if (job_.valid() || pending_) {
    throw std::logic_error("online MMFM: final_result() before finish()");
  }
  if (blocks_done_ == 0 || !last_choice_) {
    throw std::invalid_argument("online MMFM: no excitation block was completed");
  }
  const ident::OrderCandidate* best = last_choice_->best();
  if (best == nullptr) {
    throw std::invalid_argument("online MMFM: no model structure could be fitted: " +
                                last_choice_->candidates.front().error);
  }
  ident::MmfmOptions m;
  m.order = best->order;
  m.delay_s = best->model.delay_s;
  const signal::Correlation ruu = main_.ruu(), ryu = main_.ryu();
  ident::MmfmResult r = ident::estimate_mmfm(ruu, ryu, m);  // settings and equations
  const bool delay_estimated = !options_.delay_s.has_value();
  const auto [cov, delay_sd] = parameter_covariance(*best, delay_estimated);
  r.model = best->model;
  r.covariance = cov;
  r.delay_s = best->model.delay_s;
  r.delay_std_s = delay_sd;
  r.parameters = ident::parameter_table(r.model, cov, delay_sd);
  r.derived = ident::derived_figures(r.model, cov);
  r.model_ryu = ident::model_cross_correlation(r.model, ruu, ryu);
  r.correlation_fit_pct = model::fit_percent(ryu.r, r.model_ryu.r);
  r.refined = true;
  return r;
}

}  // namespace rig::session
