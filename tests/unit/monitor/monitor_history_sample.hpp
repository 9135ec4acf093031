// A two-run history for the report tests: values every second for an hour and a half, a trip,
// an alarm, and `events` events.
#pragma once

#include <cmath>
#include <string>

#include "rig/monitor/history.hpp"

namespace rig::monitor {

inline void write_sample_history(const std::filesystem::path& file, int events) {
  History h = History::open(file);
  for (int r = 0; r < 2; ++r) {
    const long run = h.begin_run({"sim://", "baseline.json", "nominal", r + 1L, 400.0});
    for (int i = 0; i <= 2700; ++i) {
      const double t = i;
      const double drift = r == 1 && t > 1800.0 ? -0.002 * (t - 1800.0) : 0.0;
      h.add_values(run, t,
                   {{"fn_hz", 1.2 + 0.01 * std::sin(0.01 * t), {}, {}},
                    {"gain_db", drift + 0.05 * std::sin(0.05 * t), -1.0, 1.0}});
    }
    if (r == 0) {
      for (int e = 0; e < events; ++e) h.add_event(run, e, "note", "event " + std::to_string(e));
      h.add_event(run, 2600.0, "trip", "power out of band");
      h.end_run(run, 3, "tripped");
    } else {
      h.add_alarm(run, {2400.0, "injector/cylinder loss", "additive", 0.9, 1800.0,
                        "Check the injectors.", R"({"z":4.2})"});
    }
  }
}

}  // namespace rig::monitor
