// Records for the diagnosis unit tests: the null case's input and nominal model, white
// noise and an rms, each seeded.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>

#include "concealed.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/placement.hpp"

namespace rig::diagnose::test {

// The null case's record (its input and the nominal model), 200 s.
inline DiagnoseInput null_record(std::uint64_t seed) {
  ConcealedSpec spec;
  spec.seed = seed;
  spec.duration_s = 200.0;
  return make_concealed(spec).input;
}

inline Eigen::VectorXd white(Eigen::Index n, double std, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, std);
  Eigen::VectorXd x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

// A PRBS-like bias: +-1 held for bits of 10 samples, each bit's sign random (seeded).
inline Eigen::VectorXd two_level(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Eigen::VectorXd u(n);
  double level = 1.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k % 10 == 0) level = (rng() & 1u) ? 1.0 : -1.0;
    u(k) = level;
  }
  return u;
}

inline double rms(const Eigen::VectorXd& x) {
  return std::sqrt((x.array() - x.mean()).square().mean());
}

// A rate limit inside the loop, behind a front lag of lag_s, at half the rms rate of the
// signal there (in bias-% equivalent per second, *limit), acting from sample `from`: the
// signal after it (the input of the rest of the model, G / F).
inline Eigen::VectorXd in_loop_rate_limited(const DiagnoseInput& in, double lag_s, double* limit,
                                            Eigen::Index from = 0) {
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd w = front_signal(u, lag_s, in.dt_s);
  const double k = rms(u) / rms(w);
  const Eigen::VectorXd w_rate = (w.tail(w.size() - 1) - w.head(w.size() - 1)) / in.dt_s;
  *limit = 0.5 * k * rms(w_rate);
  Eigen::VectorXd v = rate_limit(k * w, *limit, in.dt_s) / k;
  v.head(from) = w.head(from);  // no limit before it
  return v;
}

}  // namespace rig::diagnose::test
