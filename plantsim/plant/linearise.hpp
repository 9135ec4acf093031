// Linearisation of the plant about its operating point (noise, ripple and drift play no part:
// they live in the output path) and the model file of DESIGN.md section 5.
//
// Central differences of the ODE right-hand side give the linear delay system
//   x' = A x + b u + b_f f(t - Td),   f = c_f x (rack),   y = c x
// with u the bias in % of rated power and y the electrical power in kW after the transducer.
// The fuel dead time sits inside the governor's power/speed feedback, so the exact response
//   H(jw) = c (jw I - A - b_f c_f e^{-jw Td})^{-1} b
// is not a rational function times e^{-s Td}. The model file's TF is the rational part
// num(s)/den(s) of H(s) e^{s Td}, fitted (Sanathanan-Koerner iterations, relative error) on a
// log grid over fit_band_hz; the largest deviation from the exact H is stored with it.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <filesystem>

#include "plantsim/plant/parameters.hpp"
#include "plantsim/plant/plant.hpp"
#include "rig/model/transfer_function.hpp"

namespace plantsim {

// Second order plus dead time K e^{-s T} / (s^2/wn^2 + 2 zeta s/wn + 1) fitted to the exact
// response over a band (what the identification estimates), with its worst deviation there.
struct SopdtFit {
  double gain_kw_per_pct = 0.0;
  double fn_hz = 0.0;
  double zeta = 0.0;
  double delay_s = 0.0;
  double max_error_db = 0.0;
  double max_error_deg = 0.0;
  std::complex<double> response(double freq_hz) const;
};

struct LinearModel {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;          // per % of rated power
  Eigen::VectorXd b_fuel;     // per pu of delayed rack position
  Eigen::RowVectorXd c;       // kW
  Eigen::RowVectorXd c_fuel;  // rack position, pu
  double delay_s = 0.0;       // fuel dead time

  // The model file's TF: the rational part num/den (highest power first, den monic) with
  // e^{-s delay_s}; its response, simulation and JSON are rig_model's (DESIGN.md section 3).
  rig::model::TransferFunction tf;
  double fit_band_lo_hz = 0.0, fit_band_hi_hz = 0.0;
  double tf_max_error_db = 0.0, tf_max_error_deg = 0.0;

  double fn_hz = 0.0;  // electromechanical mode (least damped pole pair of den)
  double zeta = 0.0;
  double dc_gain_kw_per_pct = 0.0;
  SopdtFit sopdt;  // best SOPDT over 0.5-5 Hz
  std::string preset;

  std::complex<double> response(double freq_hz) const;  // exact, delay in the loop
};

LinearModel linearise(const PlantOptions& options);
LinearModel linearise(const Params& params, const std::string& name);
// The model file of DESIGN.md section 5 (rig::model::write_model): model.tf with
// "input":"bias_pct", "output":"power_kw", "units", and "source" and "derived" (how it was
// obtained, the mode, the DC gain and the SOPDT fit). Throws rig::model::InputError when the
// file cannot be written.
void write_tf_json(const LinearModel& model, const std::filesystem::path& file);

// Rational fit of g(jw) on freqs_hz: num order m, den order n (den(0) = 1 before making it
// monic). Returns false if the fit failed (singular or unstable).
bool fit_rational(const Eigen::VectorXd& freqs_hz, const Eigen::VectorXcd& g, int n, int m,
                  Eigen::VectorXd* num, Eigen::VectorXd* den);
SopdtFit fit_sopdt(const LinearModel& model, double lo_hz, double hi_hz);

}  // namespace plantsim
