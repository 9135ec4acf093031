#include "rig/session/live_messages.hpp"

#include <cmath>
#include <vector>

#include "rig/model/frf.hpp"
#include "rig/session/excitation_analysis.hpp"

namespace rig::session {
namespace {

// A JSON number, or null for NaN/inf (JSON has neither).
nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

double db(double mag) { return mag > 0.0 ? 20.0 * std::log10(mag) : std::nan(""); }

}  // namespace

nlohmann::json estimate_message(const BlockEstimate& e, double timing_correction_s) {
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : e.parameters) {
    parameters.push_back(
        {{"name", p.name}, {"value", number(p.value)}, {"std_error", number(p.std_error)}});
  }
  nlohmann::json j = {{"t_s", e.t_s},
                      {"block", e.block},
                      {"ok", e.ok},
                      {"order", e.order.n},
                      {"parameters", parameters},
                      {"delay_s", number(plant_delay_s(e.delay_s, timing_correction_s))},
                      {"band_db95", number(e.band_db95)},
                      {"band_deg95", number(e.band_deg95)},
                      {"fit_pct", number(e.fit_pct)}};
  if (!e.ok) j["error"] = e.error;
  if (e.derived.valid) {
    j["derived"] = {{"gain", number(e.derived.gain)},   {"gain_std", number(e.derived.gain_std)},
                    {"fn_hz", number(e.derived.fn_hz)}, {"fn_hz_std", number(e.derived.fn_hz_std)},
                    {"zeta", number(e.derived.zeta)},   {"zeta_std", number(e.derived.zeta_std)}};
  }
  return j;
}

nlohmann::json bode_message(const model::TransferFunction& model, double from_hz, double to_hz,
                            double timing_correction_s, double t_s) {
  constexpr int kPoints = 80;  // smooth at any page width, small on the wire
  std::vector<model::FrfPoint> frf(kPoints);
  for (int i = 0; i < kPoints; ++i) {
    const double f = from_hz * std::pow(to_hz / from_hz, i / (kPoints - 1.0));
    const auto h = model.response(f);
    frf[static_cast<std::size_t>(i)].freq_hz = f;
    frf[static_cast<std::size_t>(i)].mag = std::abs(h);
    frf[static_cast<std::size_t>(i)].phase_deg = std::arg(h) * 180.0 / M_PI;
  }
  model::add_delay(frf, timing_correction_s);
  model::unwrap_phase_deg(frf);
  nlohmann::json f_hz = nlohmann::json::array(), mag_db = nlohmann::json::array(),
                 phase = nlohmann::json::array();
  for (const auto& p : frf) {
    f_hz.push_back(p.freq_hz);
    mag_db.push_back(number(db(p.mag)));
    phase.push_back(number(p.phase_deg));
  }
  return {{"t_s", t_s}, {"f_hz", f_hz}, {"mag_db", mag_db}, {"phase_deg", phase}};
}

nlohmann::json sweep_point_message(const fra::SteppedSineResult& r, double timing_correction_s,
                                   double t_s) {
  std::vector<model::FrfPoint> one{r.frf_point()};
  model::add_delay(one, timing_correction_s);
  return {{"t_s", t_s},
          {"f_hz", one[0].freq_hz},
          {"mag_db", number(db(one[0].mag))},
          {"phase_deg", number(one[0].phase_deg)},
          {"coherence", number(one[0].coherence)},
          {"good", r.good}};
}

}  // namespace rig::session
