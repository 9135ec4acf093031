// Records for the diagnosis unit tests: the null case's input and nominal model, white
// noise and an rms, each seeded.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <random>

#include "concealed.hpp"

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

inline double rms(const Eigen::VectorXd& x) {
  return std::sqrt((x.array() - x.mean()).square().mean());
}

}  // namespace rig::diagnose::test
