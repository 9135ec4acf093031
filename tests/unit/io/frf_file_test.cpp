#include <gtest/gtest.h>

#include "rig/io/frf_file.hpp"
#include "rig/io/input_error.hpp"
#include "test_files.hpp"

namespace rig::io {
namespace {

Frf sample_frf(bool bands) {
  Frf f;
  f.freq_hz = (Eigen::VectorXd(3) << 0.5, 1.0, 2.0).finished();
  f.mag = (Eigen::VectorXd(3) << 0.09, 0.1, 0.5).finished();
  f.phase_deg = (Eigen::VectorXd(3) << -5.0, -12.5, -90.0).finished();
  f.coherence = (Eigen::VectorXd(3) << 0.8, 0.95, 0.99).finished();
  if (bands) {
    f.mag_lo = f.mag * 0.9;
    f.mag_hi = f.mag * 1.1;
  }
  return f;
}

TEST(FrfFile, RoundTripWithAndWithoutBands) {
  const auto dir = testing::scratch_dir();
  for (bool bands : {false, true}) {
    write_frf(dir / "h1.csv", sample_frf(bands));
    const Frf r = read_frf(dir / "h1.csv");
    ASSERT_EQ(r.size(), 3);
    EXPECT_TRUE(r.freq_hz.isApprox(sample_frf(bands).freq_hz));
    EXPECT_DOUBLE_EQ(r.phase_deg[2], -90.0);
    EXPECT_EQ(r.mag_lo.has_value(), bands);
    if (bands) {
      EXPECT_DOUBLE_EQ((*r.mag_hi)[1], 0.11);
    }
  }
}

TEST(FrfFile, RejectsDecreasingFrequencyWithLineAndColumn) {
  const auto dir = testing::scratch_dir();
  testing::write_text(dir / "bad.csv",
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
  const auto dir = testing::scratch_dir();
  testing::write_text(dir / "c.csv", "freq_hz,mag,phase_deg,coherence\n1,1,0,1.5\n");
  EXPECT_THROW(read_frf(dir / "c.csv"), InputError);
  testing::write_text(dir / "m.csv", "freq_hz,mag,coherence\n1,1,0.5\n");
  try {
    read_frf(dir / "m.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.column(), "phase_deg");
  }
}

}  // namespace
}  // namespace rig::io
