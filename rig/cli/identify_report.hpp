// report.json, report.html, model.json and the terminal summary of `rig identify`.
// The report keys are documented in docs/identify.md.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/cli/identify_records.hpp"
#include "rig/cli/identify_rows.hpp"
#include "rig/ident/identify.hpp"
#include "rig/ident/quality.hpp"
#include "rig/io/recording.hpp"
#include "rig/model/model_file.hpp"

namespace rig::cli {

// What `rig identify` read and how it was asked to run.
struct IdentifyContext {
  const io::Recording* recording = nullptr;
  std::string input;  // column names
  std::string output;
  std::string method;                    // --method as given ("all", "mmfm,srivc", ...)
  std::string order_arg;                 // "auto" | "n/m"
  std::string delay_arg;                 // "auto" | seconds
  signal::CorrelatorOptions correlator;  // as used (dt_s set)
  double estimation_fraction = 0.5;
  RowSelection rows;                                     // which rows of the file `recording` holds
  const std::vector<IdentifyRecord>* records = nullptr;  // every record, `recording` first
  // Added to dead times identified on the rows to refer them to the plant (sidecar
  // y_sampled_after_s); empty: they refer to the rows.
  std::optional<double> timing_correction_s;
  std::string no_model;  // why there is no model though the quality checks passed
  bool separate_validation() const {
    return records && !records->empty() && records->back().role == "validation";
  }
};

// result == nullptr: the data-quality checks stopped the run (status "data_quality_failed"),
// or no structure gave a stable model (ctx.no_model; status "no_stable_model").
nlohmann::json identify_report_json(const IdentifyContext& ctx, const ident::QualityReport& quality,
                                    const ident::IdentifyResult* result);

model::ModelFile identify_model_file(const IdentifyContext& ctx,
                                     const ident::IdentifyResult& result);

// ruu/ryu: the correlations to plot (the result's own when it exists).
void write_identify_html(const std::filesystem::path& path, const IdentifyContext& ctx,
                         const ident::QualityReport& quality, const ident::IdentifyResult* result,
                         const signal::Correlation& ruu, const signal::Correlation& ryu);

std::string identify_summary(const IdentifyContext& ctx, const ident::QualityReport& quality,
                             const ident::IdentifyResult* result,
                             const std::filesystem::path& out_dir);

// "0.07 s^2 + 0.19 s + 11.05" (highest power first).
std::string polynomial_text(const Eigen::VectorXd& coefficients);

}  // namespace rig::cli
