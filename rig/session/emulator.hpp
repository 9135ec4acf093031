// `rig commission --emulate`: starts the plantsim executable (from the rig's own bin dir) in
// lockstep (or on its realtime clock) on an ephemeral port, reads the endpoint it announces, and stops it afterwards.
// For modbus+rtu a socat pseudo-terminal pair joins the two sides.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace rig::session {

struct EmulatorError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct EmulatorOptions {
  std::filesystem::path plantsim;  // the executable
  std::string preset = "stornoway";  // a preset name, or a plant TOML (NAME.toml)
  std::uint64_t seed = 1;
  std::string link_type = "modbus+tcp";  // modbus+tcp | can+udp | modbus+rtu
  std::string clock = "lockstep";        // plantsim --clock: lockstep | realtime
  std::vector<std::string> faults;       // NAME=VALUE@t=SECONDS
  std::filesystem::path log;             // plantsim's stdout/stderr go here (empty: discarded)
  std::chrono::milliseconds start_timeout{20000};
};

// The plantsim next to the running executable (/proc/self/exe's folder).
std::filesystem::path default_plantsim_path();

class EmulatedPlant {
 public:
  // Starts plantsim and waits for its "ready" line; EmulatorError on failure (the message
  // carries plantsim's last output line).
  explicit EmulatedPlant(const EmulatorOptions& options);
  ~EmulatedPlant();
  EmulatedPlant(const EmulatedPlant&) = delete;
  EmulatedPlant& operator=(const EmulatedPlant&) = delete;

  const std::string& link_uri() const { return uri_; }  // what the rig connects to
  pid_t pid() const { return pid_; }
  // SIGTERM, then SIGKILL after a grace period; returns the exit status. Idempotent.
  int stop();

 private:
  void start_socat(const std::filesystem::path& dir);
  std::string wait_ready(int fd, const EmulatorOptions& options);

  pid_t pid_ = -1;
  pid_t socat_pid_ = -1;
  int exit_status_ = -1;
  std::string uri_;
  std::string rtu_plant_side_;
  std::thread drain_;
  std::filesystem::path pty_dir_;
};

}  // namespace rig::session
