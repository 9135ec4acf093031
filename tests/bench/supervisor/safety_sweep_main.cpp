// bench_safety_sweep: the safety sweep with a wrong starting assumption on the emulated
// Stornoway plant itself (plantsim, CVODE), driven directly as the session drives it in
// lockstep: every 10 ms tick the supervisor judges the last reading, the bias is written,
// the plant takes 10 ticks of 1 ms and is read (Plant::measure(), the rig's view: transducer
// lag, noise, 50 Hz pick-up, drift, quantisation).
//   bench_safety_sweep [--runs 200] [--seed 1] [--duration-s 120]
//   bench_safety_sweep --plant-seed N --factor F [--duration-s 120]   (replay one run)
// Each run draws a factor f log-uniform in [0.3, 3] and a plant seed from the master seed
// (xoshiro256**), builds make_plant(seed) and does what a session does (rig/session/):
//  1. steady state: 10 s record, check_steady_state() with the default limits -> P0 and the
//     noise std (a refused check ends the run and counts as a failure of the sweep);
//  2. pilot: supervised, Gaussian excitation of std 0.3 % (4 Hz, clipped at 3 sigma, seed
//     excitation seed + 7919), the 10 s soft start then 20 s, a 2 s raised-cosine fade-out
//     as the session's pilot ends, ramp-down; u (as applied) and P - P0 after the soft start;
//  3. the wrong plan: analyse_pilot() on u / f instead of u, so the pilot gain it computes is
//     exactly f times the measured one and the planned std 1/f times the right plan (unless
//     the clamp limits it): f < 1 plans too much excitation (0.3: 3.3x), f > 1 too little,
//     the convention of tests/unit/supervisor/backoff_test.cpp (prior gain = f x true gain);
//  4. excitation, right after the pilot's ramp-down (its ring-out falls into the first
//     seconds): supervised, Gaussian excitation of the planned std (4 Hz, clip 3 sigma) for
//     --duration-s, a 2 s raised-cosine fade-out (as the session ends it), finish(), the
//     ramp-down to baseline, then 2 s more at baseline (the mode rings on).
// Supervisor configuration as RunContext::supervisor_config() builds it from the default test
// file: band 3 % of P0, plan_fraction 0.8, back-off zero_fraction 0.9, resonance 2 Hz, noise
// from the steady state, clamp 5 %, ramp 2 %/s, peak_to_rms 4, bias echo (layer 0) and
// speed/frequency plausibility on. Every reading of steps 2 and 4 is judged against the band
// (|P - P0| > 3 % P0 is outside). Per run: the worst |P - P0| / band (pilot and excitation),
// the samples outside, whether a supervisor tripped, the mean applied scale of the excitation
// after its soft start. Exit 1 when any sample was outside the band or a run could not be
// carried out, 2 on a usage error.
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "plantsim/plant/plant.hpp"
#include "rig/session/pilot.hpp"
#include "rig/session/steady_state.hpp"
#include "rig/session/supervisor.hpp"
#include "rig/signal/excitation.hpp"
#include "rig/signal/random.hpp"

namespace {

using rig::session::Supervisor;
using rig::session::SupervisorConfig;
using rig::session::SupervisorOutput;
using Clock = std::chrono::steady_clock;

constexpr double kDt = 0.01;
constexpr int kPlantTicksPerTick = 10;
constexpr double kBandwidthHz = 4.0;
constexpr double kSteadyS = 10.0, kPilotS = 20.0, kPilotStdPct = 0.3;
constexpr double kFadeOutS = 2.0, kSettleS = 2.0;
constexpr double kFactorLo = 0.3, kFactorHi = 3.0;

struct Options {
  int runs = 200;
  std::uint64_t seed = 1;
  double duration_s = 120.0;
  std::optional<std::uint64_t> plant_seed;  // replay one run
  double factor = 1.0;
};

// The plant as the rig sees it, with the wall time spent integrating it.
class RigPlant {
 public:
  explicit RigPlant(std::uint64_t seed) {
    plantsim::PlantOptions po;
    po.seed = seed;
    plant_ = plantsim::make_plant(po);
  }
  // Writes the bias, advances one session tick and reads.
  const drivers::Sample& advance(double bias_pct) {
    plant_->set_bias_pct(bias_pct);
    const auto t0 = Clock::now();
    for (int i = 0; i < kPlantTicksPerTick; ++i) plant_->step();
    step_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
    const plantsim::Measurement m = plant_->measure();
    sample_.plant_time_s = m.time_s;
    sample_.power_kw = m.power_w / 1e3;
    sample_.speed_rpm = m.speed_rpm;
    sample_.freq_hz = m.freq_hz;
    sample_.bias_echo_pct = m.bias_applied_pct;
    sample_.status = drivers::kBiasActive;
    if (m.running) sample_.status |= drivers::kRunning;
    if (m.breaker_closed) sample_.status |= drivers::kBreakerClosed;
    if (m.fault) sample_.status |= drivers::kPlantFault;
    sample_.counter = static_cast<std::uint16_t>(plant_->ticks());
    return sample_;
  }
  const drivers::Sample& last() const { return sample_; }
  double step_seconds() const { return step_s_; }

 private:
  std::unique_ptr<plantsim::Plant> plant_;
  drivers::Sample sample_;
  double step_s_ = 0.0;
};

// As RunContext::supervisor_config() with the default test file (after activation).
SupervisorConfig supervisor_config(double p0_kw, double noise_kw) {
  SupervisorConfig s;
  s.p0_kw = p0_kw;
  s.band_fraction = 0.03;
  s.clamp_pct = 5.0;
  s.ramp_rate_pct_per_s = 2.0;
  s.dt_s = kDt;
  s.backoff.zero_fraction = 0.9;
  s.backoff.plan_fraction = 0.8;
  s.backoff.peak_to_rms = rig::session::kPeakFactor;
  s.backoff.resonance_hz = 2.0;
  s.noise_rms_kw = noise_kw;
  s.plausible.speed = s.plausible.freq = true;
  s.required_status_mask |= drivers::kBiasActive;
  s.echo.enabled = true;  // defaults = the test file's: 0.02 % + 10 %, 5 ticks late, 5 bad
  return s;
}

long soft_start_ticks(const SupervisorConfig& s) {
  return static_cast<long>(std::ceil(1.0 / (s.backoff.recover_rate_per_s * s.dt_s))) + 1;
}

Eigen::VectorXd excitation(Eigen::Index n, double sigma_pct, std::uint64_t seed) {
  rig::signal::GaussianOptions g;
  g.n = n;
  g.dt_s = kDt;
  g.bandwidth_hz = kBandwidthHz;
  g.sigma = sigma_pct;
  g.clip_sigma = rig::session::kExcitationClipSigma;
  g.seed = seed;
  return rig::signal::gaussian_excitation(g);
}

struct PhaseStats {
  int outside = 0;
  double worst = 0.0;  // max |P - P0| / band
  double worst_t = 0.0;
  const char* worst_where = "-";
  long ticks = 0;
  bool tripped = false;
  std::string trip_text;
  double scale_sum = 0.0;
  long scale_n = 0;
  std::string first;  // the first reading outside, with what the supervisor was doing
};

struct BandJudge {
  double p0_kw, band_kw;
  void operator()(PhaseStats& st, double t_s, const char* where, const drivers::Sample& s,
                  const SupervisorOutput* out) const {
    const double fraction = std::abs(s.power_kw - p0_kw) / band_kw;
    if (fraction > st.worst) st.worst = fraction, st.worst_t = t_s, st.worst_where = where;
    if (fraction <= 1.0) return;  // NaN counts as outside
    if (st.outside++) return;
    st.first = fmt::format("{:.3f} of band at {:.2f} s ({}): ", fraction, t_s, where);
    st.first +=
        out ? fmt::format("bias {:.3f} %, scale {:.3f}, {}, envelope {:.1f} kW", out->bias_pct,
                          out->scale, rig::session::to_string(out->state), out->envelope_kw)
            : "at baseline";
  }
};

using Request = std::function<std::optional<double>(long k)>;
using Consume = std::function<void(long k, const SupervisorOutput&, const drivers::Sample&)>;

// One supervised phase as SupervisedPhase::run(): request(k) until it has none, then
// finish() and the ramp-down until the supervisor is done; every reading is judged.
PhaseStats supervised(RigPlant& plant, const SupervisorConfig& c, const BandJudge& judge,
                      const Request& request, const Consume& consume) {
  Supervisor sup(c);
  sup.start();
  PhaseStats st;
  bool exciting = true;
  long k = 0;
  const long limit = 1000000;  // a supervisor that never finishes is a finding, not a hang
  while (!sup.done() && k < limit) {
    double req = 0.0;
    if (exciting) {
      if (const std::optional<double> next = request(k)) {
        req = *next;
      } else {
        exciting = false;
        sup.finish();
      }
    }
    const SupervisorOutput out = sup.tick(plant.last(), req);
    const drivers::Sample& s = plant.advance(out.bias_pct);
    judge(st, static_cast<double>(k + 1) * kDt, exciting ? "excitation" : "ramp-down", s, &out);
    if (exciting && !sup.tripped()) consume(k, out, s);
    ++k;
  }
  st.ticks = k;
  st.tripped = sup.tripped();
  if (st.tripped) st.trip_text = sup.trip_record()->text;
  if (!sup.done()) st.trip_text += " (supervisor never finished)";
  return st;
}

struct RunResult {
  std::uint64_t plant_seed = 0;
  double factor = 1.0;
  double p0_kw = 0.0, noise_kw = 0.0, gain = 0.0, planned_std_pct = 0.0;
  PhaseStats pilot, excite;
  std::string refused;                                     // why the run could not be carried out
  double seconds = 0.0, plant_seconds = 0.0, sim_s = 0.0;  // wall, in the plant, plant time
  double mean_scale() const {
    return excite.scale_n ? excite.scale_sum / static_cast<double>(excite.scale_n) : 0.0;
  }
};

// Step 1: the steady-state record; false (with the reason) when the check refuses.
bool steady_state(RigPlant& plant, RunResult& r) {
  const auto n = static_cast<long>(std::ceil(kSteadyS / kDt));
  std::vector<double> t, p;
  for (long k = 0; k < n; ++k) {
    t.push_back(static_cast<double>(k) * kDt);
    p.push_back(plant.advance(0.0).power_kw);
  }
  const rig::session::SteadyStateResult s = rig::session::check_steady_state(t, p, {});
  if (!s.ok) {
    r.refused = "steady state: " + s.reason;
    return false;
  }
  r.p0_kw = s.p0_kw;
  r.noise_kw = s.noise_pct / 100.0 * s.p0_kw;
  return true;
}

double fade_out(long j, long n) {
  return j >= n ? 0.0
                : 0.5 * (1.0 + std::cos(M_PI * static_cast<double>(j) / static_cast<double>(n)));
}

// Steps 2 and 3: the pilot and the plan from its gain taken f times.
bool pilot_and_plan(RigPlant& plant, const BandJudge& judge, std::uint64_t exc_seed, RunResult& r) {
  const SupervisorConfig c = supervisor_config(r.p0_kw, r.noise_kw);
  const long soft = soft_start_ticks(c);
  const long n = soft + std::lround(kPilotS / kDt), fade = std::lround(kFadeOutS / kDt);
  const Eigen::VectorXd e = excitation(n + fade, kPilotStdPct, exc_seed + 7919);
  std::vector<double> u, y;
  r.pilot = supervised(
      plant, c, judge,
      [&](long k) -> std::optional<double> {  // faded out, as the session's pilot is
        if (k >= n + fade) return std::nullopt;
        return e(k) * (k < n ? 1.0 : fade_out(k - n, fade));
      },
      [&](long k, const SupervisorOutput& out, const drivers::Sample& s) {
        if (k < soft || k >= n) return;
        u.push_back(out.excitation_pct / r.factor);  // the wrong assumption
        y.push_back(s.power_kw - r.p0_kw);
      });
  if (r.pilot.tripped) {
    r.refused = "pilot tripped: " + r.pilot.trip_text;
    return false;
  }
  rig::session::PilotPlanLimits limits;
  limits.band_kw = judge.band_kw;
  limits.plan_fraction = c.backoff.plan_fraction;
  limits.clamp_pct = c.clamp_pct;
  limits.noise_std_kw = r.noise_kw;
  const rig::session::PilotResult pr = rig::session::analyse_pilot(u, y, limits);
  if (!pr.ok) {
    r.refused = pr.reason;
    return false;
  }
  r.gain = pr.gain_kw_per_pct;
  r.planned_std_pct = pr.planned_std_pct;
  return true;
}

// Step 4: the supervised excitation, its ramp-down and the settling after it.
void excite(RigPlant& plant, const BandJudge& judge, std::uint64_t exc_seed, double duration_s,
            RunResult& r) {
  const SupervisorConfig c = supervisor_config(r.p0_kw, r.noise_kw);
  const long soft = soft_start_ticks(c);
  const long n = std::lround(duration_s / kDt), fade = std::lround(kFadeOutS / kDt);
  const Eigen::VectorXd e = excitation(n + fade, r.planned_std_pct, exc_seed);
  double scale_sum = 0.0;
  long scale_n = 0;
  r.excite = supervised(
      plant, c, judge,
      [&](long k) -> std::optional<double> {
        if (k >= n + fade) return std::nullopt;
        return e(k) * (k < n ? 1.0 : fade_out(k - n, fade));
      },
      [&](long k, const SupervisorOutput& out, const drivers::Sample&) {
        if (k < soft || k >= n) return;
        scale_sum += out.scale;
        ++scale_n;
      });
  r.excite.scale_sum = scale_sum;
  r.excite.scale_n = scale_n;
  const long settle = std::lround(kSettleS / kDt);
  for (long k = 0; k < settle; ++k) {
    judge(r.excite, static_cast<double>(r.excite.ticks + k + 1) * kDt, "settling",
          plant.advance(c.baseline_bias_pct), nullptr);
  }
}

RunResult run(std::uint64_t plant_seed, double factor, double duration_s) {
  const auto t0 = Clock::now();
  RunResult r;
  r.plant_seed = plant_seed;
  r.factor = factor;
  RigPlant plant(plant_seed);
  const std::uint64_t exc_seed = plant_seed ^ 0x5deece66dULL;
  if (steady_state(plant, r)) {
    const BandJudge judge{r.p0_kw, 0.03 * r.p0_kw};
    if (pilot_and_plan(plant, judge, exc_seed, r)) excite(plant, judge, exc_seed, duration_s, r);
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  r.plant_seconds = plant.step_seconds();
  r.sim_s = plant.last().plant_time_s;
  return r;
}

void print_header() {
  fmt::print(
      "columns: run, plant seed, f, P0 kW, noise std kW (steady state), pilot gain x f kW/%, "
      "planned std %, worst |P-P0|/band in the pilot, in the excitation + ramp-down + settling "
      "and where (s from the start of the excitation), samples outside the band (all phases), "
      "mean scale after the soft start, plant s simulated, wall s, tripped\n");
  fmt::print(
      " run plant_seed factor   P0_kW noise  gainf plan_sd pilotW  worst worst_at        outside "
      "mscale sim_s secs tripped\n");
}

void print_run(int i, const RunResult& r) {
  const std::string trip =
      r.excite.tripped ? "yes (" + r.excite.trip_text + ")" : (r.pilot.tripped ? "pilot" : "no");
  const std::string at = fmt::format("{} {:.1f}", r.excite.worst_where, r.excite.worst_t);
  fmt::print(
      "{:4d} {:10d} {:6.3f} {:7.1f} {:5.2f} {:6.1f} {:7.4f} {:6.3f} {:6.3f} {:<16} {:6d} {:6.3f} "
      "{:5.0f} {:4.1f} {}\n",
      i, r.plant_seed, r.factor, r.p0_kw, r.noise_kw, r.gain, r.planned_std_pct, r.pilot.worst,
      r.excite.worst, at, r.excite.outside + r.pilot.outside, r.mean_scale(), r.sim_s, r.seconds,
      trip);
  if (!r.refused.empty()) fmt::print("     NOT CARRIED OUT: {}\n", r.refused);
  if (r.pilot.outside)
    fmt::print("     OUTSIDE in the pilot: {} samples, first {}\n", r.pilot.outside, r.pilot.first);
  if (r.excite.outside)
    fmt::print("     OUTSIDE in the excitation phase: {} samples, first {}\n", r.excite.outside,
               r.excite.first);
  std::fflush(stdout);
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help" || i + 1 >= argc) return false;
    const char* v = argv[++i];
    if (a == "--runs") {
      o.runs = std::atoi(v);
    } else if (a == "--seed") {
      o.seed = std::strtoull(v, nullptr, 10);
    } else if (a == "--duration-s") {
      o.duration_s = std::atof(v);
    } else if (a == "--plant-seed") {
      o.plant_seed = std::strtoull(v, nullptr, 10);
    } else if (a == "--factor") {
      o.factor = std::atof(v);
    } else {
      return false;
    }
  }
  return o.runs > 0 && o.duration_s >= 1.0 && o.factor > 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    fmt::print(stderr,
               "usage: bench_safety_sweep [--runs 200] [--seed 1] [--duration-s 120]\n"
               "       bench_safety_sweep --plant-seed N --factor F [--duration-s 120]\n");
    return 2;
  }
  rig::signal::Xoshiro256 rng(o.seed);
  const int runs = o.plant_seed ? 1 : o.runs;
  fmt::print(
      "safety sweep on plantsim (stornoway): master seed {}, {} runs, excitation {:g} s, pilot "
      "gain taken x f, f log-uniform in [{:g}, {:g}]\n",
      o.seed, runs, o.duration_s, kFactorLo, kFactorHi);
  print_header();
  const auto t0 = Clock::now();
  int outside = 0, tripped = 0, refused = 0;
  double worst = 0.0, plant_s = 0.0, slowest = 0.0;
  for (int i = 0; i < runs; ++i) {
    const double f =
        o.plant_seed
            ? o.factor
            : std::exp(std::log(kFactorLo) + rng.uniform() * std::log(kFactorHi / kFactorLo));
    const std::uint64_t seed = o.plant_seed ? *o.plant_seed : (rng.next() >> 33) + 1;
    const RunResult r = run(seed, f, o.duration_s);
    print_run(i, r);
    outside += r.excite.outside + r.pilot.outside;
    tripped += r.excite.tripped || r.pilot.tripped;
    refused += !r.refused.empty();
    worst = std::max({worst, r.excite.worst, r.pilot.worst});
    plant_s += r.plant_seconds;
    slowest = std::max(slowest, r.seconds);
  }
  const double total_s = std::chrono::duration<double>(Clock::now() - t0).count();
  fmt::print(
      "summary: {} runs (master seed {}, {:g} s excitation), {} samples outside the band, {} "
      "runs tripped, {} not carried out, worst |P-P0| {:.3f} of the band\n",
      runs, o.seed, o.duration_s, outside, tripped, refused, worst);
  fmt::print(
      "time: {:.1f} s ({:.2f} s per run, slowest {:.2f} s); plant integration {:.1f} s ({:.0f} "
      "%), supervisor, excitation and planning the rest\n",
      total_s, total_s / runs, slowest, plant_s, 100.0 * plant_s / std::max(total_s, 1e-9));
  return outside > 0 || refused > 0 ? 1 : 0;
}
