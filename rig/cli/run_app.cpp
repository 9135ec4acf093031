#include <CLI/CLI.hpp>

#include "rig/cli/commands.hpp"

namespace rig::cli {

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
  }
  return kExitOk;
}

}  // namespace rig::cli
