// Continuous-time transfer functions with dead time, and their exact simulation.
//
//   H(s) = e^{-s Td} (b_m s^m + ... + b_0) / (a_n s^n + ... + a_0)
//
// Coefficients are stored highest power first (as scipy / MATLAB and the model JSON of
// DESIGN.md section 5).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace rig::model {

struct TransferFunction {
  Eigen::VectorXd num;  // b_m ... b_0
  Eigen::VectorXd den;  // a_n ... a_0
  double delay_s = 0.0;

  // H(j 2 pi f) including e^{-j 2 pi f Td}.
  std::complex<double> response(double freq_hz) const;
  // H(s) at any complex s (delay included).
  std::complex<double> evaluate(std::complex<double> s) const;
  // b_0 / a_0; +-infinity when a_0 = 0.
  double dc_gain() const;
  // All poles strictly in the left half plane.
  bool is_stable() const;
  // deg num <= deg den after trimming leading zeros.
  bool is_proper() const;
  Eigen::VectorXcd poles() const;
  Eigen::VectorXcd zeros() const;
  int order() const;            // n (after trimming)
  int numerator_order() const;  // m (after trimming)
};

// Den order n and numerator order m of a model structure.
struct ModelOrder {
  int n = 2;
  int m = 0;
};
inline bool operator==(const ModelOrder& a, const ModelOrder& b) {
  return a.n == b.n && a.m == b.m;
}

// The same TF scaled so that a_n = 1 (monic denominator); leading zeros trimmed.
TransferFunction monic(const TransferFunction& tf);

// exp of [[A h, B h, 0], [0, 0, h], [0, 0, 0]]: the state map over a step of length h for
// an input that starts at v0 and rises with slope g: x+ = Phi x + Ga v0 + Gb g (the
// first-order hold simulate() steps with; also for loops stepped sample by sample).
struct FohStep {
  Eigen::MatrixXd phi;
  Eigen::VectorXd ga, gb;
};
FohStep foh_step(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double h);

// Output of tf for input samples u_k = u(k dt), zero initial state, u = 0 before t = 0.
// Exact for an input that is piecewise linear between samples (first-order hold): the
// state-space step uses the matrix exponential of the system augmented with the input and
// its slope, so there is no half-sample lag as with a zero-order-hold discretisation. The
// dead time is exact too: a delay of d + f samples splits each step at the delayed knot.
// Throws std::invalid_argument for an improper tf, dt_s <= 0 or delay_s < 0.
Eigen::VectorXd simulate(const TransferFunction& tf, const Eigen::VectorXd& u, double dt_s);

// Filtered derivatives of a delayed signal: column i (i = 0..n) holds p^{n-i}/A(p) u(t - Td)
// for the denominator den = A (any scale; n = its order), zero initial state, the input
// piecewise linear as in simulate(). These are the state-variable-filter outputs used by
// SRIVC and the output sensitivities; simulate() is B(p) applied to them.
Eigen::MatrixXd filtered_derivatives(const Eigen::VectorXd& den, const Eigen::VectorXd& u,
                                     double dt_s, double delay_s);

// Several records joined end to end (a multi-record estimation): `starts` holds the first
// sample of each record (ascending, the first 0; empty: one record). Each record starts from
// zero state, as simulate() and filtered_derivatives() do for one.
using RecordStarts = std::vector<Eigen::Index>;
Eigen::VectorXd simulate(const TransferFunction& tf, const Eigen::VectorXd& u, double dt_s,
                         const RecordStarts& starts);
Eigen::MatrixXd filtered_derivatives(const Eigen::VectorXd& den, const Eigen::VectorXd& u,
                                     double dt_s, double delay_s, const RecordStarts& starts);

// Free (zero-input) responses of tf from the unit initial states of its controllable form,
// one column each (n columns): they span every initial-condition transient of the system.
Eigen::MatrixXd free_response_basis(const TransferFunction& tf, Eigen::Index samples, double dt_s);

// NRMSE fit in %: 100 (1 - |y - yhat| / |y - mean(y)|) (MATLAB compare, DESIGN.md 5).
double fit_percent(const Eigen::VectorXd& y, const Eigen::VectorXd& yhat);

}  // namespace rig::model
