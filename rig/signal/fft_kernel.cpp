// FFT form of a correlator run (lag_kernels.hpp).
//
// With the anchor values placed on a zero sequence am[i*s] = a[i*s] (skipped samples are
// zero, which is exactly "form only every s-th product") and the window segment
// ws[0 .. (count-1)s + L) = w[...], the wanted sums are the linear correlation
//     c[j] = sum_n am[n] ws[n + j],   j = 0..L-1,
// and c = IFFT( conj(FFT(am)) * FFT(ws) ) / M is free of wrap-around for any FFT length
// M >= (count-1)s + L because n + j never exceeds that segment.
#include <fftw3.h>

#include <algorithm>
#include <complex>
#include <memory>
#include <mutex>
#include <vector>

#include "rig/signal/fftw_planner.hpp"
#include "rig/signal/lag_kernels.hpp"

namespace rig::signal::detail {
namespace {

struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};
template <typename T>
using FftwBuffer = std::unique_ptr<T[], FftwFree>;

template <typename T>
FftwBuffer<T> fftw_buffer(Eigen::Index n) {
  return FftwBuffer<T>(static_cast<T*>(fftw_malloc(sizeof(T) * static_cast<size_t>(n))));
}

// Smallest 2^a 3^b 5^c >= n: sizes FFTW handles fastest.
Eigen::Index fast_size(Eigen::Index n) {
  Eigen::Index best = 1;
  while (best < n) best *= 2;
  for (Eigen::Index p5 = 1; p5 < best; p5 *= 5) {
    for (Eigen::Index p35 = p5; p35 < best; p35 *= 3) {
      Eigen::Index m = p35;
      while (m < n) m *= 2;
      best = std::min(best, m);
    }
  }
  return best;
}

class RealFft {
 public:
  explicit RealFft(Eigen::Index m)
      : m_(m), x_(fftw_buffer<double>(m)), f_(fftw_buffer<fftw_complex>(m / 2 + 1)) {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    const int n = static_cast<int>(m);
    forward_ = fftw_plan_dft_r2c_1d(n, x_.get(), f_.get(), FFTW_ESTIMATE);
    inverse_ = fftw_plan_dft_c2r_1d(n, f_.get(), x_.get(), FFTW_ESTIMATE);
  }
  ~RealFft() {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    fftw_destroy_plan(forward_);
    fftw_destroy_plan(inverse_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  double* x() { return x_.get(); }
  std::complex<double>* f() { return reinterpret_cast<std::complex<double>*>(f_.get()); }
  void forward() { fftw_execute(forward_); }
  void inverse() { fftw_execute(inverse_); }  // unnormalised: result is M times the IDFT

 private:
  Eigen::Index m_;
  FftwBuffer<double> x_;
  FftwBuffer<fftw_complex> f_;
  fftw_plan forward_ = nullptr, inverse_ = nullptr;
};

}  // namespace
}  // namespace rig::signal::detail

namespace rig::signal {

std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace rig::signal

namespace rig::signal::detail {

void fft_run(const double* a, const double* w, AnchorRun run, double* acc) {
  if (run.count <= 0) return;
  const Eigen::Index span = (run.count - 1) * run.stride + run.lags;
  const Eigen::Index m = fast_size(span);
  RealFft fft(m);
  const Eigen::Index bins = m / 2 + 1;

  std::fill(fft.x(), fft.x() + m, 0.0);
  for (Eigen::Index i = 0; i < run.count; ++i) fft.x()[i * run.stride] = a[i * run.stride];
  fft.forward();
  std::vector<std::complex<double>> am(fft.f(), fft.f() + bins);

  std::fill(fft.x(), fft.x() + m, 0.0);
  std::copy(w, w + span, fft.x());
  fft.forward();
  for (Eigen::Index b = 0; b < bins; ++b) fft.f()[b] *= std::conj(am[static_cast<size_t>(b)]);
  fft.inverse();

  const double scale = 1.0 / static_cast<double>(m);
  for (Eigen::Index j = 0; j < run.lags; ++j) acc[j] += fft.x()[j] * scale;
}

}  // namespace rig::signal::detail
