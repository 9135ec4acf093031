// CVODE (SUNDIALS 6) wrapper: one ODE system x' = f(t, x), BDF with a dense direct linear
// solver and a difference-quotient Jacobian. Every CVODE/SUNDIALS return code goes through
// check_retval(), the one place that turns it into a typed SolverError (as the SUNDIALS
// examples' check_retval does).
#pragma once

#include <Eigen/Core>
#include <stdexcept>
#include <string>

namespace plantsim {

class SolverError : public std::runtime_error {
 public:
  SolverError(const std::string& function, int code);
  const std::string& function() const { return function_; }
  int code() const { return code_; }

 private:
  std::string function_;
  int code_;
};

// Throws SolverError when `retval` is a failure code of `function`; returns otherwise.
void check_retval(int retval, const char* function);
// Throws SolverError when a SUNDIALS constructor returned nullptr.
void check_ptr(const void* ptr, const char* function);

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  virtual int size() const = 0;
  // dx = f(t, x). Must not throw (it is called from C); return false to signal a failure.
  virtual bool derivatives(double t, const double* x, double* dx) = 0;
};

struct SolverOptions {
  double rtol = 1e-6;
  double atol = 1e-8;
  // Per-state factors on atol (empty: atol for every state), for states in other units than
  // the rest, e.g. a rate in pu/s beside positions in pu.
  Eigen::VectorXd atol_scale;
  double max_step_s = 0.0;  // 0 = unlimited
  long max_steps = 100000;  // per advance_to()
  int max_order = 5;        // BDF order limit (1..5)
};

struct SolverStats {
  long steps = 0;
  long rhs_evals = 0;
  long jac_evals = 0;
  long error_test_fails = 0;
};

class CvodeSolver {
 public:
  CvodeSolver(OdeSystem& system, double t0, const Eigen::VectorXd& x0, const SolverOptions& opts);
  ~CvodeSolver();
  CvodeSolver(const CvodeSolver&) = delete;
  CvodeSolver& operator=(const CvodeSolver&) = delete;

  // Integrates to t_out without stepping past it (the inputs may change there).
  void advance_to(double t_out) { advance_to(t_out, t_out); }
  // Returns the solution at t_out, letting CVODE step on as far as t_stop (>= t_out) while
  // the inputs are known to stay as they are; the state at t_out is then interpolated from
  // CVODE's Nordsieck history (CVodeGetDky) and later outputs up to the internal time need no
  // new steps. reinit() rolls back from such a look-ahead when an input changes after all.
  void advance_to(double t_out, double t_stop);
  double internal_time() const;  // CVODE's own time, >= time()
  // Restart from (t, x): after a discontinuous state change.
  void reinit(double t, const Eigen::VectorXd& x);
  void set_max_step(double max_step_s);

  double time() const { return t_; }
  const Eigen::VectorXd& state() const { return x_; }
  SolverStats stats() const;

 private:
  void set_tolerances(const SolverOptions& opts, long n);
  struct Impl;
  Impl* impl_;
  double t_;
  Eigen::VectorXd x_;
};

}  // namespace plantsim
