// The plantsim subprocess behind `rig diagnose --model PLANT.toml` (diagnose_plant.hpp).
#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "rig/cli/diagnose_plant.hpp"
#include "rig/io/input_error.hpp"
#include "rig/io/recording.hpp"

extern char** environ;

namespace rig::cli {
namespace {

// The last non-empty line of a program's output, without plantsim's "plantsim: " prefix.
std::string last_line(const std::string& output) {
  std::istringstream in(output);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  const std::string prefix = "plantsim: ";
  if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
  return last.empty() ? "no message" : last;
}

// Runs plantsim; a non-zero exit becomes an InputError naming the plant file.
std::string run_plantsim(const std::filesystem::path& toml, std::vector<std::string> argv) {
  const ProcessResult r = run_process(argv);
  if (r.exit_code != 0)
    throw io::InputError(
        toml.string(), 0, "",
        fmt::format("plantsim rejected the plant (exit {}): {}", r.exit_code, last_line(r.output)));
  return r.output;
}

// --list-params prints every key as `name = value  # [unit] meaning (lo .. hi)`; toml++ reads
// the values, the comments give the ranges.
void read_params(const std::string& text, const std::filesystem::path& toml, PlantModel* m) {
  toml::table root;
  try {
    root = toml::parse(std::string_view(text), std::string_view("plantsim --list-params"));
  } catch (const toml::parse_error& e) {
    throw io::InputError(toml.string(), 0, "",
                         std::string("plantsim --list-params printed malformed TOML: ") +
                             std::string(e.description()));
  }
  for (auto&& [block, node] : root) {
    const auto* table = node.as_table();
    if (!table) continue;
    for (auto&& [key, value] : *table)
      if (const auto v = value.value<double>())
        m->params[std::string(block.str()) + "." + std::string(key.str())] = *v;
  }
  static const std::regex section(R"(^\[(\w+)\])");
  static const std::regex entry(R"(^(\w+)\s*=.*\(([-+0-9.eE]+) \.\. ([-+0-9.eE]+)\)\s*$)");
  std::istringstream in(text);
  std::string line, block;
  std::smatch mt;
  while (std::getline(in, line)) {
    if (std::regex_search(line, mt, section))
      block = mt[1];
    else if (std::regex_search(line, mt, entry))
      m->ranges[block + "." + mt[1].str()] = {std::stod(mt[2]), std::stod(mt[3])};
  }
}

}  // namespace

ProcessResult run_process(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0)
    throw std::runtime_error(fmt::format("pipe: {}", std::strerror(errno)));
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    throw std::runtime_error(fmt::format("cannot start {}: {}", args[0], std::strerror(rc)));
  }
  ProcessResult out;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n > 0)
      out.output.append(buf, static_cast<std::size_t>(n));
    else if (n == 0 || errno != EINTR)
      break;
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return out;
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "rig-diagnose-XXXXXX").string();
  if (mkdtemp(tmpl.data()) == nullptr)
    throw std::runtime_error(
        fmt::format("cannot create a temporary folder: {}", std::strerror(errno)));
  path_ = tmpl;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

PlantModel load_plant_model(const std::filesystem::path& toml,
                            const std::filesystem::path& plantsim, const TempDir& tmp) {
  if (!std::filesystem::exists(plantsim))
    throw io::InputError(toml.string(), 0, "",
                         fmt::format("a plant TOML needs the plantsim executable, not found at {}",
                                     plantsim.string()));
  PlantModel m;
  m.toml = toml, m.plantsim = plantsim;
  const std::filesystem::path tf = tmp.path() / "baseline.tf.json";
  run_plantsim(toml, {plantsim.string(), "--config", toml.string(), "--linearise", tf.string()});
  read_params(run_plantsim(toml, {plantsim.string(), "--config", toml.string(), "--list-params"}),
              toml, &m);
  m.linear = model::read_model(tf);
  return m;
}

Eigen::VectorXd replay_plant(const std::filesystem::path& plantsim,
                             const std::filesystem::path& toml, const Eigen::VectorXd& u,
                             double dt_s, const TempDir& tmp) {
  const std::filesystem::path in = tmp.path() / "replay_in.csv";
  const std::filesystem::path out = tmp.path() / "replay_out.csv";
  {
    std::ofstream f(in);
    f << "t,u\n";
    for (Eigen::Index k = 0; k < u.size(); ++k)
      f << fmt::format("{:.9g},{:.17g}\n", static_cast<double>(k) * dt_s, u(k));
    if (!f) throw std::runtime_error(fmt::format("{}: cannot write", in.string()));
  }
  const ProcessResult r = run_process({plantsim.string(), "--config", toml.string(), "--replay",
                                       in.string(), "--replay-out", out.string()});
  if (r.exit_code != 0)
    throw std::runtime_error(fmt::format("plantsim --replay of {} failed (exit {}): {}",
                                         toml.string(), r.exit_code, last_line(r.output)));
  io::ReadOptions ro;
  ro.columns = {"power_kw"};
  ro.read_sidecar = false;
  const io::Recording rec = io::read_recording(out, ro);
  if (rec.rows() != u.size())
    throw std::runtime_error(
        fmt::format("{}: {} rows, expected {}", out.string(), rec.rows(), u.size()));
  return rec.column("power_kw");
}

}  // namespace rig::cli
