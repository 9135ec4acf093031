// Streaming stepped-sine generator and analyser, driven by the session loop one tick at a
// time:
//
//   rig::fra::SteppedSineAnalyser sweep(plan);
//   while (!sweep.done()) {
//     double e = sweep.excitation_pct();           // request for this tick
//     ... supervisor, link.write(bias), link.read() -> sample ...
//     if (auto point = sweep.push(u_applied_pct, sample.power_kw)) { ... live view ... }
//   }
//   sweep.frf();                                    // freq_hz, mag, phase_deg, coherence
//
// `u_applied_pct` is the excitation as applied (after supervisor back-off and clamp, minus
// the baseline bias), so a back-off during a point shows up as excitation noise/distortion
// and marks the point invalid instead of biasing it. Each point is a faded-in sine
// A sin(2 pi f n dt) that starts at phase zero; samples of its settle time are dropped and
// its integration window (whole cycles) goes through lock_in() (rig/fra/lockin.hpp).
#pragma once

#include <optional>
#include <vector>

#include "rig/fra/frf.hpp"
#include "rig/fra/lockin.hpp"
#include "rig/fra/stepped_sine_plan.hpp"

namespace rig::fra {

struct SteppedSineOptions {
  int max_harmonic = 5;          // harmonics 2..max_harmonic enter the distortion figure
  double min_coherence = 0.95;   // quality: lock-in coherence
  double max_distortion = 0.05;  // quality: response harmonic power / fundamental power
  double max_excitation_noise =
      5e-3;  // quality: excitation (residual + harmonic) power / fundamental
             // (a deep back-off or clamp during the point exceeds it;
             // 0.001 % link quantisation at 0.01 % amplitude does not)
};

struct SteppedSineResult {
  SweepPoint point;     // as planned
  LockInPoint lock_in;  // ratio, harmonic fits of u and y, coherence, std errors
  double mag = 0.0;
  double phase_deg = 0.0;   // wrapped to (-180, 180]
  double distortion = 0.0;  // of the response (harmonics 2..K power / fundamental power)
  double noise = 0.0;       // response residual variance / fundamental power
  bool good = false;        // all quality thresholds met

  model::FrfPoint frf_point() const;
};

class SteppedSineAnalyser {
 public:
  enum class Phase { kSettling, kIntegrating, kDone };

  explicit SteppedSineAnalyser(SweepPlan plan, SteppedSineOptions options = {});

  // The excitation to request at the current tick, % of rated power (0 once done).
  double excitation_pct() const;
  // Consumes the tick's applied excitation and measured response; returns the point's result
  // when this sample completes a point.
  std::optional<SteppedSineResult> push(double u_applied_pct, double y_kw);

  bool done() const { return index_ >= plan_.points.size(); }
  Phase phase() const;
  std::size_t point_index() const { return index_; }
  const SweepPlan& plan() const { return plan_; }
  const std::vector<SteppedSineResult>& results() const { return results_; }
  std::vector<model::FrfPoint> frf() const;

 private:
  SteppedSineResult analyse() const;

  SweepPlan plan_;
  SteppedSineOptions options_;
  std::size_t index_ = 0;      // current point
  Eigen::Index n_ = 0;         // sample within the current point
  std::vector<double> u_, y_;  // integration window of the current point
  std::vector<SteppedSineResult> results_;
};

}  // namespace rig::fra
