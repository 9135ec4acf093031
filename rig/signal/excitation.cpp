#include "rig/signal/excitation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "rig/signal/butterworth.hpp"
#include "rig/signal/random.hpp"

namespace rig::signal {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("excitation: " + what);
}

// Population standard deviation (1/n) about the sample mean.
double std_dev(const Eigen::VectorXd& x) {
  return std::sqrt((x.array() - x.mean()).square().mean());
}

Eigen::VectorXd clipped(const Eigen::VectorXd& x, double gain, double limit) {
  return (gain * x.array()).max(-limit).min(limit).matrix();
}

// x has unit standard deviation. Returns clip(g x, +-k) with g >= 1 solved by bisection so
// that the clipped record again has unit standard deviation (std grows monotonically in g).
Eigen::VectorXd clip_keeping_sigma(const Eigen::VectorXd& x, double k) {
  double lo = 1.0, hi = 2.0;
  while (std_dev(clipped(x, hi, k)) < 1.0) {
    hi *= 2.0;
    if (hi > 1e6) fail("clip_sigma " + std::to_string(k) + " too small to keep sigma");
  }
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (std_dev(clipped(x, mid, k)) < 1.0 ? lo : hi) = mid;
  }
  return clipped(x, hi, k);
}

void check_common(Eigen::Index n, double dt_s) {
  if (n < 1) fail("n must be >= 1 samples, got " + std::to_string(n));
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) fail("dt_s must be > 0, got " + std::to_string(dt_s));
}

}  // namespace

Eigen::VectorXd gaussian_excitation(const GaussianOptions& o) {
  check_common(o.n, o.dt_s);
  if (o.n < 2) fail("gaussian needs n >= 2 samples to set a standard deviation");
  const double fc = o.bandwidth_hz > 0.0 ? o.bandwidth_hz : 2.0 * o.resonance_hz;
  if (!(fc > 0.0) || !(fc < 0.5 / o.dt_s)) {
    fail("bandwidth (bandwidth_hz, or 2 * resonance_hz) must be in (0, " +
         std::to_string(0.5 / o.dt_s) + ") Hz, got " + std::to_string(fc));
  }
  if (!(o.sigma > 0.0)) fail("sigma must be > 0, got " + std::to_string(o.sigma));
  if (o.clip_sigma != 0.0 && !(o.clip_sigma > 1.0)) {
    fail("clip_sigma must be 0 (off) or > 1, got " + std::to_string(o.clip_sigma));
  }
  ButterworthLowPass filter(o.filter_order, fc, o.dt_s);
  const Eigen::Index warmup =
      o.warmup >= 0 ? o.warmup : static_cast<Eigen::Index>(std::ceil(20.0 / (fc * o.dt_s)));
  Xoshiro256 rng(o.seed);
  for (Eigen::Index i = 0; i < warmup; ++i) filter.step(rng.normal());
  Eigen::VectorXd x(o.n);
  for (Eigen::Index i = 0; i < o.n; ++i) x[i] = filter.step(rng.normal());

  x.array() -= x.mean();
  const double s = std_dev(x);
  if (!(s > 0.0)) fail("gaussian record has zero variance (n too small?)");
  x /= s;
  if (o.clip_sigma > 0.0) {
    x = clip_keeping_sigma(x, o.clip_sigma);
    x /= std_dev(x);  // remove the last bisection rounding
  }
  return o.sigma * x;
}

std::vector<int> prbs_taps(int register_length) {
  // Xilinx XAPP052 (Alfke 1996), table 3: taps for maximal-length LFSRs.
  static const std::vector<std::vector<int>> kTaps = {
      {2, 1},        {3, 2},        {4, 3},          {5, 3},   {6, 5},           {7, 6},
      {8, 6, 5, 4},  {9, 5},        {10, 7},         {11, 9},  {12, 6, 4, 1},    {13, 4, 3, 1},
      {14, 5, 3, 1}, {15, 14},      {16, 15, 13, 4}, {17, 14}, {18, 11},         {19, 6, 2, 1},
      {20, 17},      {21, 19},      {22, 21},        {23, 18}, {24, 23, 22, 17}, {25, 22},
      {26, 6, 2, 1}, {27, 5, 2, 1}, {28, 25},        {29, 27}, {30, 6, 4, 1},    {31, 28}};
  if (register_length < 2 || register_length > 31) {
    fail("PRBS register_length must be 2..31, got " + std::to_string(register_length));
  }
  return kTaps[static_cast<size_t>(register_length - 2)];
}

Eigen::VectorXd prbs_excitation(const PrbsOptions& o) {
  check_common(o.n, 1.0);
  const std::vector<int> taps = prbs_taps(o.register_length);
  if (o.clock_divider < 1)
    fail("PRBS clock_divider must be >= 1, got " + std::to_string(o.clock_divider));
  if (!(o.amplitude > 0.0)) fail("PRBS amplitude must be > 0, got " + std::to_string(o.amplitude));
  const std::uint32_t period = (std::uint32_t{1} << o.register_length) - 1U;
  std::uint32_t mask = 0;
  for (int t : taps) mask |= std::uint32_t{1} << (t - 1);
  // Fibonacci LFSR: feedback = parity(state & taps), shifted in at bit 0; never all-zero.
  auto state = static_cast<std::uint32_t>(1U + o.seed % period);
  Eigen::VectorXd x(o.n);
  std::uint32_t bit = 0;
  for (Eigen::Index i = 0; i < o.n; ++i) {
    if (i % o.clock_divider == 0) {
      bit = static_cast<std::uint32_t>(__builtin_parity(state & mask));
      state = ((state << 1) | bit) & period;
    }
    x[i] = bit ? o.amplitude : -o.amplitude;
  }
  return x;
}

std::vector<double> harmonic_frequencies_hz(Eigen::Index n, double dt_s, int first, int last) {
  check_common(n, dt_s);
  if (first < 1 || last < first || static_cast<double>(last) >= 0.5 * static_cast<double>(n)) {
    fail("harmonics must satisfy 1 <= first <= last < n/2, got " + std::to_string(first) + ".." +
         std::to_string(last));
  }
  const double f0 = 1.0 / (static_cast<double>(n) * dt_s);
  std::vector<double> f;
  for (int k = first; k <= last; ++k) f.push_back(k * f0);
  return f;
}

Eigen::VectorXd multisine_excitation(const MultisineOptions& o) {
  check_common(o.n, o.dt_s);
  const size_t count = o.frequencies_hz.size();
  if (count == 0) fail("multisine needs at least one frequency");
  if (!o.amplitudes.empty() && o.amplitudes.size() != count) {
    fail("multisine amplitudes (" + std::to_string(o.amplitudes.size()) +
         ") must match frequencies_hz (" + std::to_string(count) + ") or be empty");
  }
  for (double f : o.frequencies_hz) {
    if (!(f > 0.0) || !(f < 0.5 / o.dt_s)) {
      fail("multisine frequency " + std::to_string(f) + " Hz outside (0, Nyquist)");
    }
  }
  std::vector<double> amp = o.amplitudes.empty() ? std::vector<double>(count, 1.0) : o.amplitudes;
  double power = 0.0;
  for (double a : amp) power += a * a;
  if (!(power > 0.0)) fail("multisine amplitudes are all zero");

  std::vector<double> phase(count, 0.0);
  Xoshiro256 rng(o.seed);
  for (size_t k = 0; k < count; ++k) {
    if (o.phases == MultisinePhases::kRandom) {
      phase[k] = 2.0 * std::numbers::pi * rng.uniform();
    } else {  // Schroeder (1970): phi_k = -2 pi sum_{l<k} (k - l) p_l, 0-based k.
      double sum = 0.0;
      for (size_t l = 0; l < k; ++l) sum += static_cast<double>(k - l) * amp[l] * amp[l] / power;
      phase[k] = -2.0 * std::numbers::pi * sum;
    }
  }
  Eigen::VectorXd x = Eigen::VectorXd::Zero(o.n);
  const Eigen::ArrayXd t =
      Eigen::ArrayXd::LinSpaced(o.n, 0.0, static_cast<double>(o.n - 1)) * o.dt_s;
  for (size_t k = 0; k < count; ++k) {
    x.array() += amp[k] * (2.0 * std::numbers::pi * o.frequencies_hz[k] * t + phase[k]).cos();
  }
  if (o.rms > 0.0) x *= o.rms / std::sqrt(x.squaredNorm() / static_cast<double>(o.n));
  return x;
}

double crest_factor(const Eigen::VectorXd& x) {
  const double rms =
      x.size() > 0 ? std::sqrt(x.squaredNorm() / static_cast<double>(x.size())) : 0.0;
  if (!(rms > 0.0)) throw std::invalid_argument("crest_factor: record is empty or all zero");
  return x.cwiseAbs().maxCoeff() / rms;
}

}  // namespace rig::signal
