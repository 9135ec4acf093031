// rig identify --recording REC.csv [--input COL --output COL | --columns I,J] [--dt S]
//              [--order n/m|auto] [--delay auto|SECONDS] [--method mmfm|srivc] [--lags N]
//              [--skip S] [--json] --out DIR
// Reads the recording, runs the data-quality checks (a fatal flag stops with exit 1),
// identifies the model and writes model.json, report.json and report.html (docs/identify.md).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <iostream>
#include <memory>

#include "rig/cli/commands.hpp"
#include "rig/cli/identify_report.hpp"
#include "rig/cli/identify_rows.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

struct IdentifyArgs {
  std::string recording;
  std::string input, output, columns;
  std::optional<double> dt_s;
  std::string order = "auto", delay = "auto", method = "mmfm";
  int lags = 0;  // 0: min(256, samples / 8)
  int skip = 1;
  double estimation_fraction = 0.5;
  std::string rows = "auto";  // auto | all | excitation (identify_rows.hpp)
  std::string out;
  bool json = false;
  bool force = false;
};

constexpr Eigen::Index kMinSamples = 128;

// Usage errors in option values are reported like input errors: one line, exit 2.
[[noreturn]] void bad_option(const std::string& option, const std::string& expected) {
  throw io::InputError("rig identify", 0, "", option + ": " + expected);
}

std::optional<model::ModelOrder> parse_order(const std::string& text) {
  if (text == "auto") return std::nullopt;
  model::ModelOrder order{0, 0};
  const auto slash = text.find('/');
  const std::string n = text.substr(0, slash);
  const std::string m = slash == std::string::npos ? "0" : text.substr(slash + 1);
  const auto a = std::from_chars(n.data(), n.data() + n.size(), order.n);
  const auto b = std::from_chars(m.data(), m.data() + m.size(), order.m);
  if (a.ec != std::errc() || a.ptr != n.data() + n.size() || b.ec != std::errc() ||
      b.ptr != m.data() + m.size() || order.n < 1 || order.m < 0 || order.m > order.n) {
    bad_option("--order",
               "expected auto or n/m with n >= 1 and 0 <= m <= n, found \"" + text + "\"");
  }
  return order;
}

std::optional<double> parse_delay(const std::string& text) {
  if (text == "auto") return std::nullopt;
  double v = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !(v >= 0.0) ||
      !std::isfinite(v)) {
    bad_option("--delay", "expected auto or a dead time >= 0 in seconds, found \"" + text + "\"");
  }
  return v;
}

// Which columns are input and output: --input/--output, else --columns I,J (1-based), else
// "u" and "y", else the only two data columns.
io::Recording load_recording(const IdentifyArgs& a, std::string& in, std::string& out) {
  io::ReadOptions ro;
  ro.dt_s = a.dt_s;
  ro.min_rows = kMinSamples;
  in = a.input;
  out = a.output;
  if (!a.columns.empty()) {
    const auto comma = a.columns.find(',');
    if (comma == std::string::npos)
      bad_option("--columns", "expected I,J (1-based input and output columns)");
    in = a.columns.substr(0, comma);
    out = a.columns.substr(comma + 1);
  }
  if (in.empty() != out.empty()) bad_option("--input/--output", "give both columns, or neither");
  if (!in.empty()) {
    ro.columns = {in, out};
    io::Recording rec = io::read_recording(a.recording, ro);
    in = rec.names[0];
    out = rec.names[1];
    return rec;
  }
  io::Recording rec = io::read_recording(a.recording, ro);
  if (rec.has("u") && rec.has("y")) {
    in = "u";
    out = "y";
  } else if (rec.names.size() == 2) {
    in = rec.names[0];
    out = rec.names[1];
  } else {
    throw io::InputError(rec.source, 0, "",
                         fmt::format("{} data columns and no u/y: name the "
                                     "input and output with --input/--output "
                                     "or --columns I,J",
                                     rec.names.size()));
  }
  return rec;
}

void require_excitation(const io::Recording& rec, const std::string& in, const Eigen::VectorXd& u) {
  const double sd = std::sqrt((u.array() - u.mean()).square().mean());
  if (!(sd > 1e-12 * std::max(1.0, std::abs(u.mean())))) {
    throw io::InputError(rec.source, 0, in,
                         fmt::format("expected a varying input, found the "
                                     "constant {:.6g}: nothing excites the plant",
                                     u.mean()));
  }
}

signal::CorrelatorOptions correlator_options(const IdentifyArgs& a, const io::Recording& rec) {
  signal::CorrelatorOptions c;
  c.dt_s = rec.dt_s;
  c.skip = a.skip;
  const Eigen::Index n = rec.rows();
  c.lags = a.lags > 0 ? a.lags : std::max<Eigen::Index>(16, std::min<Eigen::Index>(256, n / 8));
  if (a.skip < 1) bad_option("--skip", "expected an integer >= 1");
  if (4 * c.lags > n) {
    throw io::InputError(rec.source, 0, "",
                         fmt::format("expected at least {} samples for a lag "
                                     "window of {} (4 x --lags), found {}",
                                     4 * c.lags, c.lags, n));
  }
  return c;
}

// Sidecar "coupled_columns" name AC-coupled channels; a channel X_ac with its raw source X
// in the same recording lets the quality check measure each network's time constant.
std::vector<ident::CoupledPair> coupled_pairs(const IdentifyArgs& a, const io::Recording& rec,
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
      const io::Recording both = io::read_recording(a.recording, ro);
      pairs.push_back({name, both.columns[0].segment(rows.first, rows.count),
                       both.columns[1].segment(rows.first, rows.count)});
    } catch (const io::InputError&) {
      // No raw source in the recording: the network cannot be measured, nothing to compare.
    }
  }
  return pairs;
}

ident::QualityOptions quality_options(const io::Recording& rec, const signal::CorrelatorOptions& c,
                                      const std::optional<model::ModelOrder>& order,
                                      bool delay_auto) {
  ident::QualityOptions q;
  q.correlator = c;
  q.order = order.value_or(model::ModelOrder{2, 0});
  q.delay_estimated = delay_auto;
  q.coupling_rc_s = rec.sidecar.coupling_rc_s;
  q.jitter_max_s = rec.sampling.has_time ? rec.sampling.jitter_max_s : 0.0;
  return q;
}

void emit(const IdentifyArgs& a, const nlohmann::json& rep, const std::string& summary,
          bool failed) {
  if (a.json) {
    std::cout << rep.dump(2) << "\n";
  } else {
    (failed ? std::cerr : std::cout) << summary;
  }
}

int run_identify(const IdentifyArgs& a) {
  io::prepare_out_dir(a.out, a.force);
  IdentifyContext ctx;
  std::string in, out;
  const io::Recording whole = load_recording(a, in, out);
  ctx.rows = select_rows(a.recording, whole, a.rows);
  const io::Recording rec = slice_rows(whole, ctx.rows);
  if (rec.rows() < kMinSamples) {
    throw io::InputError(rec.source, 0, "",
                         fmt::format("expected at least {} rows, the selection "
                                     "({}) holds {}",
                                     kMinSamples, ctx.rows.reason, rec.rows()));
  }
  ctx.recording = &rec;
  ctx.input = in;
  ctx.output = out;
  ctx.method = a.method;
  ctx.order_arg = a.order;
  ctx.delay_arg = a.delay;
  ctx.estimation_fraction = a.estimation_fraction;
  const auto order = parse_order(a.order);
  const auto delay = parse_delay(a.delay);
  const Eigen::VectorXd& u = rec.column(in);
  const Eigen::VectorXd& y = rec.column(out);
  require_excitation(rec, in, u);
  ctx.correlator = correlator_options(a, rec);
  ident::QualityOptions qo = quality_options(rec, ctx.correlator, order, !delay);
  qo.coupled_pairs = coupled_pairs(a, rec, ctx.rows);
  const ident::QualityReport quality = ident::check_quality(u, y, rec.dt_s, qo);
  const std::filesystem::path dir(a.out);
  if (quality.has_fatal()) {
    const Eigen::VectorXd uc = u.array() - u.mean(), yc = y.array() - y.mean();
    const auto ruu = signal::auto_correlation(uc, ctx.correlator);
    const auto ryu = signal::cross_correlation(yc, uc, ctx.correlator);
    const nlohmann::json rep = identify_report_json(ctx, quality, nullptr);
    report::write_json_file(dir / "report.json", rep);
    write_identify_html(dir / "report.html", ctx, quality, nullptr, ruu, ryu);
    emit(a, rep, identify_summary(ctx, quality, nullptr, dir), true);
    return kExitAcceptance;
  }
  ident::IdentifyOptions io_opt;
  io_opt.method = a.method == "srivc" ? ident::IdentMethod::kSrivc : ident::IdentMethod::kMmfm;
  io_opt.order = order;
  io_opt.delay_s = delay;
  io_opt.correlator = ctx.correlator;
  io_opt.estimation_fraction = a.estimation_fraction;
  const ident::IdentifyResult result = ident::identify(u, y, rec.dt_s, io_opt);
  model::write_model(dir / "model.json", identify_model_file(ctx, result));
  const nlohmann::json rep = identify_report_json(ctx, quality, &result);
  report::write_json_file(dir / "report.json", rep);
  write_identify_html(dir / "report.html", ctx, quality, &result, result.ruu, result.ryu);
  emit(a, rep, identify_summary(ctx, quality, &result, dir), false);
  return kExitOk;
}

}  // namespace

void add_identify_command(CLI::App& app) {
  auto a = std::make_shared<IdentifyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "identify",
      "Identify a transfer function from a recording (data-quality checks, "
      "MMFM or SRIVC, order and delay selection); writes model.json, report.json, "
      "report.html");
  cmd->add_option("--recording", a->recording, "Recording: CSV with header, or .dat without")
      ->required();
  cmd->add_option("--input", a->input, "Input column name (default u, or the first of two)");
  cmd->add_option("--output", a->output, "Output column name (default y, or the second of two)");
  cmd->add_option("--columns", a->columns, "Input and output columns by 1-based index: I,J")
      ->excludes(cmd->get_option("--input"))
      ->excludes(cmd->get_option("--output"));
  cmd->add_option("--dt", a->dt_s, "Sample period in s (overrides the time column and sidecar)");
  cmd->add_option("--order", a->order, "Model order n/m (den/num), or auto")->default_str("auto");
  cmd->add_option("--delay", a->delay, "Dead time in s, or auto")->default_str("auto");
  cmd->add_option("--method", a->method, "Estimator")
      ->check(CLI::IsMember({"mmfm", "srivc"}))
      ->default_str("mmfm");
  cmd->add_option("--lags", a->lags, "Correlation lag window in samples (default min(256, N/8))");
  cmd->add_option("--skip", a->skip, "Fell's skip: form every S-th product")->default_str("1");
  cmd->add_option("--estimation-fraction", a->estimation_fraction,
                  "Share of the record used for estimation; the rest validates")
      ->check(CLI::Range(0.2, 0.8))
      ->default_str("0.5");
  cmd->add_option("--rows", a->rows,
                  "Rows to use: auto (a rig commission recording's excitation phase, else all), "
                  "all, or excitation")
      ->default_str("auto");
  cmd->add_option("--out", a->out, "Output folder (must be new or empty, see --force)")->required();
  cmd->add_flag("--force", a->force,
                "Clear a non-empty --out folder first (an earlier run's files)");
  cmd->add_flag("--json", a->json, "Print report.json on stdout instead of the summary");
  cmd->callback([a] {
    const int code = run_identify(*a);
    if (code != kExitOk) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
