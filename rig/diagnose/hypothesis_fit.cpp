#include "rig/diagnose/hypothesis_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/governor_loop.hpp"

namespace rig::diagnose {
namespace {

double logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

double to_physical(const ParamSpec& s, double x) {
  const double t = logistic(x);
  return s.log_scale ? std::exp(std::log(s.lo) + (std::log(s.hi) - std::log(s.lo)) * t)
                     : s.lo + (s.hi - s.lo) * t;
}

double to_internal(const ParamSpec& s, double p) {
  double t = s.log_scale ? (std::log(p) - std::log(s.lo)) / (std::log(s.hi) - std::log(s.lo))
                         : (p - s.lo) / (s.hi - s.lo);
  if (!std::isfinite(t)) t = 0.5;
  t = std::clamp(t, 1e-3, 1.0 - 1e-3);
  return std::log(t / (1.0 - t));
}

// The searched vector: each effect's parameters, then its place's.
struct Layout {
  std::vector<AppliedEffect> shapes;  // effect and place; parameters unused
  std::vector<std::vector<ParamSpec>> specs, place_specs;
  int size = 0;
};

std::vector<AppliedEffect> unpack(const Layout& l, const Eigen::VectorXd& x) {
  std::vector<AppliedEffect> out;
  int k = 0;
  for (std::size_t i = 0; i < l.shapes.size(); ++i) {
    AppliedEffect e{l.shapes[i].effect, {}, l.shapes[i].place, {}};
    for (const auto& s : l.specs[i]) e.params.push_back(to_physical(s, x(k++)));
    for (const auto& s : l.place_specs[i]) e.place_params.push_back(to_physical(s, x(k++)));
    out.push_back(std::move(e));
  }
  share_feedback(out);  // the loop effect's feedback, not searched (governor_loop.hpp)
  return out;
}

// A residual beyond this is a model that ran away: its square, summed over any record,
// stays finite (1e300 x samples).
constexpr double kRunawayResidual = 1e150;

// The least-squares functor Eigen's LevenbergMarquardt expects.
struct Residual {
  using Scalar = double;
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };

  const Problem* problem;
  const Layout* layout;
  std::vector<Eigen::Index> rows;  // estimation samples
  int* calls = nullptr;            // shared by the copies NumericalDiff makes

  int inputs() const { return layout->size; }
  int values() const { return static_cast<int>(rows.size()); }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& f) const {
    ++*calls;
    const auto effects = unpack(*layout, x);
    const Eigen::VectorXd yhat = model_output(*problem, effects).yhat;
    f.resize(values());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Eigen::Index k = rows[i];
      f(static_cast<Eigen::Index>(i)) = problem->y(k) - yhat(k);
    }
    // A model that did not settle (NaN) or ran away (a residual whose square overflows):
    // one large constant, so that the search backs off and the cost stays finite.
    if (!f.allFinite() || f.cwiseAbs().maxCoeff() > kRunawayResidual)
      f.setConstant(kRunawayResidual);
    return 0;
  }
};

}  // namespace

std::string HypothesisFit::name() const {
  std::string s;
  for (const auto& e : effects) {
    if (!s.empty()) s.push_back('+');
    s.append(to_string(e.effect));
  }
  return s;
}

int HypothesisFit::parameter_count() const {
  int n = 0;
  for (const auto& e : effects) {
    n += static_cast<int>(acting_params(e) + e.place_params.size());
    n += effect_model(e.effect).regressor_columns;  // e.g. amplitude and phase by LS
  }
  if (const auto s = shared_feedback(effects))
    n -= static_cast<int>(effects[s->loop].place_params.size());
  return n;
}

HypothesisFit fit_hypothesis(const Problem& pr,
                             const std::vector<std::vector<AppliedEffect>>& starts,
                             const Eigen::VectorXd& baseline_yhat, const FitOptions& options) {
  Layout layout;
  const auto shared = shared_feedback(starts.front());
  for (std::size_t i = 0; i < starts.front().size(); ++i) {
    const AppliedEffect& e = starts.front()[i];
    layout.shapes.push_back(e);
    layout.specs.push_back(parameter_specs(e.effect, pr.scales));
    layout.place_specs.push_back(shared && shared->loop == i ? std::vector<ParamSpec>{}
                                                             : place_specs(e.place, pr.scales));
    layout.size += static_cast<int>(layout.specs.back().size() + layout.place_specs.back().size());
  }
  int calls = 0;
  Residual fn{&pr, &layout, {}, &calls};
  for (Eigen::Index k = 0; k < pr.y.size(); ++k)
    if (pr.est_weight(k) > 0.0) fn.rows.push_back(k);
  // Every starting point is evaluated once; only the best few are searched from.
  std::vector<std::pair<double, Eigen::VectorXd>> points;
  for (const auto& start : starts) {
    Eigen::VectorXd x(layout.size), f;
    int k = 0;
    for (std::size_t i = 0; i < start.size(); ++i) {
      for (std::size_t j = 0; j < start[i].params.size(); ++j)
        x(k++) = to_internal(layout.specs[i][j], start[i].params[j]);
      for (std::size_t j = 0; j < layout.place_specs[i].size(); ++j)
        x(k++) = to_internal(layout.place_specs[i][j], start[i].place_params[j]);
    }
    fn(x, f);
    points.emplace_back(f.squaredNorm(), std::move(x));
  }
  std::stable_sort(points.begin(), points.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  if (points.size() > options.searched_starts) points.resize(options.searched_starts);
  // The best start as evaluated stands when no search ends with a finite cost.
  double best_cost = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x = points.front().second;
  for (auto& point : points) {
    Eigen::VectorXd& x = point.second;
    Eigen::NumericalDiff<Residual> diff(fn);
    Eigen::LevenbergMarquardt<Eigen::NumericalDiff<Residual>> lm(diff);
    lm.parameters.maxfev = options.max_evaluations;
    lm.parameters.xtol = 1e-6;
    lm.parameters.ftol = 1e-7;
    lm.minimize(x);
    Eigen::VectorXd f;
    fn(x, f);
    const double cost = f.squaredNorm();
    if (cost < best_cost) best_cost = cost, best_x = x;
  }
  HypothesisFit h = score_hypothesis(pr, unpack(layout, best_x), baseline_yhat, options);
  h.evaluations = calls;
  return h;
}

HypothesisFit score_hypothesis(const Problem& pr, std::vector<AppliedEffect> effects,
                               const Eigen::VectorXd& baseline_yhat, const FitOptions& options) {
  HypothesisFit h;
  h.effects = std::move(effects);
  ModelOutput mo = model_output(pr, h.effects);
  h.yhat = std::move(mo.yhat);
  h.tf = mo.tf;
  h.derived = std::move(mo.derived);
  h.active_from = pr.active_from;
  h.active_to = pr.active_to;
  h.fit_before = weighted_fit_pct(pr.y, baseline_yhat, pr.est_weight);
  h.fit_after = weighted_fit_pct(pr.y, h.yhat, pr.est_weight);
  h.validation_fit_before = weighted_fit_pct(pr.y, baseline_yhat, pr.val_weight);
  h.validation_fit_after = weighted_fit_pct(pr.y, h.yhat, pr.val_weight);
  h.score = h.validation_fit_after - h.validation_fit_before -
            options.penalty_pct_per_parameter * h.parameter_count();
  // A model whose output did not settle (a feedback loop that did not converge) explains
  // nothing: it ranks last, and a NaN would break the ranking's order.
  if (!std::isfinite(h.score)) h.score = -std::numeric_limits<double>::infinity();
  return h;
}

}  // namespace rig::diagnose
