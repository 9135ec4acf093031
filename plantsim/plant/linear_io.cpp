// The model file (DESIGN.md section 5), written by rig_model's one model-file writer.
#include <nlohmann/json.hpp>

#include "plantsim/plant/linearise.hpp"
#include "rig/model/model_file.hpp"

namespace plantsim {

void write_tf_json(const LinearModel& m, const std::filesystem::path& file) {
  rig::model::ModelFile out;
  out.tf = m.tf;
  out.input = "bias_pct";
  out.output = "power_kw";
  out.units = {{"input", "% of rated power"}, {"output", "kW"}, {"time", "s"}};
  out.extra["source"] = {{"plant", m.preset},
                         {"method",
                          "central-difference linearisation about the operating point; "
                          "rational part fitted to H(s) e^{s delay_s}"},
                         {"fit_band_hz", {m.fit_band_lo_hz, m.fit_band_hi_hz}},
                         {"tf_max_error_db", m.tf_max_error_db},
                         {"tf_max_error_deg", m.tf_max_error_deg}};
  out.extra["derived"] = {{"fn_hz", m.fn_hz},
                          {"zeta", m.zeta},
                          {"dc_gain_kw_per_pct", m.dc_gain_kw_per_pct},
                          {"sopdt_0p5_5hz",
                           {{"gain_kw_per_pct", m.sopdt.gain_kw_per_pct},
                            {"fn_hz", m.sopdt.fn_hz},
                            {"zeta", m.sopdt.zeta},
                            {"delay_s", m.sopdt.delay_s},
                            {"max_error_db", m.sopdt.max_error_db},
                            {"max_error_deg", m.sopdt.max_error_deg}}}};
  rig::model::write_model(file, out);
}

}  // namespace plantsim
