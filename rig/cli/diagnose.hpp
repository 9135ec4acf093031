// rig diagnose --recording REC.csv --model MODEL.json --out DIR   (diagnose.cpp)
#pragma once

namespace CLI {
class App;
}

namespace rig::cli {

void add_diagnose_command(CLI::App& app);

}  // namespace rig::cli
