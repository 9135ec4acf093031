#include "tests/integration/commission/run_rig.hpp"

#include <sys/wait.h>

#include <cmath>
#include <complex>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "rig/model/model_file.hpp"
#include "tests/support/scratch_dir.hpp"

namespace rig::testing {

std::filesystem::path bin_dir() {
  const char* d = std::getenv("RIG_BIN_DIR");
  return d != nullptr ? std::filesystem::path(d) : std::filesystem::path("build/bin");
}

std::filesystem::path source_dir() {
  const char* d = std::getenv("RIG_SOURCE_DIR");
  return d != nullptr ? std::filesystem::path(d) : std::filesystem::current_path();
}

std::filesystem::path fresh_dir(const std::string& name) {
  return rig::testing::scratch_dir("rig-commission-", name);
}

int run_rig(const std::string& args, const std::filesystem::path& log) {
  const std::string cmd =
      (bin_dir() / "rig").string() + " " + args + " > " + log.string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json read_json(const std::filesystem::path& path) {
  return nlohmann::json::parse(read_text(path));
}

TruthError error_against_truth(const std::filesystem::path& model_json) {
  const auto model = model::read_model(model_json).tf;
  const auto truth = model::read_model(source_dir() / "plantsim/presets/stornoway.tf.json").tf;
  TruthError e;
  for (int i = 0; i < 40; ++i) {
    const double f = 0.5 * std::pow(10.0, i / 39.0);  // 0.5 .. 5 Hz
    const std::complex<double> ratio = model.response(f) / truth.response(f);
    e.max_db = std::max(e.max_db, std::abs(20.0 * std::log10(std::abs(ratio))));
    e.max_deg = std::max(e.max_deg, std::abs(std::arg(ratio) * 180.0 / M_PI));
  }
  return e;
}

}  // namespace rig::testing
