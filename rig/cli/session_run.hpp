// Shared by `rig commission` and `rig sweep`: test file loading, the emulated plant,
// SIGINT handling and the human/JSON summary.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rig/cli/live_outputs.hpp"
#include "rig/session/session.hpp"
#include "rig/session/test_config.hpp"

namespace CLI {
class App;
}

namespace rig::cli {

struct SessionArgs {
  std::string link;
  std::filesystem::path test_file;
  std::filesystem::path out_dir;
  bool emulate = false;
  std::string preset = "stornoway";
  std::uint64_t seed = 1;
  std::string link_type = "modbus+tcp";
  std::string clock;  // --clock with --emulate: "lockstep" (empty: the default) or "realtime"
  std::vector<std::string> faults;
  bool json = false;
  bool quiet = false;
  bool force = false;  // clear a non-empty --out first
  LiveArgs live;       // --http, --mqtt, --set-id
};

// The options every session command shares (--link, --test, --out, --emulate, ...;
// commission.cpp).
void add_session_options(CLI::App& cmd, SessionArgs& a);
// --http, --mqtt, --set-id (part of the session options).
void add_live_options(CLI::App& cmd, LiveArgs& a);

// Loads the test file (or the defaults), applies the emulated-plant settings, checks that a
// link is named. Throws session::ConfigError (exit code 2).
session::TestConfig load_config(const SessionArgs& args, const std::string& command);

// Prepares --out, installs the SIGINT/SIGTERM handler, starts the live page and fleet feed
// (--http, --mqtt) and plantsim for --emulate, runs body with the session options, then
// stops plantsim and ends the live outputs; returns body's exit code. body publishes the
// outcome on options.feed when there is one (publish_outcome).
int with_session(const SessionArgs& args, const std::string& command,
                 const std::function<int(const session::SessionOptions&)>& body);

// The command's outcome on the live feed (nothing without one).
void publish_outcome(const session::SessionOptions& o, int exit_code, const std::string& outcome,
                     const nlohmann::json& extra = nlohmann::json::object());

// Runs the session (starting and stopping plantsim for --emulate) and returns the exit code.
int run_session(const SessionArgs& args, session::TestConfig config, const std::string& command);

}  // namespace rig::cli
