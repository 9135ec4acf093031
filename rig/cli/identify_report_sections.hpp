// Sections of `rig identify`'s report.html (identify_report_html.cpp writes the page).
#pragma once

#include <vector>

#include "rig/cli/identify_report.hpp"
#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"

namespace rig::cli {

// The fit table as seed 001's Table 1 (validation fit by order and estimator), the rule, and
// the adequate structures with AIC and BIC.
void fit_table_block(report::HtmlReport& page, const IdentifyContext& ctx,
                     const ident::IdentifyResult& result);

// Measured against model output on the validation data, and the residual tests.
void validation_block(report::HtmlReport& page, const ident::IdentifyResult& result, double dt_s);

// The model's response at the band's frequencies (freqs_hz, filled) with the simultaneous
// 95 % band of the asymptotic covariance in magnitude and phase.
void bode_band_curve(const ident::IdentifyResult& result, report::BodeCurve& model,
                     std::vector<double>& freqs_hz);

}  // namespace rig::cli
