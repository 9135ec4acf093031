// Digital Butterworth low-pass: the analogue prototype |H(jw)|^2 = 1 / (1 + (w/wc)^(2n))
// mapped by the bilinear transform s = (2/T)(1 - z^-1)/(1 + z^-1) with the corner pre-warped,
// wc = (2/T) tan(pi fc T), so the digital filter is exactly -3 dB at fc. Realised as a cascade
// of second-order sections (one per conjugate pole pair, damping zeta_k = sin(pi(2k-1)/(2n)))
// plus a first-order section for odd n, each in transposed direct form II.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace rig::signal {

class ButterworthLowPass {
 public:
  // Throws std::invalid_argument unless 1 <= order <= 8, dt_s > 0 and 0 < corner_hz < 0.5/dt_s.
  ButterworthLowPass(int order, double corner_hz, double dt_s);

  double step(double x);
  Eigen::VectorXd process(const Eigen::VectorXd& x);
  void reset();
  std::complex<double> response(double freq_hz) const;  // H(e^{j 2 pi f T})

 private:
  struct Section {  // y = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) x
    double b0, b1, b2, a1, a2;
    double s1 = 0.0, s2 = 0.0;
  };
  std::vector<Section> sections_;
  double dt_s_;
};

}  // namespace rig::signal
