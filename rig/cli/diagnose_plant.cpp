// From diagnosed effects to plantsim parameters. The baseline transfer function is plantsim's
// linearisation: input u = setpoint bias in % of rated power P_r, output y = measured power
// in kW. Each effect's mapping (effect parameter -> plant key, and the conversion) is in its
// own file, rig/diagnose/effects/<word>.cpp (the governor's scales the input nonlinearities
// map through: rig/diagnose/effects/common.hpp); an effect without one (resonance,
// static_nonlinearity, nonlinear_stiffness, coulomb_friction) leaves the plant as it was
// (augmented_model.json carries it). Every value is clamped to the range plantsim lists for
// the key (a note says so).
#include "rig/cli/diagnose_plant.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/io/input_error.hpp"

namespace rig::cli {
namespace {

double round6(double v) { return std::stod(fmt::format("{:.6g}", v)); }

class Mapper : public diagnose::PlantTarget {
 public:
  Mapper(const PlantModel& plant, PlantMapping* out) : plant_(plant), out_(out) {}

  double param(const std::string& key) const override { return plant_.param(key); }
  // Sets key to value (clamped to plantsim's range); reason names the conversion.
  void set(const std::string& key, double value, const std::string& effect,
           const std::string& reason) override {
    const double old = current(key);
    double v = value;
    const auto r = plant_.ranges.find(key);
    if (r != plant_.ranges.end() && (v < r->second.first || v > r->second.second)) {
      v = std::clamp(v, r->second.first, r->second.second);
      out_->notes.push_back(fmt::format("{}: {:.6g} clamped to plantsim's range {:.6g} .. {:.6g}",
                                        key, value, r->second.first, r->second.second));
    }
    v = round6(v);
    for (auto& c : out_->changes)
      if (c.key == key) {
        c.new_value = v, c.effect += "+" + effect, c.reason += "; " + reason;
        return;
      }
    out_->changes.push_back({key, old, v, effect, reason});
  }
  // The value as changed so far, else the plant's.
  double current(const std::string& key) const override {
    for (const auto& c : out_->changes)
      if (c.key == key) return c.new_value;
    return plant_.param(key);
  }
  void note(const std::string& text) override { out_->notes.push_back(text); }

 private:
  const PlantModel& plant_;
  PlantMapping* out_;
};

// The effect's own mapping (rig/diagnose/effects/<word>.cpp), if it has one.
void map_effect(const diagnose::AppliedEffect& e, const diagnose::HypothesisFit& h,
                const model::TransferFunction& baseline, const Eigen::VectorXd& u, Mapper& m) {
  const diagnose::EffectModel& em = diagnose::effect_model(e.effect);
  if (!em.map_to_plant) {
    m.note(fmt::format("{}: no plant parameter expresses it; see augmented_model.json", em.name));
    return;
  }
  em.map_to_plant({e, h, baseline, u}, m);
}

}  // namespace

double PlantModel::param(const std::string& key) const {
  const auto it = params.find(key);
  if (it == params.end())
    throw io::InputError(toml.string(), 0, key, "plantsim --list-params did not list this key");
  return it->second;
}

PlantMapping plant_changes(const diagnose::HypothesisFit& hypothesis, const PlantModel& plant,
                           const model::TransferFunction& baseline, const Eigen::VectorXd& u) {
  PlantMapping out;
  Mapper m(plant, &out);
  for (const auto& e : hypothesis.effects) map_effect(e, hypothesis, baseline, u, m);
  return out;
}

std::string augmented_plant_toml(const std::filesystem::path& input, const PlantMapping& mapping,
                                 const std::vector<std::string>& summary) {
  toml::table root;
  try {
    root = toml::parse_file(input.string());
  } catch (const toml::parse_error& e) {
    throw io::InputError(input.string(), static_cast<long>(e.source().begin.line), "",
                         std::string("malformed TOML: ") + std::string(e.description()));
  }
  std::ostringstream text;
  text << "# Plant written by `rig diagnose` from " << input.filename().string() << ".\n";
  for (const auto& s : summary) text << "# " << s << "\n";
  if (mapping.changes.empty()) text << "# No plant parameter changed.\n";
  for (const auto& c : mapping.changes) {
    const auto dot = c.key.find('.');
    const std::string block = c.key.substr(0, dot), name = c.key.substr(dot + 1);
    if (!root.contains(block)) root.insert(block, toml::table{});
    root[block].as_table()->insert_or_assign(name, c.new_value);
    text << fmt::format("# Changed {}: {:.6g} -> {:.6g} ({}: {}).\n", c.key, c.old_value,
                        c.new_value, c.effect, c.reason);
  }
  for (const auto& n : mapping.notes) text << "# Note: " << n << "\n";
  text << "# The original file's comments are not kept; `plantsim --list-params` describes\n"
          "# every key.\n\n";
  // Shortest round-trip floats (0.05, not 0.050000000000000003).
  text << toml::toml_formatter{root, toml::toml_formatter::default_flags |
                                         toml::format_flags::relaxed_float_precision}
       << "\n";
  return text.str();
}

}  // namespace rig::cli
