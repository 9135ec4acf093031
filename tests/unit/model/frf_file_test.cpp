#include "rig/model/frf_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../io/test_files.hpp"
#include "rig/model/input_error.hpp"

namespace rig::model {
namespace {

Frf sample_frf(bool bands) {
  Frf f(3);
  const double freq[] = {0.5, 1.0, 2.0}, mag[] = {0.09, 0.1, 0.5};
  const double phase[] = {-5.0, -12.5, -90.0}, coherence[] = {0.8, 0.95, 0.99};
  for (std::size_t i = 0; i < f.size(); ++i) {
    f[i].freq_hz = freq[i];
    f[i].mag = mag[i];
    f[i].phase_deg = phase[i];
    f[i].coherence = coherence[i];
    if (bands) {
      f[i].mag_lo = mag[i] * 0.9;
      f[i].mag_hi = mag[i] * 1.1;
    }
  }
  return f;
}

void expect_same(const FrfPoint& a, const FrfPoint& b) {
  EXPECT_EQ(a.freq_hz, b.freq_hz);
  EXPECT_EQ(a.mag, b.mag);
  EXPECT_EQ(a.phase_deg, b.phase_deg);
  EXPECT_EQ(a.coherence, b.coherence);
  EXPECT_EQ(a.has_band(), b.has_band());
  if (a.has_band() && b.has_band()) {
    EXPECT_EQ(a.mag_lo, b.mag_lo);
    EXPECT_EQ(a.mag_hi, b.mag_hi);
  }
  EXPECT_EQ(a.valid, b.valid);
}

TEST(FrfFile, RoundTripWithAndWithoutBands) {
  const auto dir = io::testing::scratch_dir();
  for (bool bands : {false, true}) {
    write_frf(dir / "h1.csv", sample_frf(bands));
    const Frf r = read_frf(dir / "h1.csv");
    ASSERT_EQ(r.size(), 3u);
    for (std::size_t i = 0; i < r.size(); ++i) expect_same(r[i], sample_frf(bands)[i]);
    EXPECT_EQ(r[1].has_band(), bands);
  }
}

// The session judged 7 sweep points where `rig compare` on its sweep.csv judged 12: the file
// lost the estimator's verdict and the bands. Every field must come back exactly.
TEST(FrfFile, RoundTripKeepsInvalidPointsBandsAndExactValues) {
  const auto dir = io::testing::scratch_dir();
  Frf f = sample_frf(true);
  f[0].valid = false;
  f[1].coherence = 0.79999999999999993;  // just below a 0.8 threshold: must stay below
  f[1].phase_deg = -12.345678901234567;
  f[2].mag_lo = std::numeric_limits<double>::quiet_NaN();  // a band unknown for one point
  f[2].mag_hi = std::numeric_limits<double>::quiet_NaN();
  write_frf(dir / "sweep.csv", f);
  const Frf r = read_frf(dir / "sweep.csv");
  ASSERT_EQ(r.size(), f.size());
  for (std::size_t i = 0; i < r.size(); ++i) expect_same(r[i], f[i]);
  EXPECT_FALSE(r[0].valid);
  EXPECT_TRUE(r[1].valid);
  EXPECT_LT(r[1].coherence, 0.8);
}

TEST(FrfFile, InvalidPointMayHoldNonFiniteValues) {
  Frf f = sample_frf(false);
  f[1].valid = false;
  f[1].mag = std::numeric_limits<double>::infinity();
  f[1].phase_deg = std::numeric_limits<double>::quiet_NaN();
  const Frf r = frf_from_csv(frf_to_csv(f), "mem");
  EXPECT_FALSE(r[1].valid);
  EXPECT_TRUE(std::isinf(r[1].mag));
  EXPECT_TRUE(std::isnan(r[1].phase_deg));
  f[1].valid = true;  // the same values on a point marked valid break the rules
  EXPECT_THROW(frf_to_csv(f), std::invalid_argument);
}

TEST(FrfFile, ReadsFilesWithoutTheValidColumnAsAllValid) {
  const Frf r = frf_from_csv("freq_hz,mag,phase_deg,coherence\n1,2,-30,0.9\n2,1,-60,0.5\n", "a");
  ASSERT_EQ(r.size(), 2u);
  EXPECT_TRUE(r[0].valid && r[1].valid);
  EXPECT_FALSE(r[0].has_band());
  // Columns in any order, extra columns ignored, comments and blank lines skipped.
  const Frf s = frf_from_csv(
      "# from a script\nvalid,coherence,note,phase_deg,mag,freq_hz\n\n0,0.9,7,-30,2,1\n", "b");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_FALSE(s[0].valid);
  EXPECT_EQ(s[0].mag, 2.0);
}

TEST(FrfFile, RejectsABadValidCell) {
  try {
    frf_from_csv("freq_hz,mag,phase_deg,coherence,valid\n1,1,0,0.9,yes\n", "v.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.column(), "valid");
  }
}

TEST(FrfFile, RejectsDecreasingFrequencyWithLineAndColumn) {
  const auto dir = io::testing::scratch_dir();
  io::testing::write_text(dir / "bad.csv",
                          "freq_hz,mag,phase_deg,coherence\n1,1,0,0.9\n0.5,1,0,0.9\n");
  try {
    read_frf(dir / "bad.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.column(), "freq_hz");
  }
}

TEST(FrfFile, RejectsCoherenceAboveOneAndMissingColumn) {
  const auto dir = io::testing::scratch_dir();
  io::testing::write_text(dir / "c.csv", "freq_hz,mag,phase_deg,coherence\n1,1,0,1.5\n");
  EXPECT_THROW(read_frf(dir / "c.csv"), InputError);
  io::testing::write_text(dir / "m.csv", "freq_hz,mag,coherence\n1,1,0.5\n");
  try {
    read_frf(dir / "m.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.column(), "phase_deg");
  }
}

TEST(FrfFile, AddDelayRotatesThePhaseOnly) {
  Frf f = sample_frf(true);
  add_delay(f, 0.01);  // 2 Hz: -7.2 deg
  EXPECT_NEAR(f[2].phase_deg, -97.2, 1e-12);
  EXPECT_EQ(f[2].mag, 0.5);
}

}  // namespace
}  // namespace rig::model
