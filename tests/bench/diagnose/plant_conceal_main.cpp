// diagnose_conceal_plant: writes one concealed-effect recording made by plantsim
// (plant_cases.hpp) for `rig diagnose`: rec.csv + rec.json (sidecar), the nominal model
// model.json (the preset's linearisation), and truth.json (the plant change and the
// parameter the diagnosis should find).
//   diagnose_conceal_plant --effect none|dead_time|... --concealment
//   noise|drift|ac_coupling|partial
//                          [--seed N] [--duration S] --out DIR
//   diagnose_conceal_plant --list     the effects with their plant parameter
#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "plant_cases.hpp"
#include "recording_out.hpp"

using namespace rig::diagnose::bench;

namespace {

void write_case(const PlantCase& pc, const PlantCaseSpec& spec, const std::filesystem::path& dir) {
  write_diagnose_recording(dir, pc.input.u, pc.input.y, pc.input.dt_s, spec.seed,
                           pc.input.output_rc_s, &pc.input.model);
  nlohmann::json truth = {{"effect", spec.effect}, {"concealment", spec.concealment},
                          {"seed", spec.seed},     {"plant_faults", pc.faults},
                          {"param", pc.param},     {"description", pc.description}};
  if (std::isfinite(pc.truth)) truth["value"] = pc.truth;
  std::ofstream(dir / "truth.json") << truth.dump(2) << '\n';
}

}  // namespace

int main(int argc, char** argv) {
  PlantCaseSpec spec;
  std::string out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      fmt::print(
          "diagnose_conceal_plant --effect E --concealment C [--seed N] [--duration S] "
          "--out DIR | --list\n");
      return 0;
    }
    if (a == "--list") {
      for (const auto& e : plant_effects())
        fmt::print("{:<22} {:<24} {:<10.5g} {}\n", e.effect, e.plant_key, e.plant_value,
                   e.description);
      return 0;
    }
    if (i + 1 >= argc)
      return std::fprintf(stderr, "diagnose_conceal_plant: %s needs a value\n", argv[i]), 2;
    const std::string v = argv[++i];
    if (a == "--effect")
      spec.effect = v;
    else if (a == "--concealment")
      spec.concealment = v;
    else if (a == "--seed")
      spec.seed = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--duration")
      spec.duration_s = std::atof(v.c_str());
    else if (a == "--out")
      out = v;
    else
      return std::fprintf(stderr, "diagnose_conceal_plant: unknown option %s\n", a.c_str()), 2;
  }
  if (out.empty())
    return std::fprintf(stderr, "diagnose_conceal_plant: --out DIR is required\n"), 2;
  try {
    const PlantCase pc = make_plant_case(spec);
    write_case(pc, spec, out);
    fmt::print("{}\n  truth: {} = {:.5g}\n", pc.description, pc.param, pc.truth);
  } catch (const std::exception& e) {
    return std::fprintf(stderr, "diagnose_conceal_plant: %s\n", e.what()), 2;
  }
  return 0;
}
