// A child process for integration tests: started with pipes on stdout and stderr, read line by
// line with timeouts, always killed (SIGKILL) and reaped when the object goes away.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace plantsim::testing {

class ChildProcess {
 public:
  explicit ChildProcess(std::vector<std::string> argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Next stdout line, or nullopt on timeout / end of file.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout);
  // Reads stdout lines until one contains `needle`; returns it.
  std::optional<std::string> wait_for_line(const std::string& needle,
                                           std::chrono::milliseconds timeout);
  // Everything the child wrote on stderr so far (reads what is available, waits up to timeout
  // for end of file when the child has exited).
  std::string stderr_text(std::chrono::milliseconds timeout = std::chrono::milliseconds(0));
  void signal(int sig);
  // Exit code (128 + signal if killed by one), or nullopt if still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  int err_fd_ = -1;
  std::string out_buffer_;
  std::string err_text_;
  std::optional<int> exit_code_;
};

// Absolute path of a program in RIG_BIN_DIR (build/bin) or next to the test (build/tests).
std::string bin_path(const std::string& name);
std::string tests_bin_path(const std::string& name);

// Parses "plantsim: modbus tcp://127.0.0.1:40123 ready" -> 40123 (also udp://).
int port_of_ready_line(const std::string& line);

}  // namespace plantsim::testing
