#include "recording_out.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

#include "rig/io/sidecar.hpp"
#include "rig/model/model_file.hpp"

namespace rig::diagnose::bench {

void write_diagnose_recording(const std::filesystem::path& dir, const Eigen::VectorXd& u,
                              const Eigen::VectorXd& y, double dt_s, std::uint64_t seed,
                              std::optional<double> output_rc_s,
                              const model::TransferFunction* model) {
  std::filesystem::create_directories(dir);
  std::ofstream csv(dir / "rec.csv");
  csv.precision(12);
  csv << "t,u,y\n";
  for (Eigen::Index k = 0; k < u.size(); ++k)
    csv << static_cast<double>(k) * dt_s << ',' << u(k) << ',' << y(k) << '\n';
  io::Sidecar sc;
  sc.sample_rate_hz = 1.0 / dt_s;
  sc.units = {{"t", "s"}, {"u", "%"}, {"y", "kW"}};
  sc.seed = seed;
  if (output_rc_s) sc.coupling_rc_s = *output_rc_s, sc.coupled_columns = {"y"};
  io::write_sidecar(dir / "rec.json", sc);
  if (!model) return;
  model::ModelFile m;
  m.tf = *model;
  m.input = std::string("u");  // (a literal assignment trips GCC 12 -Wrestrict here)
  m.output = std::string("y");
  m.units = {{"input", "% of rated power"}, {"output", "kW"}};
  model::write_model(dir / "model.json", m);
}

void print_hypotheses(const DiagnoseResult& r) {
  fmt::print("    {}\n", r.explanation);
  for (std::size_t i = 0; i < std::min<std::size_t>(4, r.hypotheses.size()); ++i) {
    const auto& h = r.hypotheses[i];
    std::string ps;
    for (const auto& a : h.effects)
      for (double p : a.params) fmt::format_to(std::back_inserter(ps), " {:.4g}", p);
    fmt::print("    #{} {} [{} ] vfit {:.1f}->{:.1f} score {:+.2f}\n", i + 1, h.name(), ps,
               h.validation_fit_before, h.validation_fit_after, h.score);
  }
}

}  // namespace rig::diagnose::bench
