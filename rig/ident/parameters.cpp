#include "rig/ident/parameters.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rig::ident {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double quad_form(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov) {
  if (cov.rows() != g.size()) return kNaN;
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

}  // namespace

const char* to_string(Normalisation normalisation) {
  return normalisation == Normalisation::kMonicDen ? "a_n = 1" : "b_0 = 1";
}

Eigen::VectorXd pack_parameters(const model::TransferFunction& tf) {
  Eigen::VectorXd theta(tf.den.size() + tf.num.size());
  theta << tf.den, tf.num;
  return theta;
}

model::TransferFunction unpack_parameters(const Eigen::VectorXd& theta, model::ModelOrder order,
                                          double delay_s) {
  if (theta.size() != order.n + order.m + 2)
    throw std::invalid_argument("unpack_parameters: theta has " + std::to_string(theta.size()) +
                                " entries, expected n + m + 2");
  return {theta.tail(order.m + 1), theta.head(order.n + 1), delay_s};
}

std::vector<std::string> parameter_names(model::ModelOrder order) {
  std::vector<std::string> names;
  // Built with append: GCC 12 warns falsely (-Wrestrict) on "a" + std::to_string(i).
  auto name = [](char letter, int power) {
    std::string s(1, letter);
    s.append(std::to_string(power));
    return s;
  };
  for (int i = order.n; i >= 0; --i) names.push_back(name('a', i));
  for (int j = order.m; j >= 0; --j) names.push_back(name('b', j));
  return names;
}

model::TransferFunction normalise(const model::TransferFunction& tf, Normalisation normalisation,
                                  Eigen::MatrixXd* cov) {
  const Eigen::VectorXd theta = pack_parameters(tf);
  const Eigen::Index ref = normalisation == Normalisation::kMonicDen ? 0 : theta.size() - 1;
  const double r = theta(ref);
  if (r == 0.0) throw std::invalid_argument("normalise: reference coefficient is zero");
  if (cov != nullptr && cov->rows() == theta.size()) {
    // theta'_i = theta_i / theta_r: J = I / r - theta e_r^T / r^2.
    Eigen::MatrixXd jac = Eigen::MatrixXd::Identity(theta.size(), theta.size()) / r;
    jac.col(ref) -= theta / (r * r);
    *cov = jac * (*cov) * jac.transpose();
  }
  return {tf.num / r, tf.den / r, tf.delay_s};
}

std::vector<ParameterEstimate> parameter_table(const model::TransferFunction& tf,
                                               const Eigen::MatrixXd& cov, double delay_std_s) {
  const model::ModelOrder order{static_cast<int>(tf.den.size()) - 1,
                                static_cast<int>(tf.num.size()) - 1};
  const Eigen::VectorXd theta = pack_parameters(tf);
  const std::vector<std::string> names = parameter_names(order);
  std::vector<ParameterEstimate> table;
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double se = cov.rows() == theta.size() ? std::sqrt(std::max(0.0, cov(i, i))) : kNaN;
    table.push_back({names[static_cast<size_t>(i)], theta(i), se});
  }
  table.push_back({"delay_s", tf.delay_s, delay_std_s});
  return table;
}

DerivedFigures derived_figures(const model::TransferFunction& tf, const Eigen::MatrixXd& cov) {
  DerivedFigures out;
  if (tf.den.size() != 3) return out;
  const Eigen::Index p = tf.den.size() + tf.num.size();
  const double a2 = tf.den(0), a1 = tf.den(1), a0 = tf.den(2);
  const double b0 = tf.num(tf.num.size() - 1);
  if (!(a0 / a2 > 0.0)) return out;
  out.valid = true;
  out.gain = b0 / a0;
  const double wn = std::sqrt(a0 / a2);
  out.fn_hz = wn / (2.0 * M_PI);
  out.zeta = a1 / (2.0 * std::sqrt(a0 * a2));
  // Gradients with respect to theta = [a2 a1 a0, b_m .. b0].
  Eigen::VectorXd g_gain = Eigen::VectorXd::Zero(p), g_fn = g_gain, g_zeta = g_gain;
  g_gain(2) = -b0 / (a0 * a0);
  g_gain(p - 1) = 1.0 / a0;
  g_fn(0) = -wn / (2.0 * a2) / (2.0 * M_PI);
  g_fn(2) = wn / (2.0 * a0) / (2.0 * M_PI);
  g_zeta(0) = -out.zeta / (2.0 * a2);
  g_zeta(1) = 1.0 / (2.0 * std::sqrt(a0 * a2));
  g_zeta(2) = -out.zeta / (2.0 * a0);
  out.gain_std = quad_form(g_gain, cov);
  out.fn_hz_std = quad_form(g_fn, cov);
  out.zeta_std = quad_form(g_zeta, cov);
  return out;
}

}  // namespace rig::ident
