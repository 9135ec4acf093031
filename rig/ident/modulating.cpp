#include "rig/ident/modulating.hpp"

#include <cmath>
#include <stdexcept>

namespace rig::ident {

const char* to_string(ModulatingFamily family) {
  return family == ModulatingFamily::kHermite ? "hermite" : "polynomial";
}

double hermite_half_width(int k) { return std::sqrt(2.0 * k + 1.0) + 4.5; }

Eigen::MatrixXd hermite_functions(const Eigen::VectorXd& tau_s, double centre_s, double scale_s,
                                  int count) {
  if (!(scale_s > 0.0) || count < 1)
    throw std::invalid_argument("hermite_functions: scale_s must be > 0 and count >= 1");
  const Eigen::Index rows = tau_s.size();
  Eigen::MatrixXd out(rows, count);
  const Eigen::ArrayXd x = (tau_s.array() - centre_s) / scale_s;
  out.col(0) = (-0.5 * x.square()).exp().matrix();
  if (count > 1) out.col(1) = (x * out.col(0).array()).matrix();
  // He_{k+1} = x He_k - k He_{k-1}, carried with the Gaussian factor.
  for (int k = 1; k + 1 < count; ++k)
    out.col(k + 1) = (x * out.col(k).array() - k * out.col(k - 1).array()).matrix();
  return out;
}

Eigen::MatrixXd polynomial_function_derivatives(const Eigen::VectorXd& tau_s, double a_s,
                                                double b_s, int power, int derivatives) {
  if (!(b_s > a_s) || power < 1 || derivatives < 0)
    throw std::invalid_argument("polynomial_function_derivatives: need b > a, power >= 1");
  // x^N (1-x)^N = sum_k C(N,k) (-1)^k x^(N+k), scaled by 4^N so that the peak is 1.
  const int deg = 2 * power;
  Eigen::VectorXd coef = Eigen::VectorXd::Zero(deg + 1);  // ascending powers of x
  double binom = 1.0;
  for (int k = 0; k <= power; ++k) {
    coef(power + k) = binom * ((k % 2) ? -1.0 : 1.0) * std::pow(4.0, power);
    binom = binom * (power - k) / (k + 1);
  }
  const double len = b_s - a_s;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(tau_s.size(), derivatives + 1);
  for (int i = 0; i <= derivatives; ++i) {
    const double scale = std::pow(len, -i);
    for (Eigen::Index r = 0; r < tau_s.size(); ++r) {
      const double x = (tau_s(r) - a_s) / len;
      if (x <= 0.0 || x >= 1.0) continue;
      double acc = 0.0;
      for (int j = deg; j >= 0; --j) acc = acc * x + coef(j);
      out(r, i) = acc * scale;
    }
    // Differentiate the coefficients for the next derivative order.
    for (int j = 0; j < deg; ++j) coef(j) = coef(j + 1) * (j + 1);
    coef(deg) = 0.0;
  }
  return out;
}

}  // namespace rig::ident
