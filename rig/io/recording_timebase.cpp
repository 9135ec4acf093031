// The time base of a recording: where dt comes from, and how uniform the time column is.
#include <fmt/format.h>

#include <cmath>

#include "rig/io/recording.hpp"

namespace rig::io {
namespace {

// Steps d_i = t_{i+1} - t_i against the mean step dt = (t_N - t_1) / (N - 1).
SamplingCheck check_time_column(const Recording& rec, double tolerance) {
  const Eigen::VectorXd& t = *rec.time_s;
  SamplingCheck out;
  out.has_time = true;
  const Eigen::Index n = t.size();
  for (Eigen::Index i = 1; i < n; ++i) {
    if (!(t[i] > t[i - 1])) {
      throw InputError(rec.source, rec.first_data_line + long(i), rec.time_name,
                       fmt::format("expected increasing time, t = {} is not after the previous "
                                   "row's {}",
                                   t[i], t[i - 1]));
    }
  }
  out.dt_s = (t[n - 1] - t[0]) / double(n - 1);
  double sum_sq = 0.0;
  for (Eigen::Index i = 1; i < n; ++i) {
    const double e = (t[i] - t[i - 1]) - out.dt_s;
    sum_sq += e * e;
    out.jitter_max_s = std::max(out.jitter_max_s, std::abs(e));
  }
  out.jitter_rms_s = std::sqrt(sum_sq / double(n - 1));
  out.uniform = out.jitter_max_s <= tolerance * out.dt_s;
  out.dt_source = "time column " + rec.time_name;
  return out;
}

bool from_scalars(const Recording& rec, double& dt_s, std::string& what) {
  for (const char* key : {"Ts", "ts", "dt", "dt_s"}) {
    const auto it = rec.scalars.find(key);
    if (it != rec.scalars.end() && it->second > 0.0) {
      dt_s = it->second;
      what = std::string("scalar column ") + key;
      return true;
    }
  }
  for (const char* key : {"fs", "Fs", "fs_hz"}) {
    const auto it = rec.scalars.find(key);
    if (it != rec.scalars.end() && it->second > 0.0) {
      dt_s = 1.0 / it->second;
      what = std::string("scalar column ") + key;
      return true;
    }
  }
  return false;
}

// The sidecar's sample_rate_hz against the file's own time base (recording.hpp: refused
// beyond kSampleRateTolerance, a warning only when --dt settles the time base).
void check_sidecar_rate(Recording& rec, const ReadOptions& options) {
  if (!rec.sidecar.sample_rate_hz) return;
  double file_dt = 0.0;
  std::string what;
  if (rec.sampling.has_time) {
    file_dt = rec.sampling.dt_s;
    what = fmt::format("the time column \"{}\" of {} says (mean step {:.6g} s)", rec.time_name,
                       rec.source, file_dt);
  } else if (std::string scalar; from_scalars(rec, file_dt, scalar)) {
    what = fmt::format("the {} of {} says ({:.6g} s)", scalar, rec.source, file_dt);
  } else {
    return;
  }
  const double rate = *rec.sidecar.sample_rate_hz;
  if (!(std::abs(1.0 / rate - file_dt) > kSampleRateTolerance * file_dt)) return;
  const std::string side = rec.sidecar.source.empty() ? "sidecar" : rec.sidecar.source;
  const std::string message = fmt::format(
      "key \"sample_rate_hz\": expected {:.6g} Hz as {}, found {:.6g} Hz (a {:.6g} s "
      "step); they must agree within {:g} %",
      1.0 / file_dt, what, rate, 1.0 / rate, 100.0 * kSampleRateTolerance);
  if (options.dt_s) {
    rec.warnings.push_back(
        fmt::format("{}: {} (--dt {} s overrides both)", side, message, *options.dt_s));
    return;
  }
  throw InputError(side, 0, "", message + ": correct the sidecar or the recording, or give --dt");
}

}  // namespace

void resolve_time_base(Recording& rec, const ReadOptions& options) {
  if (rec.time_s && rec.time_s->size() >= 2) {
    rec.sampling = check_time_column(rec, options.jitter_tolerance);
    rec.dt_s = rec.sampling.dt_s;
  }
  check_sidecar_rate(rec, options);
  if (options.dt_s) {
    if (!(*options.dt_s > 0.0) || !std::isfinite(*options.dt_s)) {
      throw InputError(
          rec.source, 0, "",
          fmt::format("--dt: expected a sample period > 0 s, found {}", *options.dt_s));
    }
    if (rec.sampling.has_time && std::abs(rec.dt_s - *options.dt_s) > 0.01 * *options.dt_s) {
      rec.warnings.push_back(fmt::format("{}: --dt {} s overrides the time column's mean step {} s",
                                         rec.source, *options.dt_s, rec.dt_s));
    }
    rec.dt_s = *options.dt_s;
    rec.sampling.dt_s = rec.dt_s;
    rec.sampling.dt_source = "option";
    return;
  }
  if (rec.sampling.has_time) return;
  std::string what;
  double dt_s = 0.0;
  if (rec.sidecar.sample_rate_hz) {
    rec.dt_s = 1.0 / *rec.sidecar.sample_rate_hz;
    rec.sampling.dt_source = "sidecar sample_rate_hz";
  } else if (from_scalars(rec, dt_s, what)) {
    rec.dt_s = dt_s;
    rec.sampling.dt_source = what;
  } else if (options.require_time_base) {
    throw InputError(rec.source, 0, "",
                     "expected a time base: no time column (t), no sample_rate_hz in a "
                     "sidecar, no Ts/fs column; give the sample period with --dt");
  }
  rec.sampling.dt_s = rec.dt_s;
}

}  // namespace rig::io
