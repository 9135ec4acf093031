// The model file (DESIGN.md section 5) and the exact step response of a TF with dead time.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "plantsim/plant/linearise.hpp"

namespace plantsim {

void write_tf_json(const LinearModel& m, const std::filesystem::path& file) {
  nlohmann::ordered_json j;
  j["type"] = "tf";
  j["num"] = std::vector<double>(m.num.data(), m.num.data() + m.num.size());
  j["den"] = std::vector<double>(m.den.data(), m.den.data() + m.den.size());
  j["delay_s"] = m.delay_s;
  j["input"] = "bias_pct";
  j["output"] = "power_kw";
  j["units"] = {{"input", "% of rated power"}, {"output", "kW"}, {"time", "s"}};
  j["source"] = {{"plant", m.preset},
                 {"method",
                  "central-difference linearisation about the operating point; "
                  "rational part fitted to H(s) e^{s delay_s}"},
                 {"fit_band_hz", {m.fit_band_lo_hz, m.fit_band_hi_hz}},
                 {"tf_max_error_db", m.tf_max_error_db},
                 {"tf_max_error_deg", m.tf_max_error_deg}};
  j["derived"] = {{"fn_hz", m.fn_hz},
                  {"zeta", m.zeta},
                  {"dc_gain_kw_per_pct", m.dc_gain_kw_per_pct},
                  {"sopdt_0p5_5hz",
                   {{"gain_kw_per_pct", m.sopdt.gain_kw_per_pct},
                    {"fn_hz", m.sopdt.fn_hz},
                    {"zeta", m.sopdt.zeta},
                    {"delay_s", m.sopdt.delay_s},
                    {"max_error_db", m.sopdt.max_error_db},
                    {"max_error_deg", m.sopdt.max_error_deg}}}};
  std::ofstream out(file);
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write the model file", file.string()));
  out << j.dump(2) << '\n';
  if (!out) throw std::runtime_error(fmt::format("{}: write failed", file.string()));
}

// Controllable companion form of num/den (den monic after scaling); the state after a unit
// step of age tau is x(tau) = int_0^tau e^{A r} dr B, evaluated with the augmented matrix
// exponential exp([[A, B], [0, 0]] tau), which needs no inverse of A.
Eigen::VectorXd tf_step_response(const Eigen::VectorXd& num, const Eigen::VectorXd& den,
                                 double delay_s, double amplitude, double t_step_s, double dt_s,
                                 int n_samples) {
  const Eigen::Index n = den.size() - 1;
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
  for (Eigen::Index i = 0; i < n; ++i) aug(0, i) = -den[i + 1] / den[0];
  for (Eigen::Index i = 1; i < n; ++i) aug(i, i - 1) = 1.0;
  aug(0, n) = 1.0;
  // y = C x with C from num padded to length n (strictly proper: num order < n).
  Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(n);
  for (Eigen::Index k = 0; k < num.size(); ++k) c[n - num.size() + k] = num[k] / den[0];
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_samples);
  const double t_on = t_step_s + delay_s;
  const Eigen::MatrixXd phi = (aug * dt_s).exp();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(n + 1);
  bool started = false;
  for (int k = 0; k < n_samples; ++k) {
    const double t = k * dt_s;
    if (t < t_on) continue;
    if (!started) {
      z.setZero();
      z[n] = 1.0;
      z = (aug * (t - t_on)).exp() * z;
      started = true;
    } else {
      z = phi * z;
    }
    y[k] = amplitude * (c * z.head(n))(0);
  }
  return y;
}

}  // namespace plantsim
