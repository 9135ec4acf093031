#include "rig/session/online_mmfm.hpp"
#include "rig/session/thread_priority.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rig::session {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kMinSpreadBlocks = 3;

signal::StreamingOptions streaming(const OnlineMmfmOptions& o, bool per_block) {
  signal::StreamingOptions s;
  s.correlator = o.correlator;
  s.block_samples = o.block_samples;
  if (per_block) {
    s.averaging = signal::Averaging::kExponential;
    s.weight = 1.0;  // R <- R_new: the last block alone
  } else {
    s.averaging = o.exponential ? signal::Averaging::kExponential : signal::Averaging::kCumulative;
    s.weight = o.weight;
  }
  return s;
}

// Robust spread of each component over the blocks: 1.4826 * median |x - median(x)| (equal
// to the standard deviation for Gaussian scatter), so that one block spoilt by a transient
// does not dominate the standard errors.
template <class V>
V robust_std(const std::vector<V>& xs) {
  V out = xs.front();
  std::vector<double> col(xs.size());
  for (Eigen::Index j = 0; j < out.size(); ++j) {
    for (std::size_t b = 0; b < xs.size(); ++b) col[b] = xs[b](j);
    const auto mid = col.begin() + static_cast<std::ptrdiff_t>(col.size() / 2);
    std::nth_element(col.begin(), mid, col.end());
    const double median = *mid;
    for (double& c : col) c = std::abs(c - median);
    std::nth_element(col.begin(), mid, col.end());
    out(j) = 1.4826 * *mid;
  }
  return out;
}

}  // namespace

OnlineMmfm::OnlineMmfm(const OnlineMmfmOptions& options)
    : options_(options), main_(streaming(options, false)), block_(streaming(options, true)) {
  if (options.ac_coupling_rc_s > 0.0) {
    couple_u_.emplace(options.correlator.dt_s, options.ac_coupling_rc_s);
    couple_y_.emplace(options.correlator.dt_s, options.ac_coupling_rc_s);
  }
}

ident::MmfmOptions OnlineMmfm::mmfm_options() const {
  ident::MmfmOptions m;
  m.order = options_.order;
  m.delay_s = options_.delay_s;
  return m;
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
  block_.push(u_pct, y_kw);
  if (++in_block_ >= options_.block_samples) {
    in_block_ = 0;
    if (!pending_) pending_.emplace();
    pending_->block = ++blocks_done_;
    pending_->t_s = static_cast<double>(main_.samples()) * options_.correlator.dt_s;
    pending_->ruu = main_.ruu();
    pending_->ryu = main_.ryu();
    pending_->blocks.emplace_back(block_.ruu(), block_.ryu());
    if (!options_.asynchronous) {
      const Snapshot s = std::move(*pending_);
      pending_.reset();
      history_.push_back(refresh(s));
      spread_blocks_ = block_thetas_.size();
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

void OnlineMmfm::launch() {
  job_ = std::async(std::launch::async,
                    [this, s = std::move(*pending_)]() {
                      use_normal_priority();  // started by the realtime loop's thread
                      return refresh(s);
                    });
  pending_.reset();
}

const BlockEstimate& OnlineMmfm::collect() {
  history_.push_back(job_.get());
  spread_blocks_ = block_thetas_.size();
  return history_.back();
}

void OnlineMmfm::finish() {
  while (job_.valid() || pending_) {
    if (!job_.valid()) launch();
    collect();
  }
}

// Runs on the worker in asynchronous mode: touches only the snapshot, the per-block state
// and the (constant) options.
BlockEstimate OnlineMmfm::refresh(const Snapshot& s) {
  BlockEstimate e;
  e.block = s.block;
  e.t_s = s.t_s;
  e.max_rel_std_error = kNaN;
  try {
    const ident::MmfmResult live = estimate_mmfm(s.ruu, s.ryu, mmfm_options());
    block_corr_.insert(block_corr_.end(), s.blocks.begin(), s.blocks.end());
    block_thetas_.clear();
    block_derived_.clear();
    for (const auto& [ruu, ryu] : block_corr_) {
      try {
        const ident::MmfmResult one =
            ident::mmfm_solve(ruu, ryu, options_.order, live.delay_s, live.settings);
        const model::TransferFunction tf = model::monic(one.model);
        block_thetas_.push_back(ident::pack_parameters(tf));
        const ident::DerivedFigures d = ident::derived_figures(tf, Eigen::MatrixXd());
        block_derived_.emplace_back(d.gain, d.fn_hz, d.zeta);
      } catch (const std::exception&) {
        // A block too short or too noisy for these settings does not enter the spread.
      }
    }
    e.parameters = live.parameters;
    e.derived = live.derived;
    e.delay_s = live.delay_s;
    e.correlation_fit_pct = live.correlation_fit_pct;
    apply_spread(e.parameters, e.derived);
    e.ok = true;
  } catch (const std::exception& ex) {
    e.error = ex.what();
    return e;
  }
  // Free parameters: all but the leading denominator coefficient (fixed at 1) and the delay.
  double worst = 0.0;
  bool known = !e.parameters.empty();
  for (std::size_t j = 1; j + 1 < e.parameters.size(); ++j) {
    const auto& p = e.parameters[j];
    const double rel = std::abs(p.std_error / p.value);
    if (!std::isfinite(rel)) known = false;
    worst = std::max(worst, rel);
  }
  e.max_rel_std_error = known ? worst : kNaN;
  return e;
}

void OnlineMmfm::apply_spread(std::vector<ident::ParameterEstimate>& params,
                              ident::DerivedFigures& derived) const {
  const auto blocks = static_cast<double>(block_thetas_.size());
  if (blocks < kMinSpreadBlocks) return;
  const double b_eff = options_.exponential ? std::min(blocks, 2.0 * options_.weight - 1.0)
                                            : blocks;
  const auto theta_std = robust_std(block_thetas_);
  for (Eigen::Index j = 1; j < theta_std.size() && j + 1 < static_cast<Eigen::Index>(params.size());
       ++j) {
    params[static_cast<std::size_t>(j)].std_error = theta_std(j) / std::sqrt(b_eff);
  }
  const auto d_std = robust_std(block_derived_);
  derived.gain_std = d_std(0) / std::sqrt(b_eff);
  derived.fn_hz_std = d_std(1) / std::sqrt(b_eff);
  derived.zeta_std = d_std(2) / std::sqrt(b_eff);
}

bool OnlineMmfm::converged() const {
  if (history_.empty() || spread_blocks_ < kMinSpreadBlocks) return false;
  const auto& last = history_.back();
  return last.ok && std::isfinite(last.max_rel_std_error) &&
         last.max_rel_std_error < options_.target_rel_std_error;
}

ident::MmfmResult OnlineMmfm::final_result() const {
  if (job_.valid() || pending_) {
    throw std::logic_error("online MMFM: final_result() before finish()");
  }
  if (main_.blocks() == 0 && main_.samples() < options_.correlator.lags) {
    throw std::invalid_argument("online MMFM: no excitation block was completed");
  }
  ident::MmfmResult r = estimate_mmfm(main_.ruu(), main_.ryu(), mmfm_options());
  ident::DerivedFigures derived = r.derived;
  apply_spread(r.parameters, derived);
  r.derived = derived;
  return r;
}

}  // namespace rig::session
