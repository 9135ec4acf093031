// diagnose_conceal: writes a concealed-effect recording (rec.csv + rec.json sidecar) and the
// nominal model (model.json) for `rig diagnose`:
//   diagnose_conceal --effect dead_time|...|none --concealment noise|drift|ac_coupling|partial
//                    [--seed N] [--duration S] --out DIR
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "rig/diagnose/concealed.hpp"
#include "rig/io/model_file.hpp"
#include "rig/io/sidecar.hpp"

using namespace rig::diagnose;

int main(int argc, char** argv) {
  std::string effect = "none", concealment = "noise", out;
  ConcealedSpec spec;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--effect")
      effect = v;
    else if (a == "--concealment")
      concealment = v;
    else if (a == "--seed")
      spec.seed = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--duration")
      spec.duration_s = std::atof(v.c_str());
    else if (a == "--out")
      out = v;
  }
  if (effect != "none") {
    spec.effect = effect_from_string(effect);
    if (!spec.effect)
      return std::fprintf(stderr, "diagnose_conceal: unknown effect %s\n", effect.c_str()), 2;
  }
  bool found = false;
  for (Concealment c :
       {Concealment::kNoise, Concealment::kDrift, Concealment::kAcCoupling, Concealment::kPartial})
    if (concealment == to_string(c)) spec.concealment = c, found = true;
  if (!found || out.empty())
    return std::fprintf(stderr, "diagnose_conceal: see the usage in the source\n"), 2;
  const ConcealedRecording rec = make_concealed(spec);
  const std::filesystem::path dir(out);
  std::filesystem::create_directories(dir);
  std::ofstream csv(dir / "rec.csv");
  csv.precision(12);
  csv << "t,u,y\n";
  for (Eigen::Index k = 0; k < rec.input.u.size(); ++k)
    csv << static_cast<double>(k) * rec.input.dt_s << ',' << rec.input.u(k) << ',' << rec.input.y(k)
        << '\n';
  rig::io::Sidecar sc;
  sc.sample_rate_hz = 1.0 / rec.input.dt_s;
  sc.units = {{"t", "s"}, {"u", "%"}, {"y", "kW"}};
  sc.seed = spec.seed;
  if (rec.input.output_rc_s) sc.coupling_rc_s = *rec.input.output_rc_s, sc.coupled_columns = {"y"};
  rig::io::write_sidecar(dir / "rec.json", sc);
  rig::io::ModelFile m;
  m.tf = rec.input.model;
  m.input = "u", m.output = "y";
  m.units = {{"input", "% of rated power"}, {"output", "kW"}};
  rig::io::write_model(dir / "model.json", m);
  std::printf("%s\n  truth:", rec.description.c_str());
  for (double p : rec.truth) std::printf(" %.6g", p);
  std::printf("\n");
  return 0;
}
