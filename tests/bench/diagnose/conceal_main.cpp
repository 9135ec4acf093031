// diagnose_conceal: writes a concealed-effect recording (rec.csv + rec.json sidecar) and the
// nominal model (model.json) for `rig diagnose`:
//   diagnose_conceal --effect dead_time|...|none --concealment noise|drift|ac_coupling|partial
//                    [--seed N] [--duration S] --out DIR
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "concealed.hpp"
#include "recording_out.hpp"

using namespace rig::diagnose;
using rig::diagnose::bench::write_diagnose_recording;

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
  write_diagnose_recording(out, rec.input.u, rec.input.y, rec.input.dt_s, spec.seed,
                           rec.input.output_rc_s, &rec.input.model);
  std::printf("%s\n  truth:", rec.description.c_str());
  for (double p : rec.truth) std::printf(" %.6g", p);
  std::printf("\n");
  return 0;
}
