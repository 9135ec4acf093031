// The one top-level handler: every command's typed errors become one line on stderr and the
// exit code of DESIGN.md section 4 (rig/io/exit_code.hpp). Commands throw; nothing below a
// session's tick loop does (the session turns its own failures into trips and exit codes).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <new>
#include <stdexcept>

#include "rig/cli/commands.hpp"
#include "rig/io/input_error.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/monitor/history.hpp"
#include "rig/session/test_config.hpp"

namespace rig::cli {
namespace {

std::string command_name(const CLI::App& app) {
  const auto subs = app.get_subcommands();
  return subs.empty() ? std::string("rig") : "rig " + subs.front()->get_name();
}

int report(const CLI::App& app, const char* what, int code) {
  fmt::print(stderr, "{}: {}\n", command_name(app), what);
  return code;
}

}  // namespace

int run_app(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own exit code, already reported
  } catch (const CLI::ParseError& e) {
    app.exit(e);  // prints the usage error
    return kExitUsage;
  } catch (const io::OutDirError& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const session::ConfigError& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const io::InputError& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const std::invalid_argument& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const monitor::HistoryError& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const std::filesystem::filesystem_error& e) {
    return report(app, e.what(), kExitUsage);
  } catch (const std::bad_alloc&) {
    return report(app, "out of memory", kExitSafety);
  } catch (const std::exception& e) {
    // A failure of the rig itself (DESIGN.md section 4: exit 4).
    return report(app, (std::string("internal failure: ") + e.what()).c_str(), kExitSafety);
  }
  return kExitOk;
}

}  // namespace rig::cli
