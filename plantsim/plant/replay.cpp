#include "plantsim/plant/replay.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace plantsim {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\"");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\"");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
  return out;
}

int column_index(const std::vector<std::string>& header, const std::string& name,
                 const std::string& where) {
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end()) {
    throw ConfigError(fmt::format("{}: no column '{}' in the header (found {})", where, name,
                                  fmt::join(header, ", ")));
  }
  return static_cast<int>(it - header.begin());
}

double number(const std::vector<std::string>& cells, int col, const std::string& where,
              const std::string& name) {
  if (col >= static_cast<int>(cells.size())) {
    throw ConfigError(fmt::format("{}: column '{}' missing", where, name));
  }
  const std::string& s = cells[static_cast<std::size_t>(col)];
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v)) {
    throw ConfigError(
        fmt::format("{}: column '{}': expected a finite number, found '{}'", where, name, s));
  }
  return v;
}

// Uniform sampling: every step within 1 % of the mean period (the tick is one period).
double sample_period(const std::vector<double>& t, const std::string& file) {
  if (t.size() < 2) throw ConfigError(fmt::format("{}: expected at least 2 rows", file));
  const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (!(dt > 0.0 && dt <= 0.1)) {
    throw ConfigError(
        fmt::format("{}: column 't': sample period {} s, expected 0 < dt <= 0.1 s", file, dt));
  }
  for (std::size_t k = 1; k < t.size(); ++k) {
    if (std::abs(t[k] - t[k - 1] - dt) > 0.01 * dt) {
      throw ConfigError(
          fmt::format("{}: column 't': step {} s at row {}, expected uniform sampling at {} s",
                      file, t[k] - t[k - 1], k + 1, dt));
    }
  }
  return dt;
}

}  // namespace

ReplayInput read_replay_csv(const std::filesystem::path& file, const std::string& column) {
  std::ifstream in(file);
  if (!in) throw ConfigError(fmt::format("{}: cannot open the replay input", file.string()));
  ReplayInput out;
  std::vector<std::string> header;
  int t_col = -1, u_col = -1;
  std::string line;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    const std::string where = fmt::format("{}:{}", file.string(), line_no);
    const auto cells = split(text);
    if (header.empty()) {
      header = cells;
      t_col = column_index(header, "t", where);
      u_col = column_index(header, column, where);
      continue;
    }
    out.t_s.push_back(number(cells, t_col, where, "t"));
    out.bias_pct.push_back(number(cells, u_col, where, column));
  }
  if (header.empty()) throw ConfigError(fmt::format("{}: expected a header row", file.string()));
  out.dt_s = sample_period(out.t_s, file.string());
  return out;
}

std::vector<std::string> deterministic_measurement_changes() {
  return {"meas.noise_kw=0@t=0", "meas.drift_kw=0@t=0", "meas.pickup_kw=0@t=0",
          "meas.quant_kw=0@t=0", "engine.ripple=0@t=0"};
}

std::vector<double> replay(const ReplayInput& input, PlantOptions options,
                           const PlantFactory& make) {
  options.tick = std::chrono::nanoseconds(std::llround(input.dt_s * 1e9));
  for (auto& c : deterministic_measurement_changes()) options.faults.push_back(c);
  const auto plant = make(options);
  std::vector<double> y(input.bias_pct.size());
  for (std::size_t k = 0; k < y.size(); ++k) {
    plant->set_bias_pct(input.bias_pct[k]);
    const Measurement m = plant->measure();
    if (m.fault) {
      throw std::runtime_error(
          fmt::format("replay: the plant solver failed before t = {:.3f} s", m.time_s));
    }
    y[k] = m.power_w / 1e3;
    plant->step();
  }
  return y;
}

void write_replay_csv(const std::filesystem::path& file, const ReplayInput& input,
                      const std::vector<double>& power_kw) {
  std::ofstream out(file);
  if (!out) throw ConfigError(fmt::format("{}: cannot write the replay output", file.string()));
  out << "t,u,power_kw\n";
  for (std::size_t k = 0; k < power_kw.size(); ++k) {
    out << fmt::format("{:.9g},{:.9g},{:.9g}\n", input.t_s[k], input.bias_pct[k], power_kw[k]);
  }
  if (!out) throw ConfigError(fmt::format("{}: cannot write the replay output", file.string()));
}

}  // namespace plantsim
