#include "plantsim/solver/cvode_solver.hpp"

#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cstdlib>

namespace plantsim {
namespace {

std::string flag_name(int code) {
  char* name = CVodeGetReturnFlagName(code);
  std::string out = name != nullptr ? name : "unknown";
  std::free(name);  // CVodeGetReturnFlagName allocates with malloc
  return out;
}

int rhs_trampoline(realtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* system = static_cast<OdeSystem*>(user_data);
  // CVODE treats a positive return as recoverable (it retries with a smaller step).
  return system->derivatives(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
}

// Errors are reported through exceptions; CVODE's own stderr print-out is suppressed.
void silent_handler(int, const char*, const char*, char*, void*) {}

}  // namespace

SolverError::SolverError(const std::string& function, int code)
    : std::runtime_error(
          fmt::format("solver: {} failed with {} ({})", function, flag_name(code), code)),
      function_(function),
      code_(code) {}

void check_retval(int retval, const char* function) {
  if (retval < 0) throw SolverError(function, retval);
}

void check_ptr(const void* ptr, const char* function) {
  if (ptr == nullptr) throw SolverError(function, CV_MEM_FAIL);
}

struct CvodeSolver::Impl {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  SUNMatrix a = nullptr;
  SUNLinearSolver ls = nullptr;
  void* mem = nullptr;

  ~Impl() {
    if (mem != nullptr) CVodeFree(&mem);
    if (ls != nullptr) SUNLinSolFree(ls);
    if (a != nullptr) SUNMatDestroy(a);
    if (y != nullptr) N_VDestroy(y);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
};

CvodeSolver::CvodeSolver(OdeSystem& system, double t0, const Eigen::VectorXd& x0,
                         const SolverOptions& opts)
    : impl_(new Impl), t_(t0), x_(x0) {
  try {
    const auto n = static_cast<sunindextype>(system.size());
    check_retval(SUNContext_Create(nullptr, &impl_->ctx), "SUNContext_Create");
    impl_->y = N_VNew_Serial(n, impl_->ctx);
    check_ptr(impl_->y, "N_VNew_Serial");
    Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(impl_->y), n) = x0;
    impl_->mem = CVodeCreate(CV_BDF, impl_->ctx);
    check_ptr(impl_->mem, "CVodeCreate");
    check_retval(CVodeSetErrHandlerFn(impl_->mem, silent_handler, nullptr), "CVodeSetErrHandlerFn");
    check_retval(CVodeInit(impl_->mem, rhs_trampoline, t0, impl_->y), "CVodeInit");
    check_retval(CVodeSetUserData(impl_->mem, &system), "CVodeSetUserData");
    set_tolerances(opts, n);
    impl_->a = SUNDenseMatrix(n, n, impl_->ctx);
    check_ptr(impl_->a, "SUNDenseMatrix");
    impl_->ls = SUNLinSol_Dense(impl_->y, impl_->a, impl_->ctx);
    check_ptr(impl_->ls, "SUNLinSol_Dense");
    check_retval(CVodeSetLinearSolver(impl_->mem, impl_->ls, impl_->a), "CVodeSetLinearSolver");
    check_retval(CVodeSetMaxNumSteps(impl_->mem, opts.max_steps), "CVodeSetMaxNumSteps");
    check_retval(CVodeSetMaxOrd(impl_->mem, opts.max_order), "CVodeSetMaxOrd");
    set_max_step(opts.max_step_s);
  } catch (...) {
    delete impl_;
    throw;
  }
}

CvodeSolver::~CvodeSolver() { delete impl_; }

void CvodeSolver::set_tolerances(const SolverOptions& opts, long n) {
  if (opts.atol_scale.size() == 0) {
    check_retval(CVodeSStolerances(impl_->mem, opts.rtol, opts.atol), "CVodeSStolerances");
    return;
  }
  if (opts.atol_scale.size() != n) throw SolverError("CVodeSVtolerances", CV_ILL_INPUT);
  N_Vector atol = N_VClone(impl_->y);  // CVODE keeps its own copy
  check_ptr(atol, "N_VClone");
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(atol), n) = opts.atol * opts.atol_scale;
  const int retval = CVodeSVtolerances(impl_->mem, opts.rtol, atol);
  N_VDestroy(atol);
  check_retval(retval, "CVodeSVtolerances");
}

void CvodeSolver::set_max_step(double max_step_s) {
  check_retval(CVodeSetMaxStep(impl_->mem, max_step_s), "CVodeSetMaxStep");
}

void CvodeSolver::advance_to(double t_out, double t_stop) {
  if (t_out <= t_) return;
  realtype t_reached = t_;
  if (t_out <= internal_time()) {
    check_retval(CVodeGetDky(impl_->mem, t_out, 0, impl_->y), "CVodeGetDky");
    t_reached = t_out;
  } else {
    // CVODE clears the stop time once it is reached, so it is set on every call.
    check_retval(CVodeSetStopTime(impl_->mem, std::max(t_stop, t_out)), "CVodeSetStopTime");
    check_retval(CVode(impl_->mem, t_out, impl_->y, &t_reached, CV_NORMAL), "CVode");
  }
  t_ = t_reached;
  x_ = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(impl_->y), x_.size());
}

double CvodeSolver::internal_time() const {
  realtype tn = t_;
  check_retval(CVodeGetCurrentTime(impl_->mem, &tn), "CVodeGetCurrentTime");
  return tn;
}

void CvodeSolver::reinit(double t, const Eigen::VectorXd& x) {
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(impl_->y), x.size()) = x;
  check_retval(CVodeReInit(impl_->mem, t, impl_->y), "CVodeReInit");
  t_ = t;
  x_ = x;
}

SolverStats CvodeSolver::stats() const {
  SolverStats s;
  check_retval(CVodeGetNumSteps(impl_->mem, &s.steps), "CVodeGetNumSteps");
  check_retval(CVodeGetNumRhsEvals(impl_->mem, &s.rhs_evals), "CVodeGetNumRhsEvals");
  check_retval(CVodeGetNumJacEvals(impl_->mem, &s.jac_evals), "CVodeGetNumJacEvals");
  check_retval(CVodeGetNumErrTestFails(impl_->mem, &s.error_test_fails), "CVodeGetNumErrTestFails");
  return s;
}

}  // namespace plantsim
