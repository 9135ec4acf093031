#include <fmt/format.h>

#include <sstream>

#include "plantsim/plant/config.hpp"

namespace plantsim {

std::string to_toml(const Params& params, const std::string& header) {
  std::ostringstream out;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);)
    out << (line.empty() ? "#" : "# " + line) << '\n';
  std::string_view block;
  const auto& specs = param_specs();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const ParamSpec& s = specs[i];
    const auto dot = s.name.find('.');
    if (s.name.substr(0, dot) != block) {
      block = s.name.substr(0, dot);
      out << "\n[" << block << "]\n";
    }
    // fmt's shortest round-trip form: the file reproduces the preset bit for bit.
    const std::string value = fmt::format("{}", params[static_cast<P>(i)]);
    const std::string key = fmt::format("{} = {}", s.name.substr(dot + 1), value);
    out << fmt::format("{:<34} # [{}] {} ({} .. {})\n", key, s.unit, s.doc, s.min_value,
                       s.max_value);
  }
  return out.str();
}

}  // namespace plantsim
