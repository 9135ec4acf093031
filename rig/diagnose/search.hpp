// The hypothesis search of `rig diagnose` (docs/diagnose.md, Method step 3): every
// applicable effect at each place it can sit, screened and the best searched in full; onsets;
// pairs when the best single leaves the residual correlated with the input.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

// The hypotheses for a located mismatch, ranked by score.
std::vector<HypothesisFit> search_hypotheses(const Problem& problem, const Location& location,
                                             const Eigen::VectorXd& baseline_yhat,
                                             const DiagnoseOptions& options);

// When the location found nothing (no failed input test, no disturbance, no clip): every
// input-side single searched all the same, ranked (no pairs). The tests see a mismatch
// through the excited band's residual; an effect at its edge or below it (a shaft mode, an
// undeclared coupling) or in part of the record can escape them and still fit. The verdict
// asks such an effect to add thresholds::kUnseenInputGainPct (verdict.cpp).
std::vector<HypothesisFit> blind_search(const Problem& problem, const Location& location,
                                        const Eigen::VectorXd& baseline_yhat,
                                        const DiagnoseOptions& options);

// The problem with the effects acting on h's span only (an onset found for h).
Problem spanned(const Problem& problem, const HypothesisFit& h);

}  // namespace rig::diagnose
