// Decisions with a designed false-alarm rate (issue "condition monitoring", item 4).
//
// Each monitored statistic x (one value per block) is learnt on the baseline's own spread:
// mean m and standard deviation s from the learning blocks, s inflated for the blocks'
// correlation (AR(1): sqrt((1 + rho) / (1 - rho)), the variance factor of a mean of
// correlated values) and for the learning's own uncertainty (the 95 % upper bound of a
// standard deviation from n values: sqrt((n - 1) / chi2_{0.05, n-1})). The standardised value
// z = (x - m) / s drives a two-sided CUSUM (Page):
//     g+ = max(0, g+ + z - k),  g- = max(0, g- - z - k),  alarm when g+ or g- > h.
// Its in-control average run length (Siegmund's approximation, N(0,1) steps):
//     ARL0(k, h) = (exp(2 k b) - 2 k b - 1) / (2 k^2),  b = h + 1.166,
// and for a shift of d standard deviations (D = d - k):
//     ARL1 = (exp(-2 D b) + 2 D b - 1) / (2 D^2).
// h is chosen so that `tests` two-sided CUSUMs, one value per block each, give at most the
// designed false alarms per month together: 2 tests / ARL0 <= rate * block_s / month_s.
#pragma once

#include <vector>

namespace rig::monitor {

inline constexpr double kMonthS = 30.0 * 86400.0;

struct Spread {
  double mean = 0.0;
  double sigma = 0.0;  // inflated (see above)
  double raw_sigma = 0.0;
  double rho = 0.0;  // lag-1 autocorrelation of the learning values (clamped to [0, 0.9])
  int n = 0;
};

// Mean and inflated spread of the learning values (n >= 3, else sigma = +inf).
Spread learn_spread(const std::vector<double>& values);

struct CusumDesign {
  double k = 0.75;           // reference value (half the shift of fastest detection), sigma
  double h = 10.0;           // decision threshold, sigma
  double arl0_blocks = 0.0;  // in-control run length of one two-sided CUSUM, blocks
  double false_alarms_per_month = 0.0;  // of all tests together, as designed
};

double cusum_arl0(double k, double h);            // one-sided, blocks
double cusum_arl1(double k, double h, double d);  // one-sided, shift d sigma, blocks
// Smallest h (to 0.01) meeting the rate for `tests` two-sided CUSUMs on blocks of block_s.
CusumDesign design_cusum(double false_alarms_per_month, double block_s, int tests, double k);

class Cusum {
 public:
  explicit Cusum(const CusumDesign& d = {}) : d_(d) {}
  // Returns +1 or -1 when the upper or lower sum crosses h (then both restart), 0 otherwise.
  int update(double z);
  void reset() {
    up_ = down_ = 0.0;
    run_ = 0;
  }
  // The reference value used from now on (>= the design's k; see monitor.cpp).
  void set_reference(double k) { d_.k = k; }
  double upper() const { return up_; }
  double lower() const { return down_; }
  double level() const { return up_ > down_ ? up_ : down_; }  // in sigma, against h
  // Blocks since the sum that crossed last left zero (the change's onset estimate).
  int run_length() const { return run_; }
  const CusumDesign& design() const { return d_; }

 private:
  CusumDesign d_;
  double up_ = 0.0, down_ = 0.0;
  int run_ = 0, up_run_ = 0, down_run_ = 0;
};

}  // namespace rig::monitor
