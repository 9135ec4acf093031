// Modulating functions and their derivatives (MMFM.md sections 3-4, thesis 3-1-2).
//
// Hermite family (Takaya), scaled lag x = (tau - c) / S:
//     phi_k(tau) = exp(-x^2/2) He_k(x),  He_{k+1} = x He_k - k He_{k-1}
//     d/dtau phi_k = -(1/S) phi_{k+1}
// so the i-th derivative of phi_k is (-1/S)^i phi_{k+i}: every derivative comes from the
// recurrence. The functions vanish only approximately at the window ends; the support
// used is c +- hermite_half_width(k) S.
//
// Polynomial family, exact at the ends: on [a, b] with x = (tau - a) / (b - a),
//     phi(tau) = x^N (1 - x)^N,  d^i/dtau^i phi = (b - a)^{-i} d^i/dx^i [x^N (1 - x)^N]
// whose derivatives up to N - 1 vanish at a and b.
#pragma once

#include <Eigen/Core>

namespace rig::ident {

enum class ModulatingFamily { kHermite, kPolynomial };
const char* to_string(ModulatingFamily family);

// Half-width (in units of S) outside which |phi_k| < 1e-9 of its peak:
// sqrt(2k+1) + 4.5 covers the oscillating core plus the Gaussian tail.
double hermite_half_width(int k);

// Columns k = 0..count-1 of exp(-x^2/2) He_k(x) at x = (tau - centre_s) / scale_s.
Eigen::MatrixXd hermite_functions(const Eigen::VectorXd& tau_s, double centre_s, double scale_s,
                                  int count);

// Columns i = 0..derivatives of d^i/dtau^i [x^N (1-x)^N], x = (tau - a)/(b - a), zero
// outside [a, b].
Eigen::MatrixXd polynomial_function_derivatives(const Eigen::VectorXd& tau_s, double a_s,
                                                double b_s, int power, int derivatives);

}  // namespace rig::ident
