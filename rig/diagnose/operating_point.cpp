// A grid event that moved the set's operating point (docs/diagnose.md, verdict step 6).
//
// A set in droop answers a step of the grid's frequency by stepping its power, and a fuel
// map is curved: at the new operating point the slope inside the speed loop, and with it the
// set's answer to the bias, is not the one the model was identified at. On droopsim a 46 mHz
// event changed that answer by 3.7 % after it (docs/droopsim.md, "The grid event's null").
// When the residual is correlated with the input on one side of the event at most (over the
// whole record it is: the input tests failed), every other test passes and no effect of the
// library explains it, the recording is a linear answer at each operating point, the model's
// at one of them at least: no missing effect. Correlated on both sides, it stays unexplained.
// The sign test may fail beside the cross-correlation if it passes on each side alone (as the
// cross-correlation's "on neither side alone"): a curved map answers a rise and a fall a
// little differently, and an asymmetry too weak to show on either operating point's own data
// is not named over both (droopsim seed 6's d084, a grid event on the curved fuel map: z -5.5
// over the record, -4.6 before the event and -3.3 after it; the other seeds' grid-event nulls
// read -1.6 to -4.5 over the record). Split at a share p of the record, one asymmetry reads z
// sqrt(p) and z sqrt(1 - p) on the sides, so this admits a whole-record z up to 5 / sqrt(max(p, 1 -
// p)), only where no effect of the library explains the record.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/evidence.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {

namespace {

// The band test on the rows [from, to) alone (its own Welch segments and bound).
bool band_on(const Problem& pr, const Eigen::VectorXd& res, Eigen::Index from, Eigen::Index to) {
  Problem side = pr;
  side.u = pr.u.segment(from, to - from);
  side.y = pr.y.segment(from, to - from);
  return locate_frequency(side, res.segment(from, to - from)).band_hz.has_value();
}

}  // namespace

std::optional<OperatingPointMove> operating_point_moved(const DiagnoseResult& r) {
  if (!r.bus_frequency || r.bus_frequency->event_at <= 0) return std::nullopt;
  const Location& loc = r.location;
  if (loc.amp.amplitude_dependent || loc.amp.direction_dependent ||
      loc.amp.direction_beyond_lag_dependent || loc.step_gain.fires || r.location.clip.side != 0)
    return std::nullopt;
  // The cross-correlation and the band are the tests this rule reads; a sign test failing
  // alone is not.
  const bool correlated = !loc.tests.independent || loc.half_dependent >= 0;
  const bool band = loc.freq.band_hz.has_value();
  if (!correlated && !band) return std::nullopt;
  const Problem& pr = r.problem;
  if (r.baseline_yhat.size() != pr.y.size()) return std::nullopt;
  const Eigen::VectorXd res = pr.y - r.baseline_yhat;
  const Eigen::Index n = res.size(), at = r.bus_frequency->event_at;
  Eigen::Index from = 0;
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index lags = residual_test_lags(pr, loc);
  // Each side long enough for the test's lags, as each half of the record (locate.cpp).
  if (at - from < 4 * lags || n - at < 4 * lags) return std::nullopt;
  const ResidualTests before = residual_tests(res.segment(from, at - from),
                                              pr.u.segment(from, at - from), pr.dt_s, lags, 2.0);
  const ResidualTests after =
      residual_tests(res.tail(n - at), pr.u.tail(n - at), pr.dt_s, lags, 2.0);
  if (!before.independent && !after.independent) return std::nullopt;
  // A band where the answer departs from the model over the record, on one side at most
  // (droopsim seed 11 d084: 95 % of the model's gain at 2.6-2.8 Hz, beside the
  // electromechanical mode, after a 36 mHz fall): the mode moved with the operating point.
  const std::array<bool, 2> band_sides{band && band_on(pr, res, from, at),
                                       band && band_on(pr, res, at, n)};
  if (band_sides[0] && band_sides[1]) return std::nullopt;
  const bool after_dependent =
      !after.independent || (before.independent && after.cross_ratio / after.cross_threshold >
                                                       before.cross_ratio / before.cross_threshold);
  const ResidualTests& worse = after_dependent ? after : before;
  const std::array<double, 2> sign_z_sides{sign_z(pr, res, r.baseline_yhat, from, at),
                                           sign_z(pr, res, r.baseline_yhat, at, -1)};
  if (loc.amp.sign_dependent &&
      std::max(std::abs(sign_z_sides[0]), std::abs(sign_z_sides[1])) > thresholds::kSignDirectionZ)
    return std::nullopt;
  return OperatingPointMove{static_cast<double>(at) * pr.dt_s,
                            r.bus_frequency->event_step,
                            after_dependent,
                            !before.independent || !after.independent,
                            worse.cross_ratio,
                            worse.cross_threshold,
                            sign_z_sides,
                            band,
                            band_sides,
                            correlated};
}

// Droopsim seed 9 d084, a grid event at 95 s on the curved fuel map: a curvature on the
// governor's error scored 2.04 points (quadratic_rel 0.15, the level test's chi^2 11.2 under
// its 13.28), the residual correlated after the event only. The move's own words say what
// it is; naming the map would name the operating point's change as an effect.
bool map_of_the_move(const DiagnoseResult& r) {
  const HypothesisFit* h = r.chosen();
  return h && has_nonlinearity(*h) && memoryless_static_maps_only(*h, r.problem.scales) &&
         !level_evidenced(r, *h) && operating_point_moved(r).has_value();
}

}  // namespace rig::diagnose
