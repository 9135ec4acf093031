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

void final_estimate(OnlineMmfm& online, double correction_s, ExcitationResult& out) {
  try {
    auto& m = out.mmfm.emplace(online.final_result());
    out.order_choice = online.final_choice();
    if (out.order_choice) {
      for (auto& c : out.order_choice->candidates) {
        c.model.delay_s = std::max(0.0, c.model.delay_s + correction_s);
      }
    }
    m.delay_s = std::max(0.0, m.delay_s + correction_s);
    m.model.delay_s = m.delay_s;
    if (!m.parameters.empty() && m.parameters.back().name == "delay_s") {
      m.parameters.back().value = m.delay_s;
    }
  } catch (const std::exception& ex) {
    out.mmfm.reset();
    out.mmfm_error = ex.what();
  }
}

std::vector<fra::FrfPoint> h1(const ExcitationRecord& r, const TestConfig& c) {
  fra::WelchOptions w;
  w.segment_length = std::min<Eigen::Index>(1024, static_cast<Eigen::Index>(r.u_pct.size()) / 4);
  w.f_min_hz = 0.05;
  w.f_max_hz = std::min(0.5 / r.dt_s, 2.0 * c.sweep.to_hz);
  auto frf = fra::h1_estimate(as_vector(r.u_pct), as_vector(r.y_kw), r.dt_s, w);
  for (auto& p : frf) {
    p.phase_deg = fra::wrap_deg(p.phase_deg - 360.0 * p.freq_hz * r.timing_correction_s);
  }
  return frf;
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

void analyse_excitation(OnlineMmfm& online, const ExcitationRecord& r, const TestConfig& c,
                        ExcitationResult& out) {
  online.finish();
  out.duration_s = static_cast<double>(r.u_pct.size()) * r.dt_s;
  out.history = online.history();
  for (auto& h : out.history) {
    h.delay_s += r.timing_correction_s;
    if (h.ok) h.model.delay_s = h.delay_s;
  }
  out.ruu = online.ruu();
  out.ryu = online.ryu();
  final_estimate(online, r.timing_correction_s, out);
  if (r.u_pct.size() >= 512) out.h1 = h1(r, c);
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
