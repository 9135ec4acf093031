#pragma once
#include <filesystem>
#include "rig/monitor/history.hpp"
namespace rig::monitor {
void write_monitor_report(const History& h, const std::filesystem::path& out_dir);
}
