#include "rig/cli/identify_records.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace rig::cli {
namespace {

constexpr Eigen::Index kMinSamples = 128;
// Sample periods that differ by less than this share are the same (time-column rounding).
constexpr double kSamePeriodRelative = 1e-6;

[[noreturn]] void bad_option(const std::string& option, const std::string& expected) {
  throw io::InputError("rig identify", 0, "", option + ": " + expected);
}

// Which columns are input and output: --input/--output, else --columns I,J (1-based), else
// "u" and "y", else the only two data columns.
io::Recording read_columns(const std::string& path, const ColumnChoice& c, std::string& in,
                           std::string& out) {
  io::ReadOptions ro;
  ro.dt_s = c.dt_s;
  ro.min_rows = kMinSamples;
  in = c.input;
  out = c.output;
  if (!c.columns.empty()) {
    const auto comma = c.columns.find(',');
    if (comma == std::string::npos)
      bad_option("--columns", "expected I,J (1-based input and output columns)");
    in = c.columns.substr(0, comma);
    out = c.columns.substr(comma + 1);
  }
  if (in.empty() != out.empty()) bad_option("--input/--output", "give both columns, or neither");
  if (!in.empty()) {
    ro.columns = {in, out};
    io::Recording rec = io::read_recording(path, ro);
    in = rec.names[0];
    out = rec.names[1];
    return rec;
  }
  io::Recording rec = io::read_recording(path, ro);
  if (rec.has("u") && rec.has("y")) {
    in = std::string("u");
    out = std::string("y");
  } else if (rec.names.size() == 2) {
    in = rec.names[0];
    out = rec.names[1];
  } else {
    throw io::InputError(rec.source, 0, "",
                         fmt::format("{} data columns and no u/y: name the input and output "
                                     "with --input/--output or --columns I,J",
                                     rec.names.size()));
  }
  return rec;
}

void require_excitation(const io::Recording& rec, const std::string& in, const Eigen::VectorXd& u) {
  const double sd = std::sqrt((u.array() - u.mean()).square().mean());
  if (!(sd > 1e-12 * std::max(1.0, std::abs(u.mean())))) {
    throw io::InputError(rec.source, 0, in,
                         fmt::format("expected a varying input, found the constant {:.6g}: "
                                     "nothing excites the plant",
                                     u.mean()));
  }
}

// Sidecar "coupled_columns" name AC-coupled channels; a channel X_ac with its raw source X
// in the same recording lets the quality check measure each network's time constant.
std::vector<ident::CoupledPair> coupled_pairs(const std::string& path, const io::Recording& rec,
                                              const RowSelection& rows) {
  std::vector<ident::CoupledPair> pairs;
  for (const std::string& name : rec.sidecar.coupled_columns) {
    const std::string suffix = "_ac";
    if (name.size() <= suffix.size() ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
      continue;
    }
    io::ReadOptions ro;
    ro.columns = {name.substr(0, name.size() - suffix.size()), name};
    ro.dt_s = rec.dt_s;
    ro.min_rows = rows.total;
    try {
      const io::Recording both = io::read_recording(path, ro);
      pairs.push_back({name, both.columns[0].segment(rows.first, rows.count),
                       both.columns[1].segment(rows.first, rows.count)});
    } catch (const io::InputError&) {
      // No raw source in the recording: the network cannot be measured, nothing to compare.
    }
  }
  return pairs;
}

}  // namespace

std::optional<double> IdentifyRecord::timing_correction_s() const {
  if (!rec.sidecar.y_sampled_after_s) return std::nullopt;
  return *rec.sidecar.y_sampled_after_s - 0.5 * rec.dt_s;
}

IdentifyRecord load_identify_record(const std::string& path, const ColumnChoice& columns,
                                    const std::string& role) {
  IdentifyRecord r;
  r.role = role;
  const io::Recording whole = read_columns(path, columns, r.input, r.output);
  r.rows = select_rows(path, whole, columns.rows);
  r.rec = slice_rows(whole, r.rows);
  if (r.rec.rows() < kMinSamples) {
    throw io::InputError(r.rec.source, 0, "",
                         fmt::format("expected at least {} rows, the selection ({}) holds {}",
                                     kMinSamples, r.rows.reason, r.rec.rows()));
  }
  require_excitation(r.rec, r.input, r.u());
  return r;
}

signal::CorrelatorOptions identify_correlator(const IdentifyRecord& first, int lags, int skip) {
  signal::CorrelatorOptions c;
  c.dt_s = first.rec.dt_s;
  c.skip = skip;
  const Eigen::Index n = first.rec.rows();
  c.lags = lags > 0 ? lags : std::max<Eigen::Index>(16, std::min<Eigen::Index>(256, n / 8));
  if (skip < 1) bad_option("--skip", "expected an integer >= 1");
  if (4 * c.lags > n) {
    throw io::InputError(first.rec.source, 0, "",
                         fmt::format("expected at least {} samples for a lag window of {} "
                                     "(4 x --lags), found {}",
                                     4 * c.lags, c.lags, n));
  }
  return c;
}

void check_record_quality(IdentifyRecord& r, const std::string& path,
                          const signal::CorrelatorOptions& correlator,
                          const std::optional<model::ModelOrder>& order, bool delay_auto) {
  if (4 * correlator.lags > r.rec.rows()) {
    throw io::InputError(r.rec.source, 0, "",
                         fmt::format("expected at least {} samples for a lag window of {} "
                                     "(4 x --lags), found {}",
                                     4 * correlator.lags, correlator.lags, r.rec.rows()));
  }
  ident::QualityOptions q;
  q.correlator = correlator;
  q.order = order.value_or(model::ModelOrder{2, 0});
  q.delay_estimated = delay_auto;
  q.coupling_rc_s = r.rec.sidecar.coupling_rc_s;
  q.jitter_max_s = r.rec.sampling.has_time ? r.rec.sampling.jitter_max_s : 0.0;
  q.coupled_pairs = coupled_pairs(path, r.rec, r.rows);
  r.quality = ident::check_quality(r.u(), r.y(), r.rec.dt_s, q);
}

void check_records_agree(const std::vector<IdentifyRecord>& records) {
  const IdentifyRecord& first = records.front();
  const double dt = first.rec.dt_s;
  const double timing = first.timing_correction_s().value_or(0.0);
  for (const IdentifyRecord& r : records) {
    if (std::abs(r.rec.dt_s - dt) > kSamePeriodRelative * dt) {
      throw io::InputError(r.rec.source, 0, "",
                           fmt::format("expected the sample period of {} ({:.6g} s), found "
                                       "{:.6g} s",
                                       first.rec.source, dt, r.rec.dt_s));
    }
    const double t = r.timing_correction_s().value_or(0.0);
    if (r.role == "estimation" && std::abs(t - timing) > kSamePeriodRelative * dt) {
      throw io::InputError(
          r.rec.source, 0, "y_sampled_after_s",
          fmt::format("expected the sample timing of {} (y sampled {:.6g} s "
                      "after u), found {:.6g} s: estimate on records timed "
                      "alike",
                      first.rec.source, first.rec.sidecar.y_sampled_after_s.value_or(0.0),
                      r.rec.sidecar.y_sampled_after_s.value_or(0.0)));
    }
  }
}

void refer_delays_to_plant(ident::IdentifyResult& r, double correction_s) {
  auto plant = [correction_s](double rows_s) { return std::max(0.0, rows_s + correction_s); };
  const double shift_s = plant(r.model.delay_s) - r.model.delay_s;
  r.model.delay_s += shift_s;
  r.delay_s = r.model.delay_s;
  for (ident::ParameterEstimate& p : r.parameters)
    if (p.name == "delay_s") p.value = r.delay_s;
  for (ident::StructureFit& f : r.table.rows) f.model.delay_s = plant(f.model.delay_s);
  for (ident::FrfUncertainty& b : r.band) b.phase_deg -= 360.0 * b.freq_hz * shift_s;
}

}  // namespace rig::cli
