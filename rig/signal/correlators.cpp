#include "rig/signal/correlators.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "rig/signal/lag_kernels.hpp"

namespace rig::signal {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("correlator: " + what);
}

// Sums for every lag in reverse lag order (j = P - k) over the anchors of a whole record.
std::vector<double> reverse_sums(const Eigen::VectorXd& a, const Eigen::VectorXd& u,
                                 const CorrelatorOptions& o, Eigen::Index z) {
  const Eigen::Index n = u.size();
  const Eigen::Index p = o.lags - 1 - z;
  const detail::AnchorRun run{products_per_lag(o, n), o.skip, o.lags};
  std::vector<double> acc(static_cast<size_t>(o.lags), 0.0);
  // Anchor 0 is sample P; its window starts at sample 0.
  switch (o.kind) {
    case CorrelatorKind::kDirect:
      detail::direct_run(a.data() + p, u.data(), run, acc.data());
      break;
    case CorrelatorKind::kFft:
      detail::fft_run(a.data() + p, u.data(), run, acc.data());
      break;
    case CorrelatorKind::kRelay: {
      std::vector<std::uint64_t> mask(static_cast<size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i) mask[static_cast<size_t>(i)] = detail::sign_mask(u[i]);
      detail::relay_run(a.data() + p, mask.data(), run, acc.data());
      break;
    }
    case CorrelatorKind::kPolarity: {
      std::vector<std::uint8_t> un(static_cast<size_t>(n)), an(static_cast<size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i) {
        un[static_cast<size_t>(i)] = detail::is_negative(u[i]);
        an[static_cast<size_t>(i)] = detail::is_negative(a[i]);
      }
      std::vector<std::int64_t> disagree(static_cast<size_t>(o.lags), 0);
      detail::polarity_run(an.data() + p, un.data(), run, disagree.data());
      // sum of sgn(a) sgn(u) = agreements - disagreements = N' - 2 disagreements.
      const auto m = static_cast<double>(run.count);
      for (size_t j = 0; j < acc.size(); ++j) acc[j] = m - 2.0 * static_cast<double>(disagree[j]);
      break;
    }
  }
  return acc;
}

}  // namespace

Eigen::Index resolved_zero_index(const CorrelatorOptions& options) {
  if (options.zero_index >= 0) return options.zero_index;
  return static_cast<Eigen::Index>(std::floor(0.4 * static_cast<double>(options.lags)));
}

void validate(const CorrelatorOptions& o, Eigen::Index samples) {
  if (o.lags < 1) fail("lags must be >= 1, got " + std::to_string(o.lags));
  if (o.zero_index < -1 || o.zero_index >= o.lags) {
    fail("zero_index must be -1 (automatic) or in [0, lags-1] = [0, " + std::to_string(o.lags - 1) +
         "], got " + std::to_string(o.zero_index));
  }
  if (o.skip < 1) fail("skip must be >= 1, got " + std::to_string(o.skip));
  if (!(o.dt_s > 0.0) || !std::isfinite(o.dt_s)) {
    fail("dt_s must be a positive sample period, got " + std::to_string(o.dt_s));
  }
  if (o.arcsine_correction && o.kind != CorrelatorKind::kPolarity) {
    fail(std::string("arcsine_correction applies to kPolarity only, kind is ") + to_string(o.kind));
  }
  if (samples >= 0 && o.lags > samples) {
    fail("lags (" + std::to_string(o.lags) + ") exceed the record length (" +
         std::to_string(samples) + " samples)");
  }
}

Eigen::Index products_per_lag(const CorrelatorOptions& o, Eigen::Index samples) {
  const Eigen::Index anchors = samples - o.lags + 1;
  if (anchors <= 0) return 0;
  return (anchors + o.skip - 1) / o.skip;
}

Correlation cross_correlation(const Eigen::VectorXd& y, const Eigen::VectorXd& u,
                              const CorrelatorOptions& options) {
  if (y.size() != u.size()) {
    fail("y and u must be equally long, got " + std::to_string(y.size()) + " and " +
         std::to_string(u.size()) + " samples");
  }
  validate(options, u.size());
  const Eigen::Index z = resolved_zero_index(options);
  const std::vector<double> acc = reverse_sums(y, u, options, z);
  const auto m = static_cast<double>(products_per_lag(options, u.size()));

  Correlation c;
  c.zero_index = z;
  c.dt_s = options.dt_s;
  c.r.resize(options.lags);
  // Sample i holds lag k = i - z, stored at j = P - k = L - 1 - i.
  for (Eigen::Index i = 0; i < options.lags; ++i) {
    c.r[i] = acc[static_cast<size_t>(options.lags - 1 - i)] / m;
  }
  if (options.arcsine_correction) {
    c.r = (c.r.array() * (std::numbers::pi / 2.0)).sin().matrix();
  }
  return c;
}

Correlation auto_correlation(const Eigen::VectorXd& u, const CorrelatorOptions& options) {
  return cross_correlation(u, u, options);
}

const char* to_string(CorrelatorKind kind) {
  switch (kind) {
    case CorrelatorKind::kDirect:
      return "direct";
    case CorrelatorKind::kFft:
      return "fft";
    case CorrelatorKind::kRelay:
      return "relay";
    case CorrelatorKind::kPolarity:
      return "polarity";
  }
  return "unknown";
}

}  // namespace rig::signal
