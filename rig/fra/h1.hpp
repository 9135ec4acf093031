// Noise-driven frequency response: the H1 estimator with Welch averaging.
//
// The record is cut into segments of L samples overlapping by `overlap` (default 50 %), each
// segment has its mean removed and is Hann-windowed, then transformed (FFTW3, real to complex).
// With U_i, Y_i the segment spectra and M segments:
//   G_uu = sum |U_i|^2,  G_yy = sum |Y_i|^2,  G_yu = sum conj(U_i) Y_i   (common scale cancels)
//   H1 = G_yu / G_uu       (unbiased by output noise uncorrelated with u)
//   gamma^2 = |G_yu|^2 / (G_uu G_yy)   (magnitude-squared coherence, 1 = fully explained)
// Random error of |H1| (Bendat & Piersol): eps = sqrt(1 - gamma^2) / (|gamma| sqrt(2 M)),
// reported as mag_lo/mag_hi = |H1| (1 -+ eps). M counts overlapped segments, so eps is
// slightly optimistic (the Hann/50 % overlap segments are not fully independent).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <vector>

#include "rig/fra/frf.hpp"

namespace rig::fra {

struct WelchOptions {
  Eigen::Index segment_length = 1024;  // L, samples per segment (resolution 1 / (L dt))
  double overlap = 0.5;                // fraction of L shared by neighbouring segments
  double f_min_hz = 0.0;               // output only bins in [f_min_hz, f_max_hz], DC excluded
  double f_max_hz = std::numeric_limits<double>::infinity();
};

struct CrossSpectra {
  Eigen::VectorXd freq_hz;
  Eigen::VectorXd guu, gyy;  // averaged auto spectra (one-sided, arbitrary common scale)
  Eigen::VectorXcd gyu;      // averaged cross spectrum conj(U) Y
  int segments = 0;
};

// Throws std::invalid_argument when u and y differ in length, the record is shorter than one
// segment, segment_length < 8 or overlap is outside [0, 0.9].
CrossSpectra welch_cross_spectra(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                                 const WelchOptions& options = {});

// H1 and coherence per bin (bins where G_uu is zero are skipped).
std::vector<model::FrfPoint> h1_estimate(const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                         double dt_s, const WelchOptions& options = {});

}  // namespace rig::fra
