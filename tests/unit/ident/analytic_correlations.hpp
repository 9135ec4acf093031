// Noise-free correlation pairs built as in thesis 5-1: a known input autocorrelation (the
// triangle of a PRBS) convolved with a known impulse response. r_yu = h * r_uu is computed
// exactly by simulating the system with r_uu as input along the lag axis (the triangle is
// piecewise linear, which the simulation integrates exactly).
#pragma once

#include <algorithm>
#include <cmath>

#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"

namespace rig::ident::testing {

struct CorrelationPair {
  signal::Correlation ruu, ryu;
};

inline CorrelationPair triangle_pair(const model::TransferFunction& tf, double half_width_s,
                                     double dt_s, Eigen::Index lags, Eigen::Index zero_index) {
  CorrelationPair p;
  p.ruu.dt_s = dt_s;
  p.ruu.zero_index = zero_index;
  p.ruu.r.resize(lags);
  for (Eigen::Index i = 0; i < lags; ++i)
    p.ruu.r(i) = std::max(0.0, 1.0 - std::abs(p.ruu.lag_s(i)) / half_width_s);
  p.ryu = p.ruu;
  p.ryu.r = simulate(tf, p.ruu.r, dt_s);
  return p;
}

inline model::TransferFunction make_tf(std::initializer_list<double> num,
                                       std::initializer_list<double> den, double delay_s = 0.0) {
  model::TransferFunction tf;
  tf.num = Eigen::Map<const Eigen::VectorXd>(num.begin(), static_cast<Eigen::Index>(num.size()));
  tf.den = Eigen::Map<const Eigen::VectorXd>(den.begin(), static_cast<Eigen::Index>(den.size()));
  tf.delay_s = delay_s;
  return tf;
}

}  // namespace rig::ident::testing
