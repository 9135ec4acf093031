#include "rig/session/excitation_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/fra/h1.hpp"
#include "rig/ident/quality.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::session {
namespace {

using ConstMap = Eigen::Map<const Eigen::VectorXd>;

ConstMap as_vector(const std::vector<double>& v) {
  return ConstMap(v.data(), static_cast<Eigen::Index>(v.size()));
}

void final_estimate(OnlineMmfm& online, ExcitationResult& out) {
  try {
    out.mmfm.emplace(online.final_result());
    out.order_choice = online.final_choice();
  } catch (const std::exception& ex) {
    out.mmfm.reset();
    out.mmfm_error = ex.what();
  }
}

// An estimate's dead time, and its delay_s parameter when it has one, moved to the plant's.
void correct_delay(std::vector<ident::ParameterEstimate>& parameters, double& delay_s,
                   double correction_s) {
  delay_s = plant_delay_s(delay_s, correction_s);
  if (!parameters.empty() && parameters.back().name == "delay_s") {
    parameters.back().value = delay_s;
  }
}

// The sample-timing correction, applied once to everything the excitation yields: the live
// estimates, the final model and its candidate structures, and H1 (docs/decisions.md, "Sample
// timing correction").
void correct_timing(ExcitationResult& out, double correction_s) {
  for (auto& h : out.history) {
    correct_delay(h.parameters, h.delay_s, correction_s);
    if (h.ok) h.model.delay_s = h.delay_s;
  }
  if (out.order_choice) {
    for (auto& c : out.order_choice->candidates) {
      c.model.delay_s = plant_delay_s(c.model.delay_s, correction_s);
    }
  }
  if (out.mmfm) {
    correct_delay(out.mmfm->parameters, out.mmfm->delay_s, correction_s);
    out.mmfm->model.delay_s = out.mmfm->delay_s;
  }
  model::add_delay(out.h1, correction_s);
}

std::vector<model::FrfPoint> h1(const ExcitationRecord& r, const TestConfig& c) {
  fra::WelchOptions w;
  w.segment_length = std::min<Eigen::Index>(1024, static_cast<Eigen::Index>(r.u_pct.size()) / 4);
  w.f_min_hz = 0.05;
  w.f_max_hz = std::min(0.5 / r.dt_s, 2.0 * c.sweep.to_hz);
  return fra::h1_estimate(as_vector(r.u_pct), as_vector(r.y_kw), r.dt_s, w);
}

// The pre-estimation checks of rig/ident/quality, after the same matched AC coupling the
// online estimate used. Only fatal findings are kept.
std::vector<std::string> fatal_quality_flags(const ExcitationRecord& r, const TestConfig& c) {
  if (static_cast<long>(r.u_pct.size()) <= 4L * c.mmfm.lags) {
    return {"excitation record shorter than four correlation windows"};
  }
  ident::QualityOptions q;
  q.correlator.lags = c.mmfm.lags;
  q.correlator.skip = c.mmfm.skip;
  q.order = {c.mmfm.order_n, c.mmfm.order_m};
  q.delay_estimated = !c.mmfm.delay_s.has_value();
  std::vector<std::string> flags;
  try {
    const double rc = c.excitation.ac_coupling_rc_s;
    const Eigen::VectorXd u = as_vector(r.u_pct), y = as_vector(r.y_kw);
    const Eigen::VectorXd uc = rc > 0.0 ? signal::ac_couple(u, r.dt_s, rc) : u;
    const Eigen::VectorXd yc = rc > 0.0 ? signal::ac_couple(y, r.dt_s, rc) : y;
    for (const auto& f : ident::check_quality(uc, yc, r.dt_s, q).flags) {
      if (f.severity == ident::Severity::kFatal) flags.push_back(f.name + ": " + f.message);
    }
  } catch (const std::exception& e) {
    flags.push_back(std::string("data-quality check failed: ") + e.what());
  }
  return flags;
}

}  // namespace

double plant_delay_s(double estimated_delay_s, double timing_correction_s) {
  return std::max(0.0, estimated_delay_s + timing_correction_s);
}

void analyse_excitation(OnlineMmfm& online, const ExcitationRecord& r, const TestConfig& c,
                        ExcitationResult& out) {
  online.finish();
  out.duration_s = static_cast<double>(r.u_pct.size()) * r.dt_s;
  out.history = online.history();
  out.ruu = online.ruu();
  out.ryu = online.ryu();
  final_estimate(online, out);
  if (r.u_pct.size() >= 512) out.h1 = h1(r, c);
  correct_timing(out, r.timing_correction_s);
  const ConstMap u = as_vector(r.u_pct);
  if (u.size() > 1) {
    out.applied_std_pct =
        std::sqrt((u.array() - u.mean()).square().sum() / static_cast<double>(u.size() - 1));
  }
  out.quality_flags = fatal_quality_flags(r, c);
}

std::string why_no_model(const ExcitationResult& e, const TestConfig& c) {
  const double planned = e.planned_std_pct;
  const double share = planned > 0.0 ? e.applied_std_pct / planned : 0.0;
  if (share < c.mmfm.min_applied_fraction) {
    return fmt::format(
        "the applied excitation (std {:.4f} %) was {:.0f} % of the planned {:.4f} % "
        "(mmfm.min_applied_fraction = {:g}): the supervisor held it back",
        e.applied_std_pct, 100.0 * share, planned, c.mmfm.min_applied_fraction);
  }
  if (!e.quality_flags.empty()) {
    return "the excitation data fail a quality check: " + e.quality_flags.front();
  }
  if (!e.mmfm) return "the MMFM estimate failed: " + e.mmfm_error;
  if (!e.mmfm->model.is_stable()) return "the MMFM model is unstable";
  return "";
}

}  // namespace rig::session
