// What `rig diagnose` writes (DESIGN.md sections 4 and 9): report.json with the documented
// keys, report.html, and the augmented model (model JSON of section 5 with the new blocks
// described in extra keys).
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/diagnose/diagnose.hpp"
#include "rig/model/model_file.hpp"

namespace rig::report {
class HtmlReport;
}  // namespace rig::report

namespace rig::diagnose {

struct ReportContext {
  std::string recording;  // file names as given
  std::string model;
  std::string input_column = "u", output_column = "y";
};

nlohmann::json report_json(const DiagnoseResult& result, const ReportContext& context);

// The chosen hypothesis applied to the baseline: the linear part as the TF, every effect in
// "augmentation" (effect, params, where it acts), the baseline in "baseline". With no chosen
// hypothesis the baseline is returned with "augmentation": [].
model::ModelFile augmented_model(const DiagnoseResult& result, const model::ModelFile& baseline);

// `more` adds sections after the verdict's key values (the plant outputs of a plant TOML).
void write_report_html(const DiagnoseResult& result, const ReportContext& context,
                       const std::filesystem::path& file,
                       const std::function<void(report::HtmlReport&)>& more = {});

}  // namespace rig::diagnose
