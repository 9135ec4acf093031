// bench_diagnose_plant: the proof of `rig diagnose` on concealed plantsim recordings
// (plant_cases.hpp): every effect plantsim can hide, each concealed in turn by noise, drift,
// a declared AC coupling and by appearing half-way through, over several seeds, plus the
// null case; prints every case, the confusion matrix (true effect -> verdicts), the error
// of the fitted parameter against the plant's truth, the validation fit before -> after,
// and the time per diagnosis.
//   bench_diagnose_plant [--seeds 5] [--first-seed 1] [--duration 300] [--only EFFECT]
//                        [--concealment noise|drift|ac_coupling|partial] [--threads 2]
//                        [--verbose 1]
// (--concealment forces one for every case; partial with the null case is the bare preset.)
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "plant_cases.hpp"
#include "recording_out.hpp"

using namespace rig::diagnose;
using namespace rig::diagnose::bench;

namespace {

struct Row {
  std::string truth, verdict;
  bool correct = false;
  double param_err_pct = NAN, vfit_before = NAN, vfit_after = NAN, seconds = 0;
};

// The chosen hypothesis's first parameter of the verdict's effect against the truth.
double param_error_pct(const PlantCase& pc, const DiagnoseResult& r) {
  const HypothesisFit* h = r.chosen();
  if (!h || !std::isfinite(pc.truth)) return NAN;
  for (const auto& e : h->effects)
    if (verdict_matches(to_string(e.effect), r.verdict) && !e.params.empty())
      return 100.0 * (e.params[0] - pc.truth) / pc.truth;
  return NAN;
}

void print_summary(const std::vector<Row>& rows, double duration_s) {
  std::map<std::string, std::map<std::string, int>> confusion;
  std::map<std::string, int> correct, total;
  std::vector<double> errs;
  int improved = 0, ok_all = 0, all = 0, null_ok = 0, nulls = 0;
  double secs = 0, worst_s = 0;
  for (const auto& r : rows) {
    ++confusion[r.truth][r.verdict];
    ++total[r.truth];
    secs += r.seconds, worst_s = std::max(worst_s, r.seconds);
    if (r.truth == "none") {
      ++nulls, null_ok += r.verdict == "none";
      continue;
    }
    ++all;
    if (!r.correct) continue;
    ++correct[r.truth], ++ok_all;
    improved += r.vfit_after > r.vfit_before;
    if (std::isfinite(r.param_err_pct)) errs.push_back(std::abs(r.param_err_pct));
  }
  fmt::print("\nconfusion (true effect -> verdicts):\n");
  for (const auto& [t, m] : confusion) {
    std::string line;
    for (const auto& [v, c] : m) line += fmt::format(" {}:{}", v, c);
    fmt::print("  {:<22} {:>2}/{:<2} |{}\n", t,
               t == "none" ? m.count("none") ? m.at("none") : 0 : correct[t], total[t], line);
  }
  int within20 = 0;
  double worst = 0;
  for (double e : errs) within20 += e <= 20.0, worst = std::max(worst, e);
  fmt::print("effects: {}/{} correct ({:.1f} %); validation fit improved in {}/{} correct\n",
             ok_all, all, 100.0 * ok_all / std::max(1, all), improved, ok_all);
  fmt::print("parameter within 20 % in {}/{} compared (worst {:.1f} %)\n", within20, errs.size(),
             worst);
  fmt::print("null: {}/{} none ({:.1f} %)\n", null_ok, nulls, 100.0 * null_ok / std::max(1, nulls));
  fmt::print("time per diagnosis of a {:.0f} s, 100 Hz record: mean {:.2f} s, max {:.2f} s\n",
             duration_s, secs / std::max<std::size_t>(1, rows.size()), worst_s);
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5, threads = 2;
  std::uint64_t first = 1;
  double duration = 300.0;
  std::string only, forced;
  bool verbose = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      fmt::print(
          "bench_diagnose_plant [--seeds 5] [--first-seed 1] [--duration 300] "
          "[--only EFFECT] [--concealment C] [--threads 2] [--verbose 1]\n");
      return 0;
    }
    if (i + 1 >= argc) break;
    const char* v = argv[++i];
    if (a == "--seeds") seeds = std::atoi(v);
    if (a == "--duration") duration = std::atof(v);
    if (a == "--threads") threads = std::atoi(v);
    if (a == "--first-seed") first = std::strtoull(v, nullptr, 10);
    if (a == "--only") only = v;
    if (a == "--concealment") forced = v;
    if (a == "--verbose") verbose = std::string(v) == "1";
  }
  DiagnoseOptions opt;
  opt.threads = threads;
  fmt::print("bench_diagnose_plant: {} seeds from {}, {:.0f} s records at 100 Hz, {} threads\n",
             seeds, first, duration, threads);
  std::vector<Row> rows;
  for (const auto& eff : plant_effects()) {
    if (!only.empty() && only != eff.effect) continue;
    for (int s = 0; s < seeds; ++s) {
      PlantCaseSpec spec;
      spec.effect = eff.effect;
      spec.seed = first + static_cast<std::uint64_t>(s);
      spec.duration_s = duration;
      const auto cons = concealments_for(eff.effect);
      spec.concealment = forced.empty() ? cons[static_cast<std::size_t>(s) % cons.size()] : forced;
      const PlantCase pc = make_plant_case(spec);
      DiagnoseResult r;
      try {
        r = diagnose(pc.input, opt);
      } catch (const std::exception& ex) {
        fmt::print("  {:<22} seed {:>3}: error {}\n", eff.effect, spec.seed, ex.what());
        r.verdict = "error";
      }
      const HypothesisFit* h = r.chosen();
      const bool ok = verdict_matches(eff.effect, r.verdict);
      Row row{eff.effect,
              r.verdict,
              ok,
              ok ? param_error_pct(pc, r) : NAN,
              h ? h->validation_fit_before : r.validation_fit_before_pct,
              h ? h->validation_fit_after : NAN,
              r.elapsed_s};
      fmt::print(
          "  {:<22} seed {:>3} {:<12} -> {:<22} {} truth {:<8.4g} err {:>7.1f} %  "
          "vfit {:5.1f} -> {:5.1f} %  {:5.1f} s\n",
          eff.effect, spec.seed, spec.concealment, r.verdict, row.correct ? "ok " : "BAD", pc.truth,
          row.param_err_pct, row.vfit_before, row.vfit_after, row.seconds);
      if (verbose) print_hypotheses(r);
      std::fflush(stdout);
      rows.push_back(row);
    }
  }
  print_summary(rows, duration);
  return 0;
}
