// Seeded test signals shared by the signal tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <iostream>

#include "rig/signal/random.hpp"

namespace rig::signal::test {

// White N(0,1) samples from a named seed (printed so that a failure can be replayed).
inline Eigen::VectorXd white(Eigen::Index n, std::uint64_t seed) {
  std::cout << "[seed] white noise n=" << n << " seed=" << seed << "\n";
  Xoshiro256 rng(seed);
  Eigen::VectorXd x(n);
  for (auto& v : x) v = rng.normal();
  return x;
}

// y_t = sum_i h_i u_{t-i} (zero initial conditions).
inline Eigen::VectorXd fir(const Eigen::VectorXd& h, const Eigen::VectorXd& u) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (Eigen::Index t = 0; t < u.size(); ++t) {
    for (Eigen::Index i = 0; i < h.size() && i <= t; ++i) y[t] += h[i] * u[t - i];
  }
  return y;
}

// The estimator of correlators.hpp written out naively: mean over anchors t of y_t u_{t-k}.
inline double naive_lag(const Eigen::VectorXd& y, const Eigen::VectorXd& u, Eigen::Index k,
                        Eigen::Index first, Eigen::Index last, Eigen::Index skip) {
  double sum = 0.0;
  Eigen::Index m = 0;
  for (Eigen::Index t = first; t <= last; t += skip, ++m) sum += y[t] * u[t - k];
  return sum / static_cast<double>(m);
}

}  // namespace rig::signal::test
