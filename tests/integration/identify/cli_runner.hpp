// Runs build/bin/rig (RIG_BIN_DIR) as a child process and captures its output and exit code.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/scratch_dir.hpp"

namespace rig::testing {

struct RunResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

inline std::filesystem::path rig_binary() {
  const char* dir = std::getenv("RIG_BIN_DIR");
  return std::filesystem::path(dir ? dir : "build/bin") / "rig";
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline std::filesystem::path scratch(const std::string& name) {
  return rig::testing::scratch_dir("rig_identify_", name);
}

// args are passed through the shell; callers quote paths they build themselves.
inline RunResult run_rig(const std::string& args, const std::filesystem::path& work) {
  const auto out = work / "stdout.txt";
  const auto err = work / "stderr.txt";
  const std::string command =
      rig_binary().string() + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace rig::testing
