// libFuzzer target for the recording reader (and the sidecar/model JSON validators, which
// read untrusted files too). Any input must either parse into a consistent Recording or
// raise InputError with a one-line message; anything else (a crash, a sanitizer report, an
// abort below) is a bug. The streamed file reader (read_recording) must give exactly what
// the in-memory parser gives.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "rig/io/recording.hpp"
#include "rig/io/sidecar.hpp"
#include "rig/model/model_file.hpp"

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

void check_consistent(const rig::io::Recording& rec, const rig::io::ReadOptions& options) {
  require(rec.names.size() == rec.columns.size());
  require(rec.rows() >= options.min_rows);
  for (const auto& c : rec.columns) {
    require(c.size() == rec.rows());
    require(c.allFinite());
  }
  if (rec.time_s) {
    require(rec.time_s->size() == rec.rows());
    for (Eigen::Index i = 1; i < rec.time_s->size(); ++i)
      require((*rec.time_s)[i] > (*rec.time_s)[i - 1]);
  }
  if (options.require_time_base) require(rec.dt_s > 0.0 && std::isfinite(rec.dt_s));
  require(rec.sampling.jitter_max_s >= 0.0 && rec.sampling.jitter_rms_s >= 0.0);
}

void parse_with(std::string_view text, const rig::io::ReadOptions& options) {
  try {
    check_consistent(rig::io::parse_recording(text, "fuzz.csv", options), options);
  } catch (const rig::io::InputError& e) {
    require(std::string_view(e.what()).find('\n') == std::string_view::npos);
  }
}

struct Outcome {
  std::optional<rig::io::Recording> rec;
  std::string error;
};

template <class Read>
Outcome outcome(Read read) {
  Outcome out;
  try {
    out.rec = read();
  } catch (const rig::io::InputError& e) {
    out.error = e.what();
  }
  return out;
}

bool same(const rig::io::Recording& a, const rig::io::Recording& b) {
  if (a.names != b.names || a.scalars != b.scalars || a.dt_s != b.dt_s ||
      a.warnings != b.warnings || a.first_data_line != b.first_data_line ||
      a.time_name != b.time_name || a.time_s.has_value() != b.time_s.has_value()) {
    return false;
  }
  if (a.time_s && *a.time_s != *b.time_s) return false;
  for (std::size_t c = 0; c < a.columns.size(); ++c) {
    if (a.columns[c] != b.columns[c]) return false;
  }
  return true;
}

// The input as a file, read by read_recording (no sidecar), against parse_recording.
void compare_file_reader(std::string_view text) {
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("fuzz_recording_" + std::to_string(::getpid()) + ".csv"))
                                      .string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return;
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  std::fclose(f);
  if (!written) return;
  rig::io::ReadOptions options;
  options.read_sidecar = false;
  const Outcome from_file = outcome([&] { return rig::io::read_recording(path, options); });
  const Outcome from_text = outcome([&] { return rig::io::parse_recording(text, path, options); });
  std::remove(path.c_str());
  require(from_file.error == from_text.error);
  require(from_file.rec.has_value() == from_text.rec.has_value());
  if (from_file.rec) require(same(*from_file.rec, *from_text.rec));
}

void parse_json_documents(std::string_view text) {
  const nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr, false);
  if (doc.is_discarded()) return;
  try {
    rig::io::parse_sidecar(doc, "fuzz.json");
  } catch (const rig::io::InputError&) {
  }
  try {
    const rig::model::ModelFile m = rig::model::model_from_json(doc, "fuzz.json");
    require(m.tf.den.size() > 0 && m.tf.den[0] != 0.0 && m.tf.delay_s >= 0.0);
    rig::model::model_to_json(m);  // a model that was accepted must be writable
  } catch (const rig::io::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  rig::io::ReadOptions plain;
  parse_with(text, plain);
  rig::io::ReadOptions selected;
  selected.columns = {"u", "2"};
  selected.dt_s = 0.01;
  parse_with(text, selected);
  rig::io::ReadOptions table;
  table.require_time_base = false;
  table.min_rows = 1;
  parse_with(text, table);
  compare_file_reader(text);
  parse_json_documents(text);
  return 0;
}
