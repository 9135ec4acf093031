#include "rig/session/emulator.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

extern char** environ;

namespace rig::session {
namespace {

pid_t spawn(const std::vector<std::string>& args, int out_fd) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (out_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, out_fd, STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, out_fd, STDERR_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  }
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw EmulatorError(fmt::format("cannot start {}: {}", args[0], std::strerror(rc)));
  }
  return pid;
}

// SIGTERM, up to `grace` for the exit, then SIGKILL. Returns the wait status.
int terminate(pid_t pid, std::chrono::milliseconds grace) {
  int status = 0;
  kill(pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + grace;
  while (std::chrono::steady_clock::now() < deadline) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return status;
}

// "plantsim: modbus tcp://127.0.0.1:40123 ready" -> "modbus+tcp://127.0.0.1:40123?unit=1".
std::string uri_from_ready_line(const std::string& line) {
  for (const std::string family : {"modbus", "can"}) {
    const std::string key = "plantsim: " + family + " ";
    const auto at = line.find(key);
    const auto end = line.rfind(" ready");
    if (at == std::string::npos || end == std::string::npos) continue;
    std::string endpoint = line.substr(at + key.size(), end - at - key.size());
    if (endpoint.rfind(family + "+", 0) != 0) endpoint = family + "+" + endpoint;
    if (family == "modbus" && endpoint.find("unit=") == std::string::npos) {
      endpoint += endpoint.find('?') == std::string::npos ? "?unit=1" : "&unit=1";
    }
    return endpoint;
  }
  return {};
}

}  // namespace

std::filesystem::path default_plantsim_path() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("plantsim") : self.parent_path() / "plantsim";
}

void EmulatedPlant::start_socat(const std::filesystem::path& dir) {
  const std::string plant = (dir / "plant").string();
  const std::string rig = (dir / "rig").string();
  socat_pid_ =
      spawn({"/usr/bin/socat", "pty,raw,echo=0,link=" + plant, "pty,raw,echo=0,link=" + rig}, -1);
  for (int i = 0; i < 250; ++i) {
    if (std::filesystem::exists(plant) && std::filesystem::exists(rig)) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw EmulatorError("socat did not create the pseudo-terminal pair in " + dir.string());
}

EmulatedPlant::EmulatedPlant(const EmulatorOptions& o) {
  // A plant TOML (e.g. plantsim --list-params edited to another load) or a preset name.
  const bool toml = o.preset.size() > 5 && o.preset.ends_with(".toml");
  std::vector<std::string> args = {o.plantsim.string(),
                                   toml ? "--config" : "--preset",
                                   o.preset,
                                   "--seed",
                                   std::to_string(o.seed),
                                   "--clock",
                                   o.clock,
                                   "--exit-with-parent"};
  if (o.link_type == "modbus+tcp") {
    args.insert(args.end(), {"--modbus", "tcp://127.0.0.1:0"});
  } else if (o.link_type == "can+udp") {
    args.insert(args.end(), {"--can", "udp://127.0.0.1:0"});
  } else if (o.link_type == "modbus+rtu") {
    std::array<char, 32> tmpl{};
    std::snprintf(tmpl.data(), tmpl.size(), "/tmp/rig-pty-XXXXXX");
    if (mkdtemp(tmpl.data()) == nullptr) throw EmulatorError("cannot create a pty folder");
    pty_dir_ = tmpl.data();
    start_socat(pty_dir_);
    args.insert(args.end(), {"--modbus", "rtu:" + (pty_dir_ / "plant").string() + "?baud=115200"});
    rtu_plant_side_ = (pty_dir_ / "plant").string();
  } else {
    throw EmulatorError("--link-type " + o.link_type +
                        ": expected modbus+tcp, can+udp or modbus+rtu");
  }
  for (const auto& f : o.faults) args.insert(args.end(), {"--fault", f});
  if (!std::filesystem::exists(o.plantsim)) {
    throw EmulatorError("plantsim executable not found at " + o.plantsim.string());
  }
  std::array<int, 2> fds{};
  if (pipe2(fds.data(), O_CLOEXEC) != 0)
    throw EmulatorError("pipe: " + std::string(strerror(errno)));
  pid_ = spawn(args, fds[1]);
  close(fds[1]);
  try {
    uri_ = wait_ready(fds[0], o);
  } catch (...) {
    close(fds[0]);
    stop();
    throw;
  }
  if (!rtu_plant_side_.empty()) {
    uri_ = "modbus+rtu:" + (pty_dir_ / "rig").string() + "?baud=115200&unit=1";
  }
  // Keep draining plantsim's output so that it never blocks on a full pipe.
  const std::filesystem::path log = o.log;
  const int fd = fds[0];
  drain_ = std::thread([fd, log] {
    std::ofstream out;
    if (!log.empty()) out.open(log, std::ios::app);
    std::array<char, 4096> buf{};
    for (;;) {
      const ssize_t n = read(fd, buf.data(), buf.size());
      if (n <= 0) break;
      if (out) out.write(buf.data(), n).flush();
    }
    close(fd);
  });
}

std::string EmulatedPlant::wait_ready(int fd, const EmulatorOptions& o) {
  std::string pending, last_line;
  const auto deadline = std::chrono::steady_clock::now() + o.start_timeout;
  std::ofstream log;
  if (!o.log.empty()) log.open(o.log, std::ios::trunc);
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    std::array<char, 1024> buf{};
    const ssize_t n = read(fd, buf.data(), buf.size());
    if (n <= 0) {
      throw EmulatorError("plantsim exited before it was ready" +
                          (last_line.empty() ? std::string{} : ": " + last_line));
    }
    pending.append(buf.data(), static_cast<std::size_t>(n));
    if (log) log.write(buf.data(), n).flush();
    for (auto nl = pending.find('\n'); nl != std::string::npos; nl = pending.find('\n')) {
      const std::string line = pending.substr(0, nl);
      pending.erase(0, nl + 1);
      if (!line.empty()) last_line = line;
      if (std::string uri = uri_from_ready_line(line); !uri.empty()) return uri;
    }
  }
  throw EmulatorError("plantsim did not report ready within the start timeout");
}

int EmulatedPlant::stop() {
  if (pid_ > 0) {
    exit_status_ = terminate(pid_, std::chrono::milliseconds(3000));
    pid_ = -1;
  }
  if (drain_.joinable()) drain_.join();
  if (socat_pid_ > 0) {
    terminate(socat_pid_, std::chrono::milliseconds(1000));
    socat_pid_ = -1;
  }
  if (!pty_dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(pty_dir_, ec);
    pty_dir_.clear();
  }
  return exit_status_;
}

EmulatedPlant::~EmulatedPlant() { stop(); }

}  // namespace rig::session
