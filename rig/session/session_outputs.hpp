// The files a commissioning test leaves in --out DIR (DESIGN.md section 4): model.json,
// sweep.csv, h1.csv, report.json (keys documented in docs/test-file.md) and report.html.
// recording.csv and its sidecar are written during the test by the recorder.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "rig/session/session.hpp"

namespace rig::session {

nlohmann::json report_json(const SessionData& data);
void write_report_html(const SessionData& data, const std::filesystem::path& path);
// Writes every output that the data supports; never throws for a missing part.
bool write_outputs(const SessionData& data, const std::filesystem::path& out_dir);

}  // namespace rig::session
