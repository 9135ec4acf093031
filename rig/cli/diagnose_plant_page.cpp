// report.html's "Plant" section of `rig diagnose --model PLANT.toml`: what was written back
// into the plant and how the augmented plant replays the recording.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/cli/diagnose_plant.hpp"
#include "rig/report/html_report.hpp"

namespace rig::cli {
namespace {

// The replays shown: this long a stretch after the warm-up (a person reads 40 s of a 100 Hz
// record; the whole fit is in the key values).
constexpr double kShownSpanS = 40.0;

report::Table changes_table(const PlantMapping& m) {
  report::Table t{{"plant parameter", "as given", "augmented", "effect", "how"}, {}, {}};
  for (const auto& c : m.changes)
    t.rows.push_back({c.key, fmt::format("{:.6g}", c.old_value), fmt::format("{:.6g}", c.new_value),
                      c.effect, c.reason});
  return t;
}

// Each series with its mean after the warm-up removed (the replay starts at its own
// operating point), over the shown stretch.
report::Chart replay_chart(const PlantPage& p) {
  const Eigen::Index n = p.y.size();
  const Eigen::Index from = std::clamp<Eigen::Index>(p.warmup, 0, std::max<Eigen::Index>(0, n - 1));
  const Eigen::Index len = std::min<Eigen::Index>(n - from, std::llround(kShownSpanS / p.dt_s));
  report::Chart c{"Recorded output vs the plant replayed, as given and augmented",
                  "time (s)",
                  "output (mean after warm-up removed)",
                  {},
                  {},
                  {},
                  false,
                  false,
                  320};
  for (Eigen::Index k = 0; k < len; ++k) c.x.push_back(static_cast<double>(from + k) * p.dt_s);
  const auto centred = [&](const Eigen::VectorXd& x) {
    const double mean = x.tail(n - from).mean();
    std::vector<double> out(static_cast<std::size_t>(len));
    for (Eigen::Index k = 0; k < len; ++k) out[static_cast<std::size_t>(k)] = x(from + k) - mean;
    return out;
  };
  c.series.push_back({"recorded", centred(p.y), "#444", false, false, 1.0});
  c.series.push_back({"plant as given", centred(p.before), "#d62728", false, false, 1.5});
  c.series.push_back({"augmented plant", centred(p.after), "#2ca02c", false, false, 1.5});
  return c;
}

}  // namespace

void plant_section(report::HtmlReport& html, const PlantPage& p) {
  html.section("Plant");
  std::vector<std::pair<std::string, std::string>> kv{{"plant as given", p.toml},
                                                      {"augmented plant", p.augmented}};
  if (p.fit_before_pct && p.fit_after_pct)
    kv.emplace_back("plant check (plantsim replay, after the warm-up)",
                    fmt::format("fit {:.1f} % -> {:.1f} %", *p.fit_before_pct, *p.fit_after_pct));
  else if (!p.check_error.empty())
    kv.emplace_back("plant check", "failed: " + p.check_error);
  else
    kv.emplace_back("plant check", "not run (--no-plant-check)");
  html.key_values(kv);
  if (p.mapping.changes.empty())
    html.paragraph(
        "No plant parameter changed: the verdict's effects have no plant parameter, "
        "or there is no verdict.");
  else
    html.table(changes_table(p.mapping));
  for (const auto& note : p.mapping.notes) html.note(report::Tone::kInfo, note);
  if (p.fit_before_pct && p.y.size() == p.before.size() && p.y.size() == p.after.size() &&
      p.y.size() > 1)
    html.chart(replay_chart(p));
}

}  // namespace rig::cli
