#include "rig/ident/identify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rig::ident {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Bode band grid when none is given: from a thousandth of the top up to 0.4 / dt.
constexpr double kBandTopPerSampleRate = 0.4;
constexpr int kBandPoints = 160;
// Spectra of the covariance: Parzen window of +-256 samples (record permitting).
constexpr int kSpectrumHalfWidth = 256;

signal::CorrelatorOptions correlator_for(const IdentifyOptions& opt, double dt_s) {
  signal::CorrelatorOptions c = opt.correlator;
  c.dt_s = dt_s;
  return c;
}

// Batch means: MMFM estimates on consecutive blocks with the final fit's settings,
// std / sqrt(blocks) for every parameter, the delay and the derived figures.
void block_std_errors(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                      const IdentifyOptions& opt, const MmfmSettings& settings,
                      IdentifyResult& res) {
  const int b = opt.blocks;
  const Eigen::Index len = u.size() / b;
  MmfmOptions mo = opt.mmfm;
  mo.order = res.structure.order;
  mo.delay_s = res.structure.delay_estimated ? std::nullopt
                                             : std::optional<double>(opt.delay_s.value_or(0.0));
  mo.max_delay_s = opt.max_delay_s;
  mo.scale_s = settings.scale_s;
  const signal::CorrelatorOptions co = correlator_for(opt, dt_s);
  std::vector<Eigen::VectorXd> thetas;
  std::vector<double> delays, gains, fns, zetas;
  for (int i = 0; i < b; ++i) {
    try {
      const Eigen::VectorXd ub = u.segment(i * len, len), yb = y.segment(i * len, len);
      const MmfmResult r = estimate_mmfm(signal::auto_correlation(ub, co),
                                         signal::cross_correlation(yb, ub, co), mo);
      const model::TransferFunction t = normalise(r.model, opt.mmfm.normalisation);
      thetas.push_back(pack_parameters(t));
      delays.push_back(t.delay_s);
      const DerivedFigures d = derived_figures(t, Eigen::MatrixXd());
      gains.push_back(d.gain), fns.push_back(d.fn_hz), zetas.push_back(d.zeta);
    } catch (const std::invalid_argument&) {
    }
  }
  const double k = static_cast<double>(thetas.size());
  if (k < 3) return;
  auto sem = [k](const std::vector<double>& v) {
    double mean = 0, ss = 0;
    for (double x : v) mean += x / k;
    for (double x : v) ss += (x - mean) * (x - mean);
    return std::sqrt(ss / (k - 1.0) / k);
  };
  for (size_t p = 0; p + 1 < res.parameters.size(); ++p) {
    std::vector<double> v;
    for (const auto& t : thetas) v.push_back(t(static_cast<Eigen::Index>(p)));
    res.parameters[p].std_error = sem(v);
  }
  res.delay_std_s = res.structure.delay_estimated ? sem(delays) : 0.0;
  res.parameters.back().std_error = res.delay_std_s;
  if (res.derived.valid) {
    res.derived.gain_std = sem(gains), res.derived.fn_hz_std = sem(fns);
    res.derived.zeta_std = sem(zetas);
  }
  res.std_error_method = "block spread (" + std::to_string(thetas.size()) + " blocks)";
}

void check_inputs(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                  const IdentifyOptions& opt) {
  if (u.size() != y.size())
    throw std::invalid_argument("identify: u has " + std::to_string(u.size()) +
                                " samples but y has " + std::to_string(y.size()));
  if (!(dt_s > 0.0)) throw std::invalid_argument("identify: dt_s must be > 0");
  if (!(opt.estimation_fraction > 0.1 && opt.estimation_fraction < 0.9))
    throw std::invalid_argument("identify: estimation_fraction must lie in (0.1, 0.9)");
  if (u.size() < 4 * opt.correlator.lags)
    throw std::invalid_argument("identify: record of " + std::to_string(u.size()) +
                                " samples is shorter than 4 correlation windows");
  if (opt.order && (opt.order->n < 1 || opt.order->m < 0 || opt.order->m > opt.order->n))
    throw std::invalid_argument("identify: order must satisfy n >= 1 and 0 <= m <= n");
  if (opt.methods.empty()) throw std::invalid_argument("identify: no estimator given");
}

// The asymptotic covariance from the estimation data's spectra, its parameter table layout
// ([a_n..a_0, b_m..b_0] with a_n fixed) and the band at the report's frequencies.
Eigen::MatrixXd covariance_and_band(const RecordSet& est, double dt_s, const IdentifyOptions& opt,
                                    IdentifyResult& res) {
  const bool with_delay = res.structure.delay_estimated;
  const int n = res.model.order(), m = static_cast<int>(res.model.num.size()) - 1;
  const Eigen::Index p = n + m + 2;
  Eigen::MatrixXd table_cov = Eigen::MatrixXd::Constant(p, p, kNaN);
  const int half = std::min<int>(kSpectrumHalfWidth, static_cast<int>(est.size() / 4));
  int fft = 1;
  while (fft < 4 * half) fft *= 2;
  try {
    const InputNoiseSpectra sp = input_noise_spectra(est.u, est.y, dt_s, res.model, half, fft);
    const double power = res.structure.method == IdentMethod::kMmfm ? kCorrelationDomainWeightPower
                                                                    : kTimeDomainWeightPower;
    res.covariance =
        asymptotic_covariance(res.model, sp, static_cast<double>(est.size()), with_delay, power);
  } catch (const std::invalid_argument&) {
    return table_cov;  // too short a record for the spectra: no band
  }
  std::vector<double> f = opt.band_freqs_hz;
  if (f.empty()) {
    const double top = kBandTopPerSampleRate / dt_s;
    f = log_frequencies_hz(top / 1000.0, top, kBandPoints);
  }
  res.band = frf_uncertainty(res.model, res.covariance, f, with_delay);
  res.band_factor = simultaneous_factor95(res.model, res.covariance, f, with_delay);
  table_cov.setZero();
  table_cov.bottomRightCorner(p - 1, p - 1) = res.covariance.topLeftCorner(p - 1, p - 1);
  res.delay_std_s = with_delay ? std::sqrt(std::max(0.0, res.covariance(p - 1, p - 1))) : 0.0;
  return table_cov;
}

// The validation data from sample `from` on, with the chosen estimate's output.
void fill_validation(const RecordSet& val, double dt_s, const StructureFit& fit,
                     const IdentifyOptions& opt, const char* what, IdentifyResult& res) {
  ValidationData& v = res.validation;
  const Eigen::Index n = val.size() - opt.validation_from;
  model::TransferFunction shifted = fit.model;
  shifted.delay_s = std::max(0.0, shifted.delay_s + opt.validation_delay_shift_s);
  v.what = what;
  v.u = val.u.tail(n);
  v.y = val.y.tail(n);
  v.y_model = val.simulate(shifted, dt_s).tail(n);
  v.fit_pct = fit.validation_fit_pct;
  const auto lags = static_cast<Eigen::Index>(std::lround(kResidualMaxLagS / dt_s));
  v.residuals = residual_tests(v.y - v.y_model, v.u, dt_s, lags);
  res.validation_fit_pct = fit.validation_fit_pct;
}

std::string settings_text(const IdentifyOptions& opt, const IdentifyResult& res,
                          const std::string& split) {
  std::ostringstream s;
  s << res.structure.name() << (opt.order ? " (order given)" : " (chosen from the table)")
    << ", delay " << (opt.delay_s ? "given" : "estimated or 0 as the table chose") << ", " << split
    << ", normalisation " << to_string(opt.mmfm.normalisation) << ", lags " << opt.correlator.lags
    << ", zero index " << res.ruu.zero_index;
  if (res.structure.method != IdentMethod::kSrivc)
    s << ", " << to_string(res.mmfm_settings.family) << " functions " << res.mmfm_settings.functions
      << " x " << res.mmfm_settings.centres_s.size() << " centres, S " << res.mmfm_settings.scale_s
      << " s, " << res.mmfm_settings.extra_bands.size() + 1 << " scale bands, "
      << to_string(res.mmfm_settings.solver)
      << (opt.mmfm.refine ? ", refined by correlation-domain output error" : "");
  return s.str();
}

// Everything but the validation data from the final fit on `data`.
void finish(const RecordSet& data, double dt_s, const StructureFit& fit, const IdentifyOptions& opt,
            IdentifyResult& res) {
  res.structure = fit.structure;
  res.order = fit.structure.order;
  res.model = fit.model;
  res.condition_number = fit.condition_number;
  res.mmfm_settings = fit.mmfm_settings;
  Eigen::MatrixXd cov = covariance_and_band(data, dt_s, opt, res);
  const double delay_std = res.delay_std_s;
  res.model = normalise(res.model, opt.mmfm.normalisation, &cov);
  res.delay_s = res.model.delay_s;
  res.parameters = parameter_table(res.model, cov, delay_std);
  res.derived = derived_figures(res.model, cov);
  res.std_error_method = "asymptotic covariance";
  const signal::CorrelatorOptions co = correlator_for(opt, dt_s);
  res.ruu = averaged_auto_correlation(data, co);
  res.ryu = averaged_cross_correlation(data, co);
  res.model_ryu = model_cross_correlation(res.model, res.ruu, res.ryu);
}

const StructureFit& chosen_or_throw(const StructureTable& t) {
  if (!t.chosen_fit()) {
    throw NoStableModel(
        "no structure of the fit table gave a stable model: the records do not determine one "
        "(more excitation, a longer record, or another --order)");
  }
  return *t.chosen_fit();
}

}  // namespace

IdentifyResult identify(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                        const IdentifyOptions& options) {
  check_inputs(u, y, dt_s, options);
  IdentifyOptions opt = options;
  opt.validation_from = static_cast<Eigen::Index>(opt.estimation_fraction * u.size());
  opt.validation_delay_shift_s = 0.0;
  RecordSet whole, est;
  whole.add(u, y);
  // The head keeps the whole record's mean, so that the tail continues from its level.
  est.u = whole.u.head(opt.validation_from);
  est.y = whole.y.head(opt.validation_from);
  est.starts = {0};
  IdentifyResult res;
  res.table = structure_table(est, whole, dt_s, opt, opt.progress);
  const StructureFit& chosen = chosen_or_throw(res.table);
  StructureFit final_fit = fit_structure(whole, dt_s, chosen.structure, opt);
  if (!final_fit.ok) final_fit = chosen;
  finish(whole, dt_s, final_fit, opt, res);
  fill_validation(whole, dt_s, chosen, opt, "held-out part", res);
  if (res.structure.method == IdentMethod::kMmfm && opt.blocks >= 3 &&
      u.size() / opt.blocks >= 4 * opt.correlator.lags) {
    block_std_errors(whole.u, whole.y, dt_s, opt, final_fit.mmfm_settings, res);
  }
  std::ostringstream split;
  split << "estimated on the first " << opt.estimation_fraction
        << " of the record and validated on the rest, then re-estimated on the whole record";
  res.settings = settings_text(opt, res, split.str());
  return res;
}

IdentifyResult identify(const RecordSet& est, const RecordSet& val, double dt_s,
                        const IdentifyOptions& opt) {
  check_inputs(est.u, est.y, dt_s, opt);
  if (val.size() < 4 * opt.correlator.lags)
    throw std::invalid_argument("identify: validation record of " + std::to_string(val.size()) +
                                " samples is shorter than 4 correlation windows");
  IdentifyResult res;
  res.table = structure_table(est, val, dt_s, opt, opt.progress);
  const StructureFit& chosen = chosen_or_throw(res.table);
  finish(est, dt_s, chosen, opt, res);
  fill_validation(val, dt_s, chosen, opt, "validation record", res);
  res.settings = settings_text(
      opt, res,
      std::to_string(est.starts.size()) + " estimation record(s), validated on a separate record");
  return res;
}

}  // namespace rig::ident
