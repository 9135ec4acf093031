// bench_diagnose: every effect of the library, concealed four ways, over several seeds, plus
// the null case; prints the confusion matrix, the primary parameter's error, the validation
// fit before/after, and the run time per diagnosis (with the record length it was for).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "concealed.hpp"
#include "recording_out.hpp"
#include "rig/diagnose/effect_registry.hpp"

using namespace rig::diagnose;

namespace {

struct Row {
  std::string truth, verdict;
  double param_err_pct = NAN, vfit_before = NAN, vfit_after = NAN, seconds = 0;
};

double primary_error_pct(const ConcealedRecording& rec, const DiagnoseResult& r) {
  const HypothesisFit* h = r.chosen();
  if (!h || rec.truth.empty()) return NAN;
  for (const auto& e : h->effects)
    if (std::string(to_string(e.effect)) == r.verdict && !e.params.empty()) {
      if (r.verdict == "drift") return NAN;  // smoother time scale vs OU time: not comparable
      return 100.0 * (e.params[0] - rec.truth[0]) / rec.truth[0];
    }
  return NAN;
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5, threads = 2;
  std::uint64_t first = 1;
  double duration = 300.0;
  std::string only;
  bool verbose = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--seeds") seeds = std::atoi(argv[i + 1]);
    if (a == "--duration") duration = std::atof(argv[i + 1]);
    if (a == "--threads") threads = std::atoi(argv[i + 1]);
    if (a == "--first-seed") first = std::strtoull(argv[i + 1], nullptr, 10);
    if (a == "--only") only = argv[i + 1];
    if (a == "--verbose") verbose = std::string(argv[i + 1]) == "1";
  }
  std::vector<std::optional<Effect>> effects = {std::nullopt};
  for (Effect e : kAllEffects)  // a second form of a word (the moved modes) is not a case
    if (first_form(e)) effects.push_back(e);
  const Concealment cons[] = {Concealment::kNoise, Concealment::kDrift, Concealment::kAcCoupling,
                              Concealment::kPartial};
  std::vector<Row> rows;
  DiagnoseOptions opt;
  opt.threads = threads;
  fmt::print("bench_diagnose: {} seeds from {}, {:.0f} s records at 100 Hz, {} threads\n", seeds,
             first, duration, threads);
  for (const auto& e : effects) {
    const std::string truth = e ? to_string(*e) : "none";
    if (!only.empty() && only != truth) continue;
    for (int s = 0; s < seeds; ++s) {
      ConcealedSpec spec;
      spec.effect = e;
      spec.seed = first + static_cast<std::uint64_t>(s);
      spec.duration_s = duration;
      // The null case has no drift (drift would be an effect): plain noise or a declared coupling.
      spec.concealment = e ? cons[static_cast<std::size_t>(s) % 4]
                           : cons[static_cast<std::size_t>(s) % 2 == 0 ? 0 : 2];
      const ConcealedRecording rec = make_concealed(spec);
      DiagnoseResult r;
      try {
        r = diagnose(rec.input, opt);
      } catch (const std::exception& ex) {
        fmt::print("  {:<22} seed {:>3}: error {}\n", truth, spec.seed, ex.what());
        r.verdict = "error";
      }
      const HypothesisFit* h = r.chosen();
      Row row{truth,
              r.verdict,
              primary_error_pct(rec, r),
              h ? h->validation_fit_before : r.validation_fit_before_pct,
              h ? h->validation_fit_after : NAN,
              r.elapsed_s};
      fmt::print(
          "  {:<22} seed {:>3} {:<12} -> {:<20} param err {:>7.1f} %  vfit {:5.1f} -> {:5.1f} %  "
          "{:5.1f} s\n",
          truth, spec.seed, to_string(spec.concealment), r.verdict, row.param_err_pct,
          row.vfit_before, row.vfit_after, row.seconds);
      if (verbose) bench::print_hypotheses(r);
      std::fflush(stdout);
      rows.push_back(row);
    }
  }
  std::map<std::string, std::map<std::string, int>> confusion;
  std::map<std::string, int> correct, total;
  for (const auto& r : rows) {
    ++confusion[r.truth][r.verdict];
    ++total[r.truth];
    if (r.truth == r.verdict) ++correct[r.truth];
  }
  fmt::print("\nconfusion (truth -> verdicts):\n");
  int all_ok = 0, all = 0;
  for (const auto& [t, m] : confusion) {
    std::string line;
    for (const auto& [v, c] : m) line += fmt::format(" {}:{}", v, c);
    fmt::print("  {:<22} {}/{} correct |{}\n", t, correct[t], total[t], line);
    all_ok += correct[t], all += total[t];
  }
  double secs = 0;
  for (const auto& r : rows) secs += r.seconds;
  fmt::print("overall {}/{} correct ({:.0f} %), mean {:.2f} s per diagnosis of {:.0f} s records\n",
             all_ok, all, 100.0 * all_ok / std::max(1, all),
             secs / std::max<std::size_t>(1, rows.size()), duration);
  return 0;
}
