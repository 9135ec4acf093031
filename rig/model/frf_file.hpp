// Frequency-response CSV (DESIGN.md section 5), lossless for rig::model::FrfPoint:
//   freq_hz,mag,phase_deg,coherence[,mag_lo,mag_hi][,valid]
// mag is |H| (linear, not dB), phase in degrees, coherence in [0, 1]; mag_lo/mag_hi bound |H|
// (about one standard deviation) when known; valid is 1 for a point its estimator judged
// usable and 0 for one it did not (distortion, noise, back-off), so every reader judges the
// same points. Frequencies strictly increasing and > 0.
//
// Writing: mag_lo,mag_hi when any point has them ("nan" where one has not); valid always;
// every number in its shortest exact form, so reading gives back the same doubles. A point
// marked invalid may carry non-finite values ("nan", "inf"); a valid one may not.
// Reading: a header row naming the columns (any order; other columns are ignored; a file
// without `valid` has every point valid, one without mag_lo/mag_hi has no bands), comma
// separated; blank lines and lines starting with '#' are skipped.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "rig/model/frf.hpp"

namespace rig::model {

// The CSV text of `frf`; std::invalid_argument when it breaks the rules above.
std::string frf_to_csv(const Frf& frf);
// InputError (source, line, column, what was expected) on any defect.
Frf frf_from_csv(std::string_view text, const std::string& source);

// InputError naming the file on any defect (see InputFile for what is refused).
Frf read_frf(const std::filesystem::path& path);
// frf_to_csv, written atomically (InputError when the folder is not writable).
void write_frf(const std::filesystem::path& path, const Frf& frf);

}  // namespace rig::model
