// The plant outputs of `rig diagnose --model PLANT.toml`: augmented_plant.toml, and the
// plant check (the recorded bias replayed through the plant as given and as augmented,
// compared with the recorded output by the NRMSE fit of DESIGN.md 5 after diagnose's warm-up).
#include <fmt/format.h>

#include <cmath>
#include <fstream>

#include "rig/cli/diagnose_plant.hpp"
#include "rig/model/model_file.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::cli {
namespace {

using nlohmann::json;

// 100 (1 - |y - yhat| / |y|) over k >= from, both with their means there removed (the plant
// replay starts at its own operating point; the recording may carry any offset).
double fit_after_warmup_pct(const Eigen::VectorXd& y, const Eigen::VectorXd& yhat,
                            Eigen::Index from) {
  const Eigen::Index n = y.size() - from;
  const Eigen::VectorXd a = y.tail(n).array() - y.tail(n).mean();
  const Eigen::VectorXd b = yhat.tail(n).array() - yhat.tail(n).mean();
  const double den = a.norm();
  return den > 0.0 ? 100.0 * (1.0 - (a - b).norm() / den) : 0.0;
}

json changes_json(const PlantMapping& m) {
  json arr = json::array();
  for (const auto& c : m.changes)
    arr.push_back({{"key", c.key},
                   {"old", c.old_value},
                   {"new", c.new_value},
                   {"effect", c.effect},
                   {"reason", c.reason}});
  return arr;
}

Eigen::VectorXd replay(const PlantOutputInput& in, const std::filesystem::path& toml) {
  Eigen::VectorXd y = replay_plant(in.plant.plantsim, toml, in.u, in.dt_s, in.tmp);
  if (in.chain_rc_s) y = signal::ac_couple(y, in.dt_s, *in.chain_rc_s);
  return y;
}

// Replays both plants; the `plant_check` object (or its error) and the summary line.
json plant_check(const PlantOutputInput& in, const std::filesystem::path& augmented, bool changed,
                 std::vector<std::string>* summary, PlantPage* page) {
  const Eigen::Index from = in.result.warmup;
  try {
    const Eigen::VectorXd before = replay(in, in.plant.toml);
    const Eigen::VectorXd after = changed ? replay(in, augmented) : before;
    const double fb = fit_after_warmup_pct(in.y, before, from);
    const double fa = fit_after_warmup_pct(in.y, after, from);
    page->fit_before_pct = fb;
    page->fit_after_pct = fa;
    page->before = before;
    page->after = after;
    std::ofstream csv(in.out_dir / "plant_check.csv");
    csv << "t,u,y,y_plant,y_augmented_plant\n";
    for (Eigen::Index k = 0; k < in.u.size(); ++k)
      csv << fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", static_cast<double>(k) * in.dt_s,
                         in.u(k), in.y(k), before(k), after(k));
    summary->push_back(
        fmt::format("plant check (plantsim replay, no noise): fit {:.1f} % -> {:.1f} % with the "
                    "augmented plant",
                    fb, fa));
    return {{"fit_before_pct", fb},
            {"fit_after_pct", fa},
            {"warmup_s", static_cast<double>(from) * in.dt_s},
            {"samples", in.u.size() - from},
            {"file", "plant_check.csv"}};
  } catch (const std::exception& e) {
    page->check_error = e.what();
    summary->push_back(fmt::format("plant check failed: {}", e.what()));
    return {{"error", e.what()}};
  }
}

}  // namespace

json write_plant_outputs(const PlantOutputInput& in, std::vector<std::string>* summary,
                         PlantPage* page) {
  const diagnose::HypothesisFit* chosen = in.result.chosen();
  PlantMapping mapping;
  if (chosen) mapping = plant_changes(*chosen, in.plant, in.baseline, in.u);
  std::vector<std::string> header{
      fmt::format("Recording {}: verdict {}{}.", in.recording, in.result.verdict,
                  chosen ? fmt::format(" (validation fit {:.1f} -> "
                                       "{:.1f} %)",
                                       chosen->validation_fit_before, chosen->validation_fit_after)
                         : std::string())};
  const std::filesystem::path augmented = in.out_dir / "augmented_plant.toml";
  {
    std::ofstream f(augmented);
    f << augmented_plant_toml(in.plant.toml, mapping, header);
    if (!f) throw std::runtime_error(fmt::format("{}: cannot write", augmented.string()));
  }
  std::string changed;
  for (const auto& c : mapping.changes)
    changed += fmt::format("{}{} {:.4g} -> {:.4g}", changed.empty() ? "" : ", ", c.key, c.old_value,
                           c.new_value);
  summary->push_back(fmt::format("plant: {} ({})", augmented.string(),
                                 changed.empty() ? "no parameter changed" : changed));
  json out;
  out["plant_model"] = {{"file", in.plant.toml.string()},
                        {"plantsim", in.plant.plantsim.string()},
                        {"linearised", model::model_to_json(in.plant.linear)},
                        {"alignment_s", in.baseline.delay_s - in.plant.linear.tf.delay_s},
                        {"augmented_plant", "augmented_plant.toml"},
                        {"changes", changes_json(mapping)},
                        {"notes", mapping.notes}};
  page->toml = in.plant.toml.string();
  page->augmented = augmented.string();
  page->y = in.y;
  page->dt_s = in.dt_s;
  page->warmup = in.result.warmup;
  out["plant_check"] = in.plant_check
                           ? plant_check(in, augmented, !mapping.changes.empty(), summary, page)
                           : json(nullptr);
  page->mapping = std::move(mapping);
  return out;
}

}  // namespace rig::cli
