// Fitting many candidate hypotheses: each from its starting points on the worker threads,
// or screened first (a short search on a decimated record) with only the best searched in
// full (thresholds.hpp "Speed"). Used by the hypothesis search (search.cpp).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

using Candidate = std::vector<std::vector<AppliedEffect>>;  // starting points of one hypothesis

// Best score first (stable).
void rank(std::vector<HypothesisFit>& hypotheses);

// A ranked list without the repeats: a hypothesis whose effects, places, parameters and span
// equal one ranked above it (the same pair reached by two of the search's routes) is
// dropped, so that the report lists each once.
void drop_repeats(std::vector<HypothesisFit>& hypotheses);

// Every candidate fitted in full, on options.threads threads.
std::vector<HypothesisFit> fit_all(const Problem& problem, const std::vector<Candidate>& candidates,
                                   const Eigen::VectorXd& baseline_yhat,
                                   const DiagnoseOptions& options);

// Every candidate screened, the best `refine` searched in full from where the screen
// stopped, the rest scored as screened; ranked.
std::vector<HypothesisFit> screen_and_refine(const Problem& problem,
                                             const std::vector<Candidate>& candidates,
                                             const Eigen::VectorXd& baseline_yhat,
                                             const DiagnoseOptions& options,
                                             std::size_t refine = thresholds::kRefinedSingles);

}  // namespace rig::diagnose
