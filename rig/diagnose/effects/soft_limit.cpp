// saturation, third form: limits whose corners a dither rounds. A limit that ripple or noise
// reaches from the operating point is met now and then, more often the nearer the demand
// comes: on average the demand passes a smooth, one-sided compression, not a corner (a
// rack limit just above the operating demand with the firing ripple on the governor's
// output; droopsim's smoke limiter beside its half-order ripple fitted 0.9-2.6 points under
// static_nonlinearity's kinked map as a hard limit, on every seed). For a Gaussian dither of
// rms s the mean of clamp(v + n, -L, U) is
//   v - s [z_u Phi(z_u) + phi(z_u)] + s [z_l Phi(z_l) + phi(z_l)],  z_u = (v - U) / s,
//   z_l = (-L - v) / s,
// less its value at v = 0 (the recorded operating point already carries the dither's mean).
// Far beyond the corner it is flat, as a limit is (a kink keeps a slope); s -> 0 is the
// hard limit (first form, saturation.cpp).
//
// Plant: as the hard limit's (gov.tmax_pu, gov.tmin_pu, saturation.cpp); the dither is the
// plant's own ripple and noise: not mapped.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// The dither's rms: from a twentieth of the input's spread (a corner hardly rounded) to
// twice it (a limit seen only as a compression).
constexpr double kDitherLoStd = 0.05, kDitherHiStd = 2.0;
// A fitted dither at this fraction of its upper bound or more stopped there.
constexpr double kDitherAtBound = 0.98;
// A Gaussian dither reaches three of its rms beyond the recorded excursion (99.7 %).
constexpr double kDitherReachRms = 3.0;

// A side's distance from the operating point: up to six of the input's standard deviations;
// at this fraction of that or more it stopped at the bound, never met.
constexpr double kSideHiStd = 6.0, kSideAtBound = 0.98;

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"upper_limit", 0.05 * su, kSideHiStd * su, true},
          {"lower_limit_magnitude", 0.05 * su, kSideHiStd * su, true},
          {"dither_rms", kDitherLoStd * su, kDitherHiStd * su, true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{1.0 * su, 2.5 * su, 0.5 * su}, {0.5 * su, 2.5 * su, 0.3 * su}, {1.5 * su, 1.5 * su, su}};
}

// E[(x - c)+] / s for x ~ N(v, s^2), z = (v - c) / s.
double excess(double z) {
  const double cdf = 0.5 * std::erfc(-z / std::numbers::sqrt2);
  const double pdf = std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi);
  return z * cdf + pdf;
}

double dithered_clamp(double v, const Params& p) {
  const double s = std::max(p[2], 1e-12);
  return v - s * excess((v - p[0]) / s) + s * excess((-p[1] - v) / s);
}

// The map's value at the operating point, kept for the parameters last asked: the loops
// step the map a sample at a time (a third of the soft limit's time went to this constant).
double at_zero(const Params& p) {
  thread_local Params last;
  thread_local double value = 0.0;
  if (p != last) last = p, value = dithered_clamp(0.0, p);
  return value;
}

double limited(double v, const Params& p) { return dithered_clamp(v, p) - at_zero(p); }

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  const double zero = at_zero(p);
  for (double& x : v) x = dithered_clamp(x, p) - zero;
  return v;
}

// Where it is tried: the bias's own path (the set's noise at a limit on it) and the
// governor's error and PI output with the loop's feedback fitted, where the ripple that loop
// feeds back reaches a limit. Of 8 soft-limit verdicts on droopsim seeds 1, 4, 6-8 and gensim
// seed 5 every one was at these three; the unity loop's error and PI, the in-loop and the
// output places never led, and took 60 % of its screen time (1.26 of 2.08 s of CPU on a
// 600 s record).
bool tried_at(Place place) {
  return place == Place::kInput || place == Place::kGovernorError || place == Place::kGovernorPi;
}

double apply_on_error(const Params& p, std::span<const double> e, double, double) {
  return limited(e.back(), p);
}

double step(const Params& p, StepState&, double x, double, double) { return limited(x, p); }

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  // A side at its bound was never met: a one-sided limit.
  const double far = kSideAtBound * kSideHiStd * su;
  const auto side = [&](const char* sign, double lim) {
    return lim >= far ? std::string()
                      : fmt::format("{}{:.3g} ({:.1f} standard deviations)", sign, lim, lim / su);
  };
  const std::string up = side("+", p[0]), down = side("-", p[1]);
  const std::string sides = up.empty() || down.empty() ? up + down : up + " / " + down;
  return fmt::format(
      "the input is limited {}{} about the operating point, its corners rounded by ripple or "
      "noise of {:.3g} rms at the limit",
      sides.empty() ? "" : (up.empty() != down.empty() ? "on one side only, at " : "at "),
      sides.empty() ? "on neither side" : sides, p[2]);
}

// The limits as the hard limit maps them (saturation.cpp); the dither is not the plant's. A
// limit the dither reaches is identified a little beyond the recorded excursion: three of
// its rms.
void to_plant(const PlantContext& c, PlantTarget& m) {
  const auto& p = c.effect.params;
  effects::limits_to_plant(c, m, p[0], p[1], kDitherReachRms * p[2]);
}

// A dither at its upper bound rounds small limits into a plain gain ((U + L) / (s
// sqrt(2 pi)) near the operating point): the search's stand-in for a gain change.
bool credible(const AppliedEffect& e, const DataScales& s) {
  return e.params.size() < 3 || e.params[2] < kDitherAtBound * kDitherHiStd * s.u_std;
}

}  // namespace

const EffectModel kSoftLimitEffect{
    .id = Effect::kSoftLimit,
    .name = "saturation",
    .kind = EffectKind::kInputNonlinearity,
    .description = "limits on the input whose corners ripple or noise rounds",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .apply_on_error = apply_on_error,
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .level_shaped = true,
    .tried_at = tried_at,
    .credible = credible,
};

}  // namespace rig::diagnose
