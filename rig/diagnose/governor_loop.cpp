#include "rig/diagnose/governor_loop.hpp"

#include <algorithm>
#include <cmath>

#include "rig/diagnose/blocks.hpp"

namespace rig::diagnose {
namespace {

// a - b (highest power first, aligned at the constant term).
Eigen::VectorXd poly_subtract(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::Index n = std::max(a.size(), b.size());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  out.tail(a.size()) += a;
  out.tail(b.size()) -= b;
  return out;
}

}  // namespace

FeedbackFilter::FeedbackFilter(const LoopFeedback& h, double dt_s)
    : static_(h.static_share),
      rate_(h.derivative_s / std::max(h.filter_s, 1e-300)),
      q_(std::exp(-dt_s / std::max(h.filter_s, 1e-300))),
      c_(1.0 + std::expm1(-dt_s / std::max(h.filter_s, 1e-300)) * h.filter_s / dt_s) {}

Eigen::VectorXd feed_back(const LoopFeedback& h, const Eigen::VectorXd& y, double dt_s) {
  FeedbackFilter f(h, dt_s);
  Eigen::VectorXd out(y.size());
  for (Eigen::Index k = 0; k < y.size(); ++k) out(k) = f.at(y(k)), f.advance(y(k));
  return out;
}

bool feedback_fitted(Place place) {
  return place == Place::kGovernorLoop || place == Place::kGovernorError ||
         place == Place::kGovernorPi;
}

LoopFeedback loop_feedback(std::span<const double> p) {
  const std::size_t n = p.size();
  return {p[n - 3], p[n - 2], p[n - 1]};
}

std::optional<SharedFeedback> shared_feedback(std::span<const AppliedEffect> effects) {
  SharedFeedback s;
  bool loop = false, error = false;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    if (effects[i].place == Place::kGovernorLoop) s.loop = i, loop = true;
    if (in_error_loop(effects[i].place) && feedback_fitted(effects[i].place))
      s.error = i, error = true;
  }
  if (!loop || !error) return std::nullopt;
  return s;
}

void share_feedback(std::vector<AppliedEffect>& effects) {
  const auto s = shared_feedback(effects);
  if (!s) return;
  const std::vector<double>& from = effects[s->error].place_params;
  effects[s->loop].place_params.assign(from.end() - 3, from.end());
}

bool governor_loop_possible(const model::TransferFunction& tf) {
  const double g0 = tf.dc_gain();
  return std::isfinite(g0) && std::abs(g0) > 1e-12;
}

model::TransferFunction close_governor_loop(const model::TransferFunction& tf,
                                            const Eigen::VectorXd& nf, const Eigen::VectorXd& df,
                                            std::span<const double> place_params) {
  const LoopFeedback h = loop_feedback(place_params);
  const double a = h.static_share, t_d = h.derivative_s, t_h = h.filter_s;
  const Eigen::VectorXd nh = Eigen::Vector2d(t_d, a), dh = Eigen::Vector2d(t_h, 1.0);
  const double g0 = tf.dc_gain();
  model::TransferFunction out = tf;
  out.num = g0 * poly_multiply(tf.num, poly_multiply(nf, dh));
  out.den = poly_subtract(g0 * poly_multiply(tf.den, poly_multiply(df, dh)),
                          poly_multiply(tf.num, poly_multiply(nh, poly_subtract(df, nf))));
  return out;
}

void pade_delay(double tau_s, Eigen::VectorXd& num, Eigen::VectorXd& den) {
  const double t = std::max(0.0, tau_s);
  if (t < 1e-6) {
    num = den = Eigen::VectorXd::Ones(1);
    return;
  }
  // e^{-s t} ~ (1 - s t/2 + (s t)^2/10 - (s t)^3/120) / (1 + s t/2 + (s t)^2/10 + (s t)^3/120)
  const double c3 = t * t * t / 120.0, c2 = t * t / 10.0, c1 = t / 2.0;
  num = Eigen::Vector4d(-c3, c2, -c1, 1.0);
  den = Eigen::Vector4d(c3, c2, c1, 1.0);
}

}  // namespace rig::diagnose
