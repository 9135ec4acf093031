#include "rig/fra/stepped_sine.hpp"

#include <cmath>
#include <numbers>
#include <utility>

namespace rig::fra {

model::FrfPoint SteppedSineResult::frf_point() const {
  model::FrfPoint p;
  p.freq_hz = point.freq_hz;
  p.mag = mag;
  p.phase_deg = phase_deg;
  p.coherence = lock_in.coherence;
  const double k = std::pow(10.0, lock_in.mag_std_db / 20.0);
  p.mag_lo = mag / k;
  p.mag_hi = mag * k;
  p.valid = good;
  return p;
}

SteppedSineAnalyser::SteppedSineAnalyser(SweepPlan plan, SteppedSineOptions options)
    : plan_(std::move(plan)), options_(options) {
  if (!done()) u_.reserve(static_cast<std::size_t>(plan_.points.front().integrate_samples));
}

SteppedSineAnalyser::Phase SteppedSineAnalyser::phase() const {
  if (done()) return Phase::kDone;
  return n_ < plan_.points[index_].settle_samples ? Phase::kSettling : Phase::kIntegrating;
}

double SteppedSineAnalyser::excitation_pct() const {
  if (done()) return 0.0;
  const SweepPoint& p = plan_.points[index_];
  const double t_s = static_cast<double>(n_) * plan_.dt_s;
  // Raised-cosine fade-in: 0.5 (1 - cos(pi n / n_ramp)) rises from 0 to 1 with zero slope
  // at both ends.
  double envelope = 1.0;
  if (n_ < p.ramp_samples) {
    envelope = 0.5 * (1.0 - std::cos(std::numbers::pi * static_cast<double>(n_) /
                                     static_cast<double>(p.ramp_samples)));
  }
  return envelope * p.amplitude_pct * std::sin(2.0 * std::numbers::pi * p.freq_hz * t_s);
}

std::optional<SteppedSineResult> SteppedSineAnalyser::push(double u_applied_pct, double y_kw) {
  if (done()) return std::nullopt;
  const SweepPoint& p = plan_.points[index_];
  if (n_ >= p.settle_samples) {
    u_.push_back(u_applied_pct);
    y_.push_back(y_kw);
  }
  ++n_;
  if (n_ < p.total_samples()) return std::nullopt;
  SteppedSineResult r = analyse();
  results_.push_back(r);
  ++index_;
  n_ = 0;
  u_.clear();
  y_.clear();
  return r;
}

SteppedSineResult SteppedSineAnalyser::analyse() const {
  const SweepPoint& p = plan_.points[index_];
  const auto n = static_cast<Eigen::Index>(u_.size());
  const Eigen::Map<const Eigen::VectorXd> u(u_.data(), n), y(y_.data(), n);
  // The window starts settle_samples into the point; its time origin must match the
  // generator's so that the phase of U_1 is the generator's.
  const double t0_s = static_cast<double>(p.settle_samples) * plan_.dt_s;
  SteppedSineResult r;
  r.point = p;
  bool finite = u.allFinite() && y.allFinite();
  if (!finite) return r;  // good stays false; a NaN means the supervisor tripped anyway
  r.lock_in = lock_in(u, y, p.freq_hz, plan_.dt_s, t0_s, options_.max_harmonic);
  r.mag = std::abs(r.lock_in.ratio);
  r.phase_deg = model::wrap_deg(std::arg(r.lock_in.ratio) * 180.0 / std::numbers::pi);
  r.distortion = r.lock_in.y.distortion();
  r.noise = r.lock_in.y.noise_ratio();
  const double u_noise = r.lock_in.u.noise_ratio() + r.lock_in.u.distortion();
  r.good = r.lock_in.coherence >= options_.min_coherence &&
           r.distortion <= options_.max_distortion && u_noise <= options_.max_excitation_noise;
  return r;
}

std::vector<model::FrfPoint> SteppedSineAnalyser::frf() const {
  std::vector<model::FrfPoint> out;
  out.reserve(results_.size());
  for (const auto& r : results_) out.push_back(r.frf_point());
  return out;
}

}  // namespace rig::fra
