#include "concealed.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/excitation.hpp"
#include "rig/signal/random.hpp"

namespace rig::diagnose {
namespace {

constexpr int kOversample = 5;

// The generator's own constants. They are deliberately not taken from the fitter
// (rig/diagnose/thresholds.hpp, the effects' parameter ranges, seeds or smoothing), so that
// tuning the fitter cannot move the truth it is judged against. Where a value equals the
// fitter's, it is the generator's choice, kept so that the cases stay the ones the earlier
// benchmark figures were made on.

// The nominal genset (the Stornoway SOPDT of DESIGN.md 7): static gain in kW/%, the
// electromechanical mode, the combustion lag and the dead time.
constexpr double kNominalGainKwPerPct = 46.0;
constexpr double kNominalModeHz = 2.0;
constexpr double kNominalModeZeta = 0.1;
constexpr double kNominalCombustionLagS = 0.03;
constexpr double kNominalDeadTimeS = 0.06;

// The true plant's Coulomb friction is smoothed as fc tanh(dz / eps) with eps this fraction
// of the output rate's std (a sharp sign() would need a much finer grid). The fitter's
// coulomb_friction effect happens to use 0.05 too; this one is the generator's own.
constexpr double kTrueFrictionSmoothing = 0.05;

Eigen::VectorXd upsample(const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd f(n * kOversample);
  for (Eigen::Index k = 0; k < n; ++k)
    for (int j = 0; j < kOversample; ++j) {
      const double a = static_cast<double>(j) / kOversample;
      f(k * kOversample + j) = (1 - a) * x(k) + a * x(std::min(k + 1, n - 1));
    }
  return f;
}

Eigen::VectorXd decimate(const Eigen::VectorXd& f) {
  Eigen::VectorXd x(f.size() / kOversample);
  for (Eigen::Index k = 0; k < x.size(); ++k) x(k) = f(k * kOversample);
  return x;
}

// The effect's true parameters: sized so that each is visible to an engineer but small
// against the noise.
std::vector<double> true_params(Effect e, const DataScales& s, const model::TransferFunction& tf) {
  const double su = s.u_std;
  switch (e) {
    case Effect::kDeadTime:
      return {0.04};
    case Effect::kExtraLag:
      return {0.08};
    case Effect::kResonance:
      return {3.2, 0.05, 2.5, 1.0};
    case Effect::kAcCoupling:
      return {3.0};
    case Effect::kSensorLag:
      return {0.06};
    case Effect::kDeadband:
      return {0.3 * su};
    case Effect::kBacklash:
      return {0.3 * su};
    case Effect::kSaturation:
      return {1.0 * su, 1.6 * su};
    case Effect::kRateLimit:
      return {0.4 * s.u_rate_std};
    case Effect::kStaticNonlinearity:
      return {0.25, -0.04, 0.0};
    // Softening, as the synchronising power's sin(delta): hardening would destabilise the
    // lagged loop of this plant (Routh: 3 k3 z^2 K < 0.65) at the excitation's peaks.
    case Effect::kNonlinearStiffness:
      return {-0.06};
    case Effect::kCoulombFriction:
      return {0.3 * su};
    case Effect::kLoadDamping:
      return {2.0 *
              dominant_mode(tf).value_or(std::make_pair(kNominalModeHz, kNominalModeZeta)).second};
    case Effect::kGainChange:
      return {0.85};
    case Effect::kPeriodicDisturbance:
      return {0.73};
    case Effect::kDrift:
      return {30.0};
    case Effect::kHysteresis:
      return {0.3 * su, 0.0, 1.0, -1.0};  // a play-type loop: v = u - z
    case Effect::kMovedModes:             // a second form of resonance: its cases are resonance's
      return {};
    case Effect::kBoostLimit:  // a second form of saturation: its cases are saturation's
      return {};
    case Effect::kCurvature:  // a second form of static_nonlinearity: its cases are that's
      return {};
    case Effect::kSoftLimit:  // a third form of saturation: its cases are saturation's
      return {};
  }
  return {};
}

// Ornstein-Uhlenbeck drift of correlation time tau and the given rms.
Eigen::VectorXd ou_drift(Eigen::Index n, double dt, double tau, double rms, std::uint64_t seed) {
  signal::Xoshiro256 rng(seed);
  const double a = std::exp(-dt / tau), b = rms * std::sqrt(1 - a * a);
  Eigen::VectorXd d(n);
  double x = rms * rng.normal();
  for (Eigen::Index k = 0; k < n; ++k) d(k) = x = a * x + b * rng.normal();
  return d;
}

}  // namespace

const char* to_string(Concealment c) {
  switch (c) {
    case Concealment::kNoise:
      return "noise";
    case Concealment::kDrift:
      return "drift";
    case Concealment::kAcCoupling:
      return "ac_coupling";
    case Concealment::kPartial:
      return "partial";
  }
  return "?";
}

model::TransferFunction nominal_genset_model() {
  const double wn = 2.0 * std::numbers::pi * kNominalModeHz, zeta = kNominalModeZeta,
               k = kNominalGainKwPerPct, tc = kNominalCombustionLagS;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, k * wn * wn);
  Eigen::VectorXd mode(3), lag(2);
  mode << 1.0, 2.0 * zeta * wn, wn * wn;
  lag << tc, 1.0;
  tf.den = poly_multiply(mode, lag);
  tf.delay_s = kNominalDeadTimeS;
  return tf;
}

namespace {

// The true plant's clean output on the fine grid, decimated to the recording's.
Eigen::VectorXd true_output(const ConcealedSpec& spec, const model::TransferFunction& tf,
                            const Eigen::VectorXd& u, const DataScales& s,
                            const std::vector<double>& p) {
  const double dtf = spec.dt_s / kOversample;
  Eigen::VectorXd uf = upsample(u);
  const Effect e = *spec.effect;
  switch (e) {
    case Effect::kDeadband:
      uf = deadband(uf, p[0]);
      break;
    case Effect::kBacklash:
      uf = backlash(uf, p[0]);
      break;
    case Effect::kHysteresis:
      uf = bouc_wen(uf, p[0], p[1]);
      break;
    case Effect::kSaturation:
      uf = saturate(uf, -p[1], p[0]);
      break;
    case Effect::kRateLimit:
      uf = rate_limit(uf, p[0], dtf);
      break;
    case Effect::kStaticNonlinearity:
      uf = polynomial(uf, p[0], p[1], s.u_std);
      break;
    default:
      break;
  }
  if (kind_of(e) == EffectKind::kFeedback) {
    // nonlinear_stiffness' parameter is the stiffness change at one output std, 3 k3 sz^2 K
    // (its parameter_specs() unit, so that the truth compares with the fitted value).
    const double k3 =
        e == Effect::kNonlinearStiffness ? p[0] / (3 * s.z_std * s.z_std * s.dc_gain) : 0.0;
    const double fc = e == Effect::kCoulombFriction ? p[0] : 0.0,
                 eps = kTrueFrictionSmoothing * s.z_rate_std;
    return decimate(simulate_with_feedback(tf, uf, dtf, [=](double z, double dz) {
      return k3 * z * z * z + fc * std::tanh(dz / eps);
    }));
  }
  const bool linear_in_model =
      kind_of(e) == EffectKind::kLinear && e != Effect::kSensorLag && e != Effect::kAcCoupling;
  const AppliedEffect applied{e, p};
  const model::TransferFunction t =
      linear_in_model ? augmented_tf(tf, std::span<const AppliedEffect>(&applied, 1)) : tf;
  return decimate(model::simulate(t, uf, dtf));
}

Eigen::VectorXd white(Eigen::Index n, double std, std::uint64_t seed) {
  signal::Xoshiro256 rng(seed);
  Eigen::VectorXd w(n);
  for (Eigen::Index k = 0; k < n; ++k) w(k) = std * rng.normal();
  return w;
}

}  // namespace

ConcealedRecording make_concealed(const ConcealedSpec& spec) {
  ConcealedRecording rec;
  const model::TransferFunction tf = nominal_genset_model();
  const auto n = static_cast<Eigen::Index>(std::llround(spec.duration_s / spec.dt_s));
  signal::GaussianOptions go;
  go.n = n, go.dt_s = spec.dt_s, go.bandwidth_hz = 4.0, go.sigma = 0.8, go.clip_sigma = 3.0;
  go.seed = spec.seed;
  const Eigen::VectorXd u = signal::gaussian_excitation(go);
  Problem pr;  // for the data scales the parameters are expressed in
  pr.tf = tf, pr.dt_s = spec.dt_s, pr.u = u, pr.y = u;
  pr.est_weight = pr.val_weight = Eigen::ArrayXd::Ones(n);
  finish_problem(pr);
  const DataScales& s = pr.scales;
  const Eigen::VectorXd z_nominal = pr.baseline_z;
  Eigen::VectorXd z = z_nominal;
  const double noise_ratio =
      spec.noise_to_signal * (spec.concealment == Concealment::kNoise ? 5.0 / 3.0 : 1.0);
  const double sn = noise_ratio * s.z_std;
  Eigen::VectorXd noise = white(n, sn, spec.seed * 7919 + 1);
  std::string what = "null case (nominal model is right)";
  if (spec.effect) {
    const Effect e = *spec.effect;
    rec.truth = true_params(e, s, tf);
    rec.primary_param = parameter_specs(e, s).front().name;
    what = fmt::format("{} {}={:.4g}", to_string(e), rec.primary_param, rec.truth[0]);
    z = true_output(spec, tf, u, s, rec.truth);
    const Eigen::ArrayXd t =
        Eigen::ArrayXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * spec.dt_s;
    if (e == Effect::kSensorLag) {
      // The transducer lag filters the plant's own fluctuations as well as the signal.
      model::TransferFunction lag{Eigen::VectorXd::Ones(1), Eigen::Vector2d(rec.truth[0], 1.0),
                                  0.0};
      z = model::simulate(lag, z + white(n, sn, spec.seed * 7919 + 2), spec.dt_s);
      noise *= 0.2;
    }
    if (e == Effect::kAcCoupling) z = signal::ac_couple(z, spec.dt_s, rec.truth[0]);
    if (e == Effect::kPeriodicDisturbance)
      z += (0.25 * s.z_std * (2 * std::numbers::pi * rec.truth[0] * t + 0.4).cos()).matrix();
    if (e == Effect::kDrift)
      z += ou_drift(n, spec.dt_s, rec.truth[0], 0.5 * s.z_std, spec.seed + 99);
    if (spec.concealment == Concealment::kPartial) z.head(n * 2 / 5) = z_nominal.head(n * 2 / 5);
  }
  Eigen::VectorXd y = z + noise;
  if (spec.concealment == Concealment::kDrift)
    y += ou_drift(n, spec.dt_s, 60.0, 0.4 * s.z_std, spec.seed + 4242);
  if (spec.concealment == Concealment::kAcCoupling) {
    y = signal::ac_couple(y, spec.dt_s, 10.0);
    rec.input.output_rc_s = 10.0;
  }
  rec.input.model = tf;
  rec.input.u = u.array() + 50.0;
  rec.input.y = y.array() + 3500.0;
  rec.input.dt_s = spec.dt_s;
  rec.description =
      fmt::format("{}, concealed by {}, seed {}, {:.0f} s at {:.0f} Hz", what,
                  to_string(spec.concealment), spec.seed, spec.duration_s, 1.0 / spec.dt_s);
  return rec;
}

}  // namespace rig::diagnose
