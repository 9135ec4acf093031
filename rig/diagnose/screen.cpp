#include "rig/diagnose/screen.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <numbers>
#include <thread>
#include <type_traits>

#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kLongScreenSearchedStarts;
using thresholds::kPolishEvaluations;
using thresholds::kScreenEvaluations;
using thresholds::kScreenMaxDecimation;
using thresholds::kScreenMinSamples;
using thresholds::kScreenOversampling;

// The screen's decimation: keep kScreenOversampling samples per period of the highest
// excited frequency, at most kScreenMaxDecimation, none for a short record.
int screen_decimation(const Problem& pr) {
  if (pr.u.size() < kScreenMinSamples) return 1;
  double band_hz = 0.0;  // the input's band: its rate over its rms, as a frequency
  band_hz = pr.scales.u_rate_std / (2.0 * std::numbers::pi * std::max(pr.scales.u_std, 1e-300));
  const int f =
      static_cast<int>(std::floor(1.0 / (pr.dt_s * kScreenOversampling * std::max(band_hz, 1e-9))));
  int most = kScreenMaxDecimation;
  // Keep a whole sample of the model's dead time: under one, the loops on the governor's
  // error solve each sample in several passes (error_loop.cpp), which costs more than the
  // samples saved.
  if (pr.tf.delay_s >= pr.dt_s)
    most = std::min(most, static_cast<int>(std::floor(pr.tf.delay_s / pr.dt_s + 1e-9)));
  return std::clamp(f, 1, most);
}

// Every f-th sample of the problem (the input and output as recorded, the weights and
// spans with them), its derived fields rebuilt.
Problem decimated(const Problem& pr, int f) {
  if (f <= 1) return pr;
  Problem out = pr;
  const Eigen::Index n = (pr.u.size() + f - 1) / f;
  auto pick = [&](const auto& x) {
    std::decay_t<decltype(x)> y(n);
    for (Eigen::Index i = 0; i < n; ++i) y(i) = x(i * f);
    return y;
  };
  out.u = pick(pr.u);
  out.y = pick(pr.y);
  out.est_weight = pick(pr.est_weight);
  out.val_weight = pick(pr.val_weight);
  out.dt_s = pr.dt_s * f;
  out.active_from = pr.active_from / f;
  out.active_to = pr.active_to < 0 ? -1 : (pr.active_to + f - 1) / f;
  out.level_shift_at = pr.level_shift_at < 0 ? -1 : pr.level_shift_at / f;
  out.level_step_removed_at = pr.level_step_removed_at < 0 ? -1 : pr.level_step_removed_at / f;
  finish_problem(out);
  return out;
}

}  // namespace

void rank(std::vector<HypothesisFit>& hs) {
  std::stable_sort(hs.begin(), hs.end(), [](const HypothesisFit& a, const HypothesisFit& b) {
    return a.score > b.score;
  });
}

void drop_repeats(std::vector<HypothesisFit>& hs) {
  const auto same = [](const HypothesisFit& a, const HypothesisFit& b) {
    if (a.effects.size() != b.effects.size() || a.active_from != b.active_from ||
        a.active_to != b.active_to)
      return false;
    for (std::size_t i = 0; i < a.effects.size(); ++i) {
      const AppliedEffect &x = a.effects[i], &y = b.effects[i];
      if (x.effect != y.effect || x.place != y.place || x.params != y.params ||
          x.place_params != y.place_params)
        return false;
    }
    return true;
  };
  std::vector<HypothesisFit> kept;
  kept.reserve(hs.size());
  for (auto& h : hs)
    if (std::none_of(kept.begin(), kept.end(), [&](const HypothesisFit& k) { return same(k, h); }))
      kept.push_back(std::move(h));
  hs = std::move(kept);
}

namespace {

// Every candidate fitted on the problem as it is, on the worker threads. A fit that throws
// stops the others from taking more work; every thread is joined before the first error is
// rethrown (a joinable thread destroyed by an exception ends the process).
std::vector<HypothesisFit> fit_each(const Problem& pr, const std::vector<Candidate>& cands,
                                    const Eigen::VectorXd& base, const FitOptions& fit,
                                    int threads) {
  std::vector<HypothesisFit> out(cands.size());
  std::atomic<std::size_t> next{0};
  std::mutex failed_mutex;
  std::exception_ptr failed;
  auto work = [&] {
    try {
      for (std::size_t i = next++; i < cands.size(); i = next++)
        out[i] = fit_hypothesis(pr, cands[i], base, fit);
    } catch (...) {
      next = cands.size();
      const std::lock_guard<std::mutex> lock(failed_mutex);
      if (!failed) failed = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (failed) std::rethrow_exception(failed);
  return out;
}

}  // namespace

std::vector<HypothesisFit> fit_all(const Problem& pr, const std::vector<Candidate>& cands,
                                   const Eigen::VectorXd& base, const DiagnoseOptions& o) {
  const int f = screen_decimation(pr);
  if (f <= 1) return fit_each(pr, cands, base, o.fit, o.threads);
  // A long record: each candidate searched in full on the decimated record (the screen's),
  // then polished on the whole one from there (thresholds.hpp kPolishEvaluations).
  const Problem coarse = decimated(pr, f);
  const std::vector<HypothesisFit> rough =
      fit_each(coarse, cands, model_output(coarse, {}).yhat, o.fit, o.threads);
  std::vector<Candidate> from_rough;
  for (const auto& h : rough) from_rough.push_back({h.effects});
  FitOptions polish = o.fit;
  polish.max_evaluations = std::min(o.fit.max_evaluations, kPolishEvaluations);
  std::vector<HypothesisFit> out = fit_each(pr, from_rough, base, polish, o.threads);
  for (std::size_t i = 0; i < out.size(); ++i) out[i].evaluations += rough[i].evaluations;
  return out;
}

// Every single hypothesis is fitted with a short search (a screen; on a long record from
// its best start only), and the best few are then searched in full from where the screen
// stopped (thresholds.hpp).
std::vector<HypothesisFit> screen_and_refine(const Problem& pr, const std::vector<Candidate>& cands,
                                             const Eigen::VectorXd& base, const DiagnoseOptions& o,
                                             std::size_t refine) {
  DiagnoseOptions screen = o;
  screen.fit.max_evaluations = std::min(o.fit.max_evaluations, kScreenEvaluations);
  const int f = screen_decimation(pr);
  if (f > 1)
    screen.fit.searched_starts = std::min(o.fit.searched_starts, kLongScreenSearchedStarts);
  const Problem coarse = decimated(pr, f);
  std::vector<HypothesisFit> hs = fit_all(coarse, cands, model_output(coarse, {}).yhat, screen);
  rank(hs);
  const std::size_t k = std::min(hs.size(), refine);
  std::vector<Candidate> best;
  for (std::size_t i = 0; i < k; ++i) best.push_back({hs[i].effects});
  std::vector<HypothesisFit> refined = fit_all(pr, best, base, o);
  for (std::size_t i = 0; i < hs.size(); ++i) {
    const int screened = hs[i].evaluations;
    hs[i] = i < k ? std::move(refined[i]) : score_hypothesis(pr, hs[i].effects, base, o.fit);
    hs[i].evaluations += screened;
    hs[i].screened_only = i >= k;
  }
  rank(hs);
  return hs;
}

}  // namespace rig::diagnose
