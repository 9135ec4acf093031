#include "plantsim/plant/bias_path.hpp"

#include <algorithm>
#include <unsupported/Eigen/MatrixFunctions>

namespace plantsim {

void BiasPath::configure(const Params& p, double dt_s) {
  const double t1 = p[P::kGovT1], t2 = p[P::kGovT2], t3 = p[P::kGovT3];
  const double k = p[P::kGovK], t4 = p[P::kGovT4], t5 = p[P::kGovT5], t6 = p[P::kGovT6];
  // The same canonical forms as Degov1::derivatives with e = r:
  //   T1 T2 z1'' + T1 z1' + z1 = r,  c = z1 + T3 z1';  T5 T6 a1'' + (T5+T6) a1' + a1 = K c;
  //   xi' = a1 + T4 a1'.
  a_.setZero();
  a_(0, 1) = 1.0;
  a_(1, 0) = -1.0 / (t1 * t2);
  a_(1, 1) = -1.0 / t2;
  a_(2, 3) = 1.0;
  a_(3, 0) = k / (t5 * t6);
  a_(3, 1) = k * t3 / (t5 * t6);
  a_(3, 2) = -1.0 / (t5 * t6);
  a_(3, 3) = -(t5 + t6) / (t5 * t6);
  a_(4, 2) = 1.0;
  a_(4, 3) = t4;
  b_.setZero();
  b_[1] = 1.0 / (t1 * t2);
  discretise(dt_s, &phi_, &gamma_);
}

// exp([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, 1]]: exact for an input held over h.
void BiasPath::discretise(double duration_s, Eigen::Matrix<double, kStates, kStates>* phi,
                          Vector* gamma) const {
  Eigen::Matrix<double, kStates + 1, kStates + 1> aug =
      Eigen::Matrix<double, kStates + 1, kStates + 1>::Zero();
  aug.topLeftCorner<kStates, kStates>() = a_;
  aug.topRightCorner<kStates, 1>() = b_;
  const Eigen::Matrix<double, kStates + 1, kStates + 1> e = (aug * duration_s).exp();
  *phi = e.topLeftCorner<kStates, kStates>();
  *gamma = e.topRightCorner<kStates, 1>();
}

void BiasPath::advance(double r_pu) { s_ = phi_ * s_ + gamma_ * r_pu; }

void BiasPath::advance(double r_pu, double duration_s) {
  if (duration_s <= 0.0) return;
  Eigen::Matrix<double, kStates, kStates> phi;
  Vector gamma;
  discretise(duration_s, &phi, &gamma);
  s_ = phi * s_ + gamma * r_pu;
}

void BiasPath::clamp_integrator(double actuator_ode_pu, double lo_pu, double hi_pu) {
  s_[kStates - 1] = std::clamp(s_[kStates - 1], lo_pu - actuator_ode_pu, hi_pu - actuator_ode_pu);
}

}  // namespace plantsim
