#include "rig/ident/structure_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rig/ident/output_error.hpp"
#include "rig/ident/srivc.hpp"

namespace rig::ident {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct MethodName {
  IdentMethod method;
  const char* name;
};
constexpr MethodName kMethodNames[] = {{IdentMethod::kMmfm, "mmfm"},
                                       {IdentMethod::kMmfmOe, "mmfm+oe"},
                                       {IdentMethod::kSrivc, "srivc"}};

std::pair<Eigen::Index, Eigen::Index> span(const RecordSet& r, std::size_t i) {
  const Eigen::Index end = i + 1 < r.starts.size() ? r.starts[i + 1] : r.size();
  return {r.starts[i], end - r.starts[i]};
}

template <class Correlate>
signal::Correlation averaged(const RecordSet& r, Correlate correlate) {
  signal::Correlation sum;
  double total = 0.0;
  for (std::size_t i = 0; i < r.starts.size(); ++i) {
    const auto [b, len] = span(r, i);
    const signal::Correlation c = correlate(b, len);
    const double w = static_cast<double>(len);
    if (i == 0) {
      sum = c;
      sum.r *= w;
    } else {
      sum.r += w * c.r;
    }
    total += w;
  }
  sum.r /= total;
  return sum;
}

MmfmResult mmfm_estimate(const RecordSet& est, double dt_s, const Structure& s,
                         const StructureTableOptions& opt) {
  signal::CorrelatorOptions co = opt.correlator;
  co.dt_s = dt_s;
  MmfmOptions mo = opt.mmfm;
  mo.order = s.order;
  mo.delay_s = s.delay_estimated ? std::nullopt : std::optional<double>(opt.delay_s.value_or(0.0));
  mo.max_delay_s = opt.max_delay_s;
  return estimate_mmfm(averaged_auto_correlation(est, co), averaged_cross_correlation(est, co), mo);
}

model::TransferFunction srivc_model(const RecordSet& est, double dt_s, const Structure& s,
                                    const StructureTableOptions& opt) {
  SrivcOptions so;
  so.order = s.order;
  so.delay_s = s.delay_estimated ? std::nullopt : std::optional<double>(opt.delay_s.value_or(0.0));
  if (opt.max_delay_s > 0) so.max_delay_s = opt.max_delay_s;
  so.starts = est.starts;
  return estimate_srivc(est.u, est.y, dt_s, so).model;
}

double mean_square(const Eigen::VectorXd& e) {
  return e.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, e.size()));
}

void score_validation(StructureFit& f, const RecordSet& val, double dt_s,
                      const StructureTableOptions& opt) {
  model::TransferFunction shifted = f.model;
  shifted.delay_s = std::max(0.0, shifted.delay_s + opt.validation_delay_shift_s);
  const Eigen::Index n = val.size() - opt.validation_from;
  f.validation_fit_pct = model::fit_percent(val.y.tail(n), val.simulate(shifted, dt_s).tail(n));
}

// The rule of the header: adequate = within the margin of the best, chosen = the simplest.
void choose(StructureTable& t, double margin_pct) {
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const StructureFit& f = t.rows[i];
    if (f.ok && (t.best < 0 || f.validation_fit_pct > t.rows[t.best].validation_fit_pct))
      t.best = static_cast<int>(i);
  }
  if (t.best < 0) return;
  const double floor_pct = t.rows[t.best].validation_fit_pct - margin_pct;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    StructureFit& f = t.rows[i];
    f.adequate = f.ok && f.validation_fit_pct >= floor_pct;
    if (!f.adequate) continue;
    const StructureFit* c = t.chosen_fit();
    const int p = f.structure.parameters();
    if (!c || p < c->structure.parameters() ||
        (p == c->structure.parameters() && f.validation_fit_pct > c->validation_fit_pct))
      t.chosen = static_cast<int>(i);
  }
  t.rule = fmt::format(
      "the simplest structure (fewest parameters, then the higher validation fit) whose "
      "validation fit is within {:g} points of the best ({:.1f} %, {})",
      margin_pct, t.rows[t.best].validation_fit_pct, t.rows[t.best].structure.name());
}

}  // namespace

const char* to_string(IdentMethod method) {
  for (const MethodName& m : kMethodNames)
    if (m.method == method) return m.name;
  return "?";
}

std::optional<IdentMethod> ident_method_from(std::string_view text) {
  for (const MethodName& m : kMethodNames)
    if (text == m.name) return m.method;
  return std::nullopt;
}

std::string Structure::name() const {
  return fmt::format("{}/{}{} {}", order.n, order.m, delay_estimated ? " +Td" : "",
                     to_string(method));
}

void RecordSet::add(const Eigen::VectorXd& u_raw, const Eigen::VectorXd& y_raw) {
  if (u_raw.size() != y_raw.size() || u_raw.size() == 0)
    throw std::invalid_argument("RecordSet: u and y must be equally long and non-empty");
  const Eigen::Index at = u.size();
  starts.push_back(at);
  u.conservativeResize(at + u_raw.size());
  y.conservativeResize(at + y_raw.size());
  u.tail(u_raw.size()) = u_raw.array() - u_raw.mean();
  y.tail(y_raw.size()) = y_raw.array() - y_raw.mean();
}

Eigen::VectorXd RecordSet::simulate(const model::TransferFunction& tf, double dt_s) const {
  return model::simulate(tf, u, dt_s, starts);
}

signal::Correlation averaged_auto_correlation(const RecordSet& r,
                                              const signal::CorrelatorOptions& co) {
  return averaged(r, [&](Eigen::Index b, Eigen::Index len) {
    return signal::auto_correlation(r.u.segment(b, len), co);
  });
}

signal::Correlation averaged_cross_correlation(const RecordSet& r,
                                               const signal::CorrelatorOptions& co) {
  return averaged(r, [&](Eigen::Index b, Eigen::Index len) {
    return signal::cross_correlation(r.y.segment(b, len), r.u.segment(b, len), co);
  });
}

std::vector<Structure> table_structures(const StructureTableOptions& opt) {
  std::vector<model::ModelOrder> orders;
  if (opt.order) {
    orders.push_back(*opt.order);
  } else {
    for (int n = 1; n <= opt.max_order; ++n)
      for (int m = 0; m < n; ++m) orders.push_back({n, m});
  }
  std::vector<Structure> out;
  for (const model::ModelOrder& o : orders)
    for (IdentMethod method : opt.methods) {
      if (!opt.delay_s) out.push_back({o, true, method});
      if (opt.delay_s || opt.without_delay) out.push_back({o, false, method});
    }
  return out;
}

StructureFit fit_structure(const RecordSet& est, double dt_s, const Structure& s,
                           const StructureTableOptions& opt) {
  StructureFit f;
  f.structure = s;
  f.estimation_fit_pct = f.validation_fit_pct = f.aic = f.bic = f.condition_number = kNaN;
  try {
    if (s.method == IdentMethod::kSrivc) {
      f.model = srivc_model(est, dt_s, s, opt);
    } else {
      const MmfmResult r = mmfm_estimate(est, dt_s, s, opt);
      f.model = model::monic(r.model);
      f.mmfm_settings = r.settings;
      f.condition_number = r.condition_number;
      if (s.method == IdentMethod::kMmfmOe) {
        f.model =
            refine_output_error(est.u, est.y, dt_s, f.model, s.delay_estimated, est.starts).model;
      }
    }
  } catch (const std::invalid_argument& e) {
    f.error = e.what();  // e.g. an order whose functions do not fit the correlation window
    return f;
  }
  if (!f.model.is_stable() || !f.model.den.allFinite() || !f.model.num.allFinite()) {
    f.error = "unstable or non-finite model";
    return f;
  }
  const Eigen::VectorXd e = est.y - est.simulate(f.model, dt_s);
  const double n = static_cast<double>(est.size()), v = mean_square(e);
  const int p = s.parameters();
  f.estimation_fit_pct = model::fit_percent(est.y, est.y - e);
  f.aic = n * std::log(v) + 2.0 * p;
  f.bic = n * std::log(v) + p * std::log(n);
  f.ok = std::isfinite(f.estimation_fit_pct);
  if (!f.ok) f.error = "non-finite simulation";
  return f;
}

StructureTable structure_table(const RecordSet& est, const RecordSet& val, double dt_s,
                               const StructureTableOptions& opt, const TableProgress& progress) {
  StructureTable t;
  const std::vector<Structure> structures = table_structures(opt);
  for (const Structure& s : structures) {
    StructureFit f = fit_structure(est, dt_s, s, opt);
    if (f.ok) score_validation(f, val, dt_s, opt);
    f.ok = f.ok && std::isfinite(f.validation_fit_pct);
    t.rows.push_back(std::move(f));
    if (progress) progress(static_cast<int>(t.rows.size()), static_cast<int>(structures.size()));
  }
  choose(t, opt.adequacy_margin_pct);
  return t;
}

}  // namespace rig::ident
