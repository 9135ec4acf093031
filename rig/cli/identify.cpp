// rig identify --recording REC.csv [--estimation C.csv ...] [--validation B.csv]
//              [--input COL --output COL | --columns I,J] [--dt S] [--order n/m|auto]
//              [--delay auto|SECONDS] [--method all|mmfm|mmfm+oe|srivc[,...]] [--lags N]
//              [--skip S] [--json] --out DIR
// Reads the records, runs the data-quality checks (a fatal flag stops with exit 1), fills
// the fit table, identifies the model and writes model.json, report.json and report.html
// (docs/identify.md).
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "rig/cli/commands.hpp"
#include "rig/cli/identify_records.hpp"
#include "rig/cli/identify_report.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

struct IdentifyArgs {
  std::string recording;
  std::vector<std::string> estimation;  // more estimation records
  std::string validation;               // a separate validation record
  ColumnChoice columns;
  std::string order = "auto", delay = "auto", method = "all";
  int lags = 0;  // 0: min(256, samples / 8)
  int skip = 1;
  double estimation_fraction = 0.5;
  std::string out;
  bool json = false;
  bool force = false;
};

// Usage errors in option values are reported like input errors: one line, exit 2.
[[noreturn]] void bad_option(const std::string& option, const std::string& expected) {
  throw io::InputError("rig identify", 0, "", option + ": " + expected);
}

std::vector<ident::IdentMethod> parse_methods(const std::string& text) {
  if (text == "all")
    return {ident::IdentMethod::kMmfm, ident::IdentMethod::kMmfmOe, ident::IdentMethod::kSrivc};
  std::vector<ident::IdentMethod> out;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const auto m = ident::ident_method_from(text.substr(at, comma - at));
    if (!m) {
      bad_option("--method",
                 "expected all, or one or more of mmfm, mmfm+oe, srivc separated by commas, "
                 "found \"" +
                     text + "\"");
    }
    if (std::find(out.begin(), out.end(), *m) == out.end()) out.push_back(*m);
    at = comma + 1;
  }
  return out;
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

// auto: the table has structures with an estimated dead time and without one; estimated:
// only with one; a number: that dead time.
std::optional<double> parse_delay(const std::string& text) {
  if (text == "auto" || text == "estimated") return std::nullopt;
  double v = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !(v >= 0.0) ||
      !std::isfinite(v)) {
    bad_option("--delay",
               "expected auto, estimated or a dead time >= 0 in seconds, found \"" + text + "\"");
  }
  return v;
}

void emit(const IdentifyArgs& a, const nlohmann::json& rep, const std::string& summary,
          bool failed) {
  if (a.json) {
    std::cout << rep.dump(2) << "\n";
  } else {
    (failed ? std::cerr : std::cout) << summary;
  }
}

std::vector<IdentifyRecord> load_records(const IdentifyArgs& a) {
  if (!a.estimation.empty() && a.validation.empty()) {
    bad_option("--estimation",
               "more estimation records need a separate --validation record to choose on");
  }
  std::vector<IdentifyRecord> records;
  records.push_back(load_identify_record(a.recording, a.columns, "estimation"));
  ColumnChoice same = a.columns;
  same.columns.clear();
  same.input = records.front().input;
  same.output = records.front().output;
  for (const std::string& path : a.estimation)
    records.push_back(load_identify_record(path, same, "estimation"));
  if (!a.validation.empty())
    records.push_back(load_identify_record(a.validation, same, "validation"));
  check_records_agree(records);
  return records;
}

// A's quality report with every other record's flags, named by their file.
ident::QualityReport combined_quality(const std::vector<IdentifyRecord>& records) {
  ident::QualityReport q = records.front().quality;
  for (std::size_t i = 1; i < records.size(); ++i) {
    for (ident::QualityFlag f : records[i].quality.flags) {
      f.message = records[i].rec.source + " (" + records[i].role + "): " + f.message;
      q.flags.push_back(f);
    }
  }
  return q;
}

// Progress of the fit table on an interactive terminal (nothing in a pipe or a log).
ident::TableProgress table_progress(bool json) {
  if (json || !isatty(fileno(stderr))) return {};
  return [](int done, int total) {
    std::fprintf(stderr, "\r  fit table: %d/%d structures", done, total);
    if (done == total) std::fprintf(stderr, "\r%*s\r", 40, "");
    std::fflush(stderr);
  };
}

ident::IdentifyResult identify_records(const IdentifyArgs& a,
                                       const std::vector<IdentifyRecord>& records,
                                       const IdentifyContext& ctx) {
  ident::IdentifyOptions o;
  o.methods = parse_methods(a.method);
  o.order = parse_order(a.order);
  o.delay_s = parse_delay(a.delay);
  o.without_delay = a.delay == "auto";
  // A given dead time refers to what the report's do: the plant when the timing is known.
  if (o.delay_s && ctx.timing_correction_s)
    o.delay_s = std::max(0.0, *o.delay_s - *ctx.timing_correction_s);
  o.correlator = ctx.correlator;
  o.estimation_fraction = a.estimation_fraction;
  o.progress = table_progress(a.json);
  const double dt_s = records.front().rec.dt_s;
  if (a.validation.empty())
    return ident::identify(records.front().u(), records.front().y(), dt_s, o);
  ident::RecordSet est, val;
  for (const IdentifyRecord& r : records) (r.role == "validation" ? val : est).add(r.u(), r.y());
  const double corr_est = ctx.timing_correction_s.value_or(0.0);
  o.validation_delay_shift_s = corr_est - records.back().timing_correction_s().value_or(corr_est);
  return ident::identify(est, val, dt_s, o);
}

// Exit 1 with report.json and report.html but no model.json: a fatal data-quality flag, or
// no structure gave a stable model (ctx.no_model says so).
int without_model(const IdentifyArgs& a, const IdentifyContext& ctx,
                  const ident::QualityReport& quality, const std::filesystem::path& dir) {
  const IdentifyRecord& first = ctx.records->front();
  const Eigen::VectorXd uc = first.u().array() - first.u().mean();
  const Eigen::VectorXd yc = first.y().array() - first.y().mean();
  const nlohmann::json rep = identify_report_json(ctx, quality, nullptr);
  report::write_json_file(dir / "report.json", rep);
  write_identify_html(dir / "report.html", ctx, quality, nullptr,
                      signal::auto_correlation(uc, ctx.correlator),
                      signal::cross_correlation(yc, uc, ctx.correlator));
  emit(a, rep, identify_summary(ctx, quality, nullptr, dir), true);
  return kExitAcceptance;
}

int run_identify(const IdentifyArgs& a) {
  io::prepare_out_dir(a.out, a.force);
  std::vector<IdentifyRecord> records = load_records(a);
  IdentifyContext ctx;
  const IdentifyRecord& first = records.front();
  ctx.recording = &first.rec;
  ctx.rows = first.rows;
  ctx.input = first.input;
  ctx.output = first.output;
  ctx.method = a.method;
  ctx.order_arg = a.order;
  ctx.delay_arg = a.delay;
  ctx.estimation_fraction = a.estimation_fraction;
  ctx.records = &records;
  ctx.timing_correction_s = first.timing_correction_s();
  const auto order = parse_order(a.order);
  const auto delay = parse_delay(a.delay);
  parse_methods(a.method);
  ctx.correlator = identify_correlator(first, a.lags, a.skip);
  std::vector<std::string> paths{a.recording};
  paths.insert(paths.end(), a.estimation.begin(), a.estimation.end());
  if (!a.validation.empty()) paths.push_back(a.validation);
  for (std::size_t i = 0; i < records.size(); ++i)
    check_record_quality(records[i], paths[i], ctx.correlator, order, !delay);
  const ident::QualityReport quality = combined_quality(records);
  const std::filesystem::path dir(a.out);
  if (quality.has_fatal()) return without_model(a, ctx, quality, dir);
  ident::IdentifyResult result;
  try {
    result = identify_records(a, records, ctx);
  } catch (const ident::NoStableModel& e) {
    ctx.no_model = e.what();
    return without_model(a, ctx, quality, dir);
  }
  if (ctx.timing_correction_s) refer_delays_to_plant(result, *ctx.timing_correction_s);
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
  cmd->add_option("--recording", a->recording,
                  "Recording to estimate on: CSV with header, or .dat without")
      ->required();
  cmd->add_option("--estimation", a->estimation,
                  "More records to estimate on, with the recording (repeatable; needs "
                  "--validation)");
  cmd->add_option("--validation", a->validation,
                  "A separate record to validate on: the fit table is scored on it and it "
                  "takes no part in the estimate (default: the recording's held-out tail)");
  cmd->add_option("--input", a->columns.input,
                  "Input column name (default u, or the first of two)");
  cmd->add_option("--output", a->columns.output,
                  "Output column name (default y, or the second of two)");
  cmd->add_option("--columns", a->columns.columns, "Input and output columns by 1-based index: I,J")
      ->excludes(cmd->get_option("--input"))
      ->excludes(cmd->get_option("--output"));
  cmd->add_option("--dt", a->columns.dt_s,
                  "Sample period in s (overrides the time column and sidecar)");
  cmd->add_option("--order", a->order, "Model order n/m (den/num), or auto")->default_str("auto");
  cmd->add_option("--delay", a->delay,
                  "Dead time in s; auto: structures with an estimated dead time and without one; "
                  "estimated: only with one")
      ->default_str("auto");
  cmd->add_option("--method", a->method,
                  "Estimators in the fit table: all, or any of mmfm, mmfm+oe (MMFM refined by "
                  "the time-domain output error), srivc, separated by commas")
      ->default_str("all");
  cmd->add_option("--lags", a->lags, "Correlation lag window in samples (default min(256, N/8))");
  cmd->add_option("--skip", a->skip, "Fell's skip: form every S-th product")->default_str("1");
  cmd->add_option("--estimation-fraction", a->estimation_fraction,
                  "Without --validation: the share of the recording used for estimation; the "
                  "rest validates")
      ->check(CLI::Range(0.2, 0.8))
      ->default_str("0.5");
  cmd->add_option("--rows", a->columns.rows,
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
