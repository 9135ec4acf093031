#include "plantsim/plant/governor.hpp"

#include <algorithm>
#include <cmath>

namespace plantsim {

double Degov1::pref_pu() const { return p_[P::kGovR] * p_[P::kPowerKw] / p_[P::kRatedKw]; }

void Degov1::init(double pe0_pu, double xf0_pu, double* x) const {
  // With e = 0 every lead-lag state is at rest: z1 = z2 = a1 = a2 = 0.
  x[kPeFilt] = pe0_pu;
  x[kZ1] = x[kZ2] = x[kA1] = x[kA2] = 0.0;
  x[kXf] = xf0_pu;
}

double Degov1::error_pu(const double* x, double bias_pu, double dw_pu) const {
  const double r = p_[P::kGovR];
  const double e = pref_pu() + r * bias_pu - p_[P::kGovSpeedGain] * dw_pu - r * x[kPeFilt];
  const double db = p_[P::kGovDeadband];
  if (db <= 0.0) return e;
  return std::abs(e) <= db ? 0.0 : e - std::copysign(db, e);
}

void Degov1::derivatives(const double* x, double pe_pu, double dw_pu, double bias_pu, double* dx,
                         bool limit_integrator) const {
  const double te = p_[P::kGovTe], t1 = p_[P::kGovT1], t2 = p_[P::kGovT2], t3 = p_[P::kGovT3];
  const double k = p_[P::kGovK], t4 = p_[P::kGovT4], t5 = p_[P::kGovT5], t6 = p_[P::kGovT6];
  dx[kPeFilt] = (pe_pu - x[kPeFilt]) / te;
  // Control box in controllable canonical form: T1 T2 z1'' + T1 z1' + z1 = e, c = z1 + T3 z1'.
  const double e = error_pu(x, bias_pu, dw_pu);
  dx[kZ1] = x[kZ2];
  dx[kZ2] = (e - x[kZ1] - t1 * x[kZ2]) / (t1 * t2);
  const double c = x[kZ1] + t3 * x[kZ2];
  // Actuator lead-lags the same way: T5 T6 a1'' + (T5 + T6) a1' + a1 = K c, v = a1 + T4 a1'.
  dx[kA1] = x[kA2];
  dx[kA2] = (k * c - x[kA1] - (t5 + t6) * x[kA2]) / (t5 * t6);
  double v = x[kA1] + t4 * x[kA2];
  const double rate = p_[P::kGovRate];
  if (rate > 0.0) v = std::clamp(v, -rate, rate);
  // Non-windup integrator: stop at a limit while the input pushes further out.
  const double xf = x[kXf];
  const bool pushing_out = (xf >= p_[P::kGovTmax] && v > 0.0) || (xf <= p_[P::kGovTmin] && v < 0.0);
  if (limit_integrator && pushing_out) v = 0.0;
  dx[kXf] = v;
}

}  // namespace plantsim
