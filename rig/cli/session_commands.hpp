// The session commands of the `rig` executable (DESIGN.md section 4):
//   rig commission --link URI --test test.toml --out DIR
//   rig commission --emulate [--preset stornoway] [--seed N] [--link-type T] --out DIR
//   rig sweep      --link URI|--emulate --from HZ --to HZ --points N --out DIR
//   rig compare    --model MODEL.json --frf FRF.csv --out DIR
//   rig monitor    --link URI|--emulate --baseline MODEL.json --out DIR [--history DB] ...
//   rig monitor    --report DB --out DIR
// Each add_* registers a subcommand whose callback runs it; a non-zero exit code is thrown
// as CLI::RuntimeError(code), which CLI::App::exit() returns without printing.
#pragma once

namespace CLI {
class App;
}

namespace rig::cli {

void add_commission_command(CLI::App& app);
void add_sweep_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_monitor_command(CLI::App& app);

}  // namespace rig::cli
