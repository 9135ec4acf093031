// The records `rig identify` reads: the recording (--recording), more estimation records
// (--estimation) and a validation record (--validation). Every one is cut to its rows
// (identify_rows.hpp), checked for data quality, and timed: a sidecar that says when y was
// sampled (y_sampled_after_s) lets the identified dead time refer to the plant.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "rig/cli/identify_rows.hpp"
#include "rig/ident/identify.hpp"
#include "rig/ident/quality.hpp"
#include "rig/io/recording.hpp"
#include "rig/signal/correlators.hpp"

namespace rig::cli {

// How to read a record: the columns (by name, or by 1-based index as "I,J"), the time base
// and the rows.
struct ColumnChoice {
  std::string input, output, columns;
  std::optional<double> dt_s;
  std::string rows = "auto";
};

struct IdentifyRecord {
  std::string role;   // "estimation" or "validation"
  io::Recording rec;  // the selected rows only
  RowSelection rows;
  std::string input, output;  // the column names used
  ident::QualityReport quality;
  const Eigen::VectorXd& u() const { return rec.column(input); }
  const Eigen::VectorXd& y() const { return rec.column(output); }
  // Add to a dead time identified on these rows to refer it to the plant: the hold of each
  // u for a sample (-dt/2) and the read lag (+y_sampled_after_s). Empty without the sidecar
  // key: the dead time then refers to the rows.
  std::optional<double> timing_correction_s() const;
};

// Reads one record; the first one resolves the columns (--input/--output, --columns, u/y,
// or the only two data columns) and the later ones use its names. InputError (exit 2) for a
// missing file, column, too few rows or a constant input.
IdentifyRecord load_identify_record(const std::string& path, const ColumnChoice& columns,
                                    const std::string& role);

// The correlator of the first record (--lags 0: min(256, samples / 8)); InputError when a
// record is shorter than 4 windows.
signal::CorrelatorOptions identify_correlator(const IdentifyRecord& first, int lags, int skip);

// Runs the data-quality checks of one record (coupled pairs from its own file).
void check_record_quality(IdentifyRecord& r, const std::string& path,
                          const signal::CorrelatorOptions& correlator,
                          const std::optional<model::ModelOrder>& order, bool delay_auto);

// InputError unless every record has the first one's sample period, and the estimation
// records share their sample timing.
void check_records_agree(const std::vector<IdentifyRecord>& records);

// Adds the timing correction to every dead time of the result (model, parameters, the fit
// table, the band's phase); the validation data and correlations stay on the rows.
void refer_delays_to_plant(ident::IdentifyResult& result, double correction_s);

}  // namespace rig::cli
