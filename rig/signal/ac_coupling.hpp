// Matched AC coupling (MMFM.md section 6, the IEE paper's "A.C. coupling network").
//
// The analogue coupler is the first-order high-pass Hc(s) = s RC / (1 + s RC). The excitation
// leaves the DAC piecewise constant (zero-order hold), so its ZOH-equivalent discretisation
//
//     Hd(z) = (1 - z^-1) Z{ Hc(s)/s } = (1 - z^-1) / (1 - a z^-1),   a = exp(-dt/RC)
//     v_k = a v_{k-1} + x_k - x_{k-1}
//
// reproduces the analogue network's output exactly at the sample instants (just after each
// DAC step) for a staircase input. Apply the SAME replica to excitation and response
// (R_vw = H R_ww holds for the coupled pair), or to the excitation only when the recorded
// response already went through an analogue coupler of the same RC.
// Initial state: discharged capacitor (x_{-1} = v_{-1} = 0), or settled at a constant input
// via reset(x_settled) so that a constant input gives zero output from the first sample.
#pragma once

#include <Eigen/Core>

namespace rig::signal {

class AcCoupler {
 public:
  // Throws std::invalid_argument unless dt_s > 0 and rc_s > 0.
  AcCoupler(double dt_s, double rc_s);

  double step(double x) {
    const double v = a_ * v_ + x - x_prev_;
    x_prev_ = x;
    v_ = v;
    return v;
  }
  Eigen::VectorXd process(const Eigen::VectorXd& x);  // streams a block through step()
  void reset(double x_settled = 0.0) {
    x_prev_ = x_settled;
    v_ = 0.0;
  }
  double pole() const { return a_; }  // a = exp(-dt/RC)

 private:
  double a_ = 0.0;
  double x_prev_ = 0.0;
  double v_ = 0.0;
};

// The whole record through a discharged coupler.
Eigen::VectorXd ac_couple(const Eigen::VectorXd& x, double dt_s, double rc_s);

// RC for a -3 dB corner frequency: RC = 1 / (2 pi f_c).
double rc_from_corner_hz(double corner_hz);

}  // namespace rig::signal
