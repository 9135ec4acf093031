// The decision thresholds of `rig diagnose` in one place, each with its reason. Scores and
// gains are in percentage points of the validation fit (DESIGN.md 5); ratios are plain.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <utility>

namespace rig::diagnose::thresholds {

// --- Verdict (diagnose.cpp) ---
// A hypothesis can be the verdict when its validation score (gain minus penalty) reaches
// this: below it the effect does not make the model better on the data it was not fitted to
// (the default of DiagnoseOptions::min_gain_pct).
inline constexpr double kMinGainPct = 0.2;
// Each fitted parameter costs this much validation gain, so a parameter that buys less is
// over-fitting and the simpler hypothesis wins (the default of
// FitOptions::penalty_pct_per_parameter).
inline constexpr double kPenaltyPctPerParameter = 0.25;
// Below kMinGainPct a hypothesis is still the verdict when the input tests failed, nothing
// reached kMinGainPct, and it scores above this and leaves a residual independent of the
// input (verdict.cpp explains_below_min_gain): its parameters paid for themselves.
inline constexpr double kExplainedBelowMinGainPct = 0.0;

// An input-side nonlinearity is the verdict only when it scores this much more than the
// best hypothesis without one: at one amplitude a play or a hysteresis inside the loop acts
// as a lag (its describing function), and with a fitted place they shape the band as freely
// as a linear effect. 0.75 points (three parameters' penalty): on the gensim benchmark a
// 60 ms combustion lag gave its best placed play 0.67 points over the lag, while deadbands
// and plays beat the best linear effect by 0.86 points or more.
inline constexpr double kNonlinearOverLinearPct = 0.75;
// A memoryless static map of the level (EffectModel::level_shaped, not has_memory: a
// deadband, a plain limit, a curved map) at a place that fits no dynamics of its own (no
// place parameters: at the input, on the governor's error, at the output) has no lag to
// stand in for: at one amplitude it is a gain, its describing function. What it adds over a gain
// change is the dependence on the level itself, and its score has paid for its parameters. It needs
// one parameter's penalty over the best linear choice, not the placed plays' three (gensim seed 5
// g034, a deadband on the governor's error from 60 s: 0.60 points over a gain change from the same
// onset).
inline constexpr double kStaticMapOverLinearPct = kPenaltyPctPerParameter;
// A play or a placed map from an onset stands in for a lag on its span only: it needs the
// span's share of kNonlinearOverLinearPct over the best linear choice (verdict.cpp), but never
// less than one parameter's penalty, what fitting noise alone buys a parameter. The share is of
// the whole record, over which the validation blocks interleave, whether an onset or the
// residual's located window gated the effect. Measured: droopsim seed 11 d037, a linkage play
// from 99 s, 0.40 points over a delay from the same onset (the margin on its third of the
// record 0.26); seed 11 d032, a speed-error deadband located at 102-135 s, 0.28 points over a
// gain change there (margin 0.25, the floor).
inline constexpr double kSpannedMarginFloorPct = kPenaltyPctPerParameter;
// Another explanation within this many points of the verdict's score is named beside it in
// the explanation (report.json "alternative"): the margin a nonlinearity needs over a linear
// effect, below which the data do not tell two shapes apart.
inline constexpr double kCloseAlternativePct = kNonlinearOverLinearPct;

// An effect that contains a simpler one as a special case (EffectModel::generalises:
// hysteresis, a play at shape_ratio 1) is named only when it scores this much more than the
// simpler one: four parameters' penalty, so that its extra shape parameter has bought more
// than the fitting noise of two placed nonlinearities.
inline constexpr double kNestedMarginPct = 1.0;

// A lag is named rather than a transport delay at the same place only when it scores this
// much more: the two agree to first order in frequency (1 / (1 + sT) and e^{-sT} are both
// 1 - sT), and what tells them apart is the lag's attenuation near the band's top, which a
// closer fit does not show. Measured on droopsim seeds 1-3 (30 cases): a delay inside the
// governor's loop lost to the lag there by at most 0.008 points, a lag there beat the delay
// by 0.14 points or more; 0.075 is midway (under a third of one parameter's penalty).
inline constexpr double kLagOverDelayMarginPct = 0.075;

// A resonance that re-damps one of the model's own modes is a damping change (verdict.cpp):
// its zeros cancel the mode (frequency within kRedampZerosFrequency, damping ratio within
// kRedampZerosDamping, relative) and its poles moved the damping ratio at least
// kDampingOverStiffness times as much (relative) as the frequency. A change of stiffness or
// inertia moves both by the same relative amount (f ~ sqrt(k/m), zeta ~ c / sqrt(k m)); a
// change of damping moves the damping ratio alone (droopsim's damper windings: the swing
// mode's damping ratio 0.147 -> 0.10, its frequency 2 %).
inline constexpr double kRedampZerosFrequency = 0.1;
inline constexpr double kRedampZerosDamping = 0.3;
inline constexpr double kDampingOverStiffness = 3.0;

// A play or a hysteresis loop is the verdict only when the location's direction test
// (the residual on G(sign du/dt), locate_amplitude.cpp) gives |z| >= 3: a direction
// effect at three standard errors. On gensim every play and hysteresis case shows
// |z| 2.8-8.7 (2.8 the one present in half the record), every deadband case 0.2-1.5.
inline constexpr double kDirectionEvidenceZ = 3.0;
// The same test with the model's response to du/dt beside it (what a missing lag or delay
// adds): a play's sign at this z is a play beyond any lag, and a play or hysteresis loop
// within kNonlinearOverLinearPct of the best hypothesis is then the verdict (verdict.cpp).
// Measured (seed 1): droopsim's plays and hysteresis after the governor -2.2 to -3.8
// (half-way and behind 3x the grid's wander -1.0, -1.2); every other case of droopsim and
// gensim -2.1 (a saturation) or above (a rate limit: +3 to +8, the other sign); gensim's
// plays and hysteresis inside the PI loop -1.9 to +2.1 (no evidence: there the margin holds).
inline constexpr double kDirectionBeyondLagZ = 2.5;
// A gain the data show: |H1 / G| this far from 1 (6 dB, twice or half the model's gain) in a
// bin whose residual coherence is significant and where |H1|'s relative standard error
// sqrt((1 - c) / (2 M c)) (coherence c, M effective Welch segments) is at most
// kGainPeakRelError: the 6 dB are then four standard errors or more. A hypothesis accounts for it
// when its own response there (H1 less the residual's) takes at least kGainPeakTakenShare of
// the disagreement's |ln|H1 / G||, i.e. leaves under half of it in dB; the
// best one that does, within kNonlinearOverLinearPct of the choice, is the verdict
// (verdict.cpp): a delay or a lag in the loop cannot raise the gain by 6 dB above the band,
// a moved shaft mode does (droopsim's softened coupling: +10 to +15 dB at 5-5.4 Hz, the
// delay on the governor's error 0.1-0.3 points above the moved modes).
inline constexpr double kGainPeakRatio = 2.0;
inline constexpr double kGainPeakRelError = 0.25;
inline constexpr double kGainPeakTakenShare = 0.5;
// When none within the margin takes that share, the best one whose own response takes more
// of the disagreement's |ln| than the choice's by at least the peak's standard error (|H1|'s
// relative error bound above, that of ln|H1|): the data's gain is nearer its shape. Noise
// hides the top of a mode above the band, so its fit takes a quarter to a half of the peak
// where a delay in the loop takes none (droopsim's softened coupling, 6-7 Hz: 0.32-0.63 more
// of the |ln| than the delay on the governor's error; docs/diagnose.md).
inline constexpr double kGainPeakLeadLog = kGainPeakRelError;
// An effect found to act from late in the record (onset.cpp) is looked for over its own span
// when the whole record shows no peak, if the span holds this many samples: 16 disjoint
// segments of welch_segment's shortest length (64), so that its own segments (128 at this
// length) number 15 or more, as on the whole record.
inline constexpr Eigen::Index kGainPeakSpanMinSamples = 16 * 64;
// Failing that, it is looked for again with Welch segments this many times shorter (never
// under 64 samples: 2 times on spans under 2048): four times the segments shrink |H1|'s
// standard error by half where noise hides a mode, at a resolution (0.4 Hz on 150 s at
// 100 Hz) still finer than a mode's half-power width.
inline constexpr Eigen::Index kGainPeakCoarserBy = 4;

// --- Location (locate*.cpp; docs/diagnose.md Method step 2) ---
// A residual spectral line: its PSD bin exceeds this many times the median of its
// neighbours' (8 bins each side, the adjacent ones left out). The median of a chi^2(2 M)
// periodogram's neighbours is steady; a factor 12 above it is beyond the Welch estimate's
// own spread for the segment counts used (a false line on none of the gensim and plantsim
// nulls).
inline constexpr double kLineToNeighbours = 12.0;
// The drift test's smoother: a time scale of at least this many samples and of the record
// over this (slower than the excited band, a few dozen per record).
inline constexpr double kDriftSmoothMinSamples = 50.0;
inline constexpr double kDriftSmoothRecordDivisor = 40.0;
// A drift: the smoothed residual carries more than this share of the residual's variance
// (white noise through the smoother keeps about dt / tau of it) ...
inline constexpr double kDriftShare = 0.10;
// ... and more than this many times that white-noise share ...
inline constexpr double kDriftOverWhite = 30.0;
// ... and it is not the smoothed model output (|correlation| below this): a slow wander the
// input drives is an input effect seen slowly (a limit inside the loop), not a drift.
inline constexpr double kDriftNotModelCorr = 0.7;
// The time windows: a window's ln(mean r^2) over the quiet level by this many of its
// standard deviations (a Gaussian tail of 3e-6 per window, 40 windows) ...
inline constexpr double kWindowExcessSds = 4.5;
// ... and its rms by this factor at least (a 15 % louder window is no effect worth locating) ...
inline constexpr double kWindowMinRmsRatio = 1.15;
// ... and its mean square more than this factor above what the quiet windows predict from
// its model output (a residual loud where the signal is loud is a gain, not a span).
inline constexpr double kWindowOverSignalPrediction = 2.25;
// The amplitude test: the gains of the lowest and highest input levels differ by more than
// this (2 %, below a transducer's accuracy class) as well as significantly.
inline constexpr double kAmplitudeMinSpread = 0.02;
// The level test as evidence that tells a static map of the level (a deadband, a limit, a
// curved map) from a linear effect fitted as well, once a mismatch is established
// (evidence.cpp level_evidenced): chi^2(4) at 1e-2, a conventional significance. As a finding
// (amplitude_dependent) the test runs on every record beside the other input tests and takes
// 1e-4 (23.51). Measured: of 160 records with a linear effect (droopsim seeds 1-5, gensim
// seed 1) and 41 nulls none exceeds 13.28; 31 of 98 with a nonlinearity do.
inline constexpr double kLevelEvidenceChi2 = 13.28;
// The sign and direction tests: |z| beyond this (the regression's standard error inflated by
// the residual's correlation; 5: a false alarm in over a million records per test).
inline constexpr double kSignDirectionZ = 5.0;
// The sign test as evidence that tells a static map of the level from a linear effect fitted
// as well (evidence.cpp level_evidenced): a gain that differs between positive and negative
// excursions is what no gain, lag or delay gives, and a one-sided limit or a curved map does.
// Behind drift, wander and grid events the test's z has heavier tails than its bound
// assumes: of 391 records with a linear effect or none (droopsim seeds 1, 9-13, gensim seed
// 5) the largest |z| is 5.5 (an AC coupling behind the wander), three nulls reach 4.5-4.9;
// 59 of the 244 with a nonlinearity exceed 6.5, a margin of 1 over the linear records.
inline constexpr double kSignEvidenceZ = 6.5;

// --- Speed: screening the singles (screen.cpp) ---
// Every single hypothesis (each effect at each place: about 35) is first searched with at
// most this many simulations per starting point ...
inline constexpr int kScreenEvaluations = 30;
// ... and only this many of the best are then searched in full (FitOptions), from where the
// screen stopped: the rest are ranked well below the verdict's margins already. A quarter of
// the candidates: 10 of about 43 since saturation's soft limit added its places (with 8 its
// forms took the slots of the limit that follows the air after the governor's PI, which
// was then never refined: droopsim seed 6 d025 and seed 1 d029 named `static_nonlinearity`).
inline constexpr std::size_t kRefinedSingles = 10;
// The screen runs on every f-th sample of a record of at least kScreenMinSamples samples,
// f keeping kScreenOversampling samples per period of the input's rms frequency (its rate
// over its rms, over 2 pi: 2.8 Hz for the rig's 4 Hz Gaussian bias; 6 samples per period
// keep the simulated response within several per cent, enough to rank, and the refined and
// polished fits run on the whole record), at most kScreenMaxDecimation and at most the
// model's dead time in samples (screen.cpp). On ten 600 s gensim records the verdicts are
// those of 10 samples per period, the median time 3.9 s against 5.7 s.
inline constexpr Eigen::Index kScreenMinSamples = 20000;
inline constexpr double kScreenOversampling = 6.0;
inline constexpr int kScreenMaxDecimation = 8;
// On such a record every full search (the refined singles, the pairs) also runs on the
// decimated samples, and is then polished on the whole record from where it stopped with at
// most this many simulations: a few Levenberg-Marquardt steps of a 2-7 parameter hypothesis,
// enough to take up the decimation's few per cent (a 10-minute 100 Hz record: the search's
// simulations cost a third, docs/diagnose.md "Speed"). 20 is not enough: EMPS's pulses
// record (24 841 samples) then chose a worse-fitting pair (87.3 % against 90.2 %).
inline constexpr int kPolishEvaluations = 40;
// On such a record the screen searches each single from its best starting point only (3
// otherwise, FitOptions::searched_starts): every start is still evaluated once, and over
// ten minutes that first evaluation tells them apart. The screen cost 60-70 % of a 600 s
// record's time (on ten 600 s gensim records and the 83 cases of gensim seed 3's list at
// 600 s every verdict is that of three starts, docs/diagnose.md "Speed").
inline constexpr std::size_t kLongScreenSearchedStarts = 1;

// --- A two-level input (locate.hpp two_level_input) ---
// A PRBS sits on two values; rounding to 1 % of the input's standard deviation keeps a
// Gaussian's thousands of values apart (its two most common then hold ~1 % of the samples)
// while a recorded PRBS's setpoints, exact to the register's resolution, stay two. 95 %:
// a few samples of a ramp between levels (a slew-limited setpoint writer) are allowed.
inline constexpr double kTwoLevelResolution = 0.01;
inline constexpr double kTwoLevelShare = 0.95;
// On such an input the direction test is no evidence; a play or hysteresis loop inside the
// loop or at the output is shown by its fit when it outscores every hypothesis without one
// by this much (evidence.cpp weigh_plays_on_two_level_input): the nested margin, four
// parameters' penalty. Measured on gensim seed 1 with a PRBS bias (83 records): where the
// actuator has no play, the best play came at most 0.20 points over the rest (a transducer
// lag); the actuator's Bouc-Wen hysteresis 1.4-3.3 points; its plays 0.74 at most (on equal
// steps a play in the loop acts much as a lag: not told apart, not named).
inline constexpr double kTwoLevelPlayMarginPct = kNestedMarginPct;

// --- A clipped output (augmented_model.hpp OutputClip) ---
// A sensor at the end of its range, or a level held by an overflow, records one value again
// and again at the edge of the output's distribution. A measured, noisy signal repeats a
// value only through its quantisation, and then less often towards its extremes; so the
// output is clipped when its extreme value holds at least kClipMinSamples samples and
// kClipPileRatio times as many as any of the next values inward (ident::extreme_pile). The
// cascaded tanks: 47 and 37 samples at exactly 10.0 V, no value near it more than twice.
inline constexpr Eigen::Index kClipMinSamples = 10;
inline constexpr double kClipPileRatio = 4.0;

// --- Pairs (diagnose.cpp) ---
// Only the best input-side singles are paired with each other (every pair is a full fit).
inline constexpr std::size_t kPairedInputSingles = 3;
// The best input-side single is also paired with every other input-side effect (at its best
// place): these pairs are screened as the singles are, and this many of them refined.
inline constexpr std::size_t kRefinedForwardPairs = 3;
// Of the best input-side singles, this many are also paired with each detected disturbance.
inline constexpr std::size_t kPairedWithDisturbance = 2;
// The pairs inside the governor's loop (a nonlinearity on its error beside its best lag) are
// screened and this many refined.
inline constexpr std::size_t kRefinedLoopPairs = 2;
// A disturbance whose single scores this much dominates the residual: the input-side
// singles, fitted without it, are ranked by noise then, so every input-side effect is paired
// with it (the drift materiality gain below: the same "clearly more than noise").
inline constexpr double kDominantDisturbanceGainPct = 3.0;
// Its pairs with the other places of each nonlinearity (not the best: it was placed without
// the disturbance) are screened; the best this many are then searched in full.
inline constexpr std::size_t kRefinedDominantPlaces = 2;

// When the input tests passed beside a dominant disturbance, every input-side effect is
// paired with it (search.cpp behind_disturbance) and this many of the screened pairs are
// searched in full ...
inline constexpr std::size_t kRefinedBehindDisturbance = 3;
// ... and such a pair is the verdict only when it adds this much to the disturbance alone:
// the input tests saw nothing, so the evidence is the fit itself, and it must be clearly more
// than noise (the same gain that makes a drift material). On gensim a rack stop behind the
// grid's wander adds 6.6 points that the tests, their bounds widened by the wander, missed.
inline constexpr double kUnseenInputGainPct = 3.0;

// --- Drift materiality (drift_materiality.cpp) ---
// A drift alone is material when its rms is at least this fraction of the input-driven
// response's: a slow wander of a few kW on a set excited by +-3 % is the operating noise of
// a running set (every plant recording has some), not a missing effect.
inline constexpr double kDriftMaterialFraction = 0.10;
// ... or when modelling it raises the validation fit by this much.
inline constexpr double kDriftMaterialGainPct = 3.0;
// An output carries its operating level when |mean| exceeds this many standard deviations
// (e.g. a power reading) ...
inline constexpr double kOperatingLevelStds = 10.0;
// ... and then a drift must also exceed this fraction of that level: wander within a power
// transducer's accuracy (class 0.2-0.5 %) is no missing effect however small the excitation
// (a commissioning test's is small on purpose).
inline constexpr double kDriftMaterialOfLevel = 0.002;
// ... unless modelling it raises the validation fit by this much: then the record shows it
// clearly, whatever the transducer's class. Twice the most a null's nuisance drift gained
// (5.5 points, droopsim seed 1 d086, over the 50 nulls of droopsim seeds 1 and 9-13 and
// gensim seeds 5 and 6); gensim seed 6's 20 kW and 8 kW drifts gained 20.8 and 14.3 points
// at 0.12-0.16 % of the level.
inline constexpr double kDriftClearGainPct = 10.0;

// --- The extra_lag / sensor_lag twins (split.cpp) ---
// The residual's noise PSD above the corner fc over that below is about 1 for noise that
// bypassed the lag and about |1/(1 + j 3)|^2 = 0.1 for noise inside it; below this ratio the
// lag is the transducer's.
inline constexpr double kSensorLagRolloffRatio = 0.5;
// The bands compared, in multiples of fc: [2 fc, 4 fc] (capped below Nyquist) over
// [fc/4, fc/2], an octave each, far enough from the corner for the lag to show.
inline constexpr double kRolloffHighFrom = 2.0;
inline constexpr double kRolloffHighTo = 4.0;
inline constexpr double kRolloffLowFrom = 0.25;
inline constexpr double kRolloffLowTo = 0.5;
// What a first-order lag alone makes of white noise over those bands: the mean of
// 1 / (1 + (f/fc)^2) over [2 fc, 4 fc], (atan 4 - atan 2) / 2, over that over [fc/4, fc/2],
// 4 (atan 0.5 - atan 0.25): 0.1094 / 0.8747 = 0.125. A ratio under half of it falls off more
// steeply than the lag can make it: the residual has a colour of its own (a disturbance the
// plant filters, gensim's grid wander through the swing mode: 0.02-0.07 for a combustion lag
// and a transducer lag alike), and the roll-off no longer tells the transducer from the plant.
inline constexpr double kLagWhiteNoiseRolloff = 0.125;
inline constexpr double kRolloffOwnColourShare = 0.5;

// --- Effects present in part of the record (split.cpp gate_to_windows, onset.cpp) ---
// The residual's windows out of bounds gate the input-side effects to their span when they
// cover at least this fraction of the record (too little to fit on) ...
inline constexpr double kGateMinCoverage = 0.05;
// ... at most this fraction (more is most of the record: fit it all) ...
inline constexpr double kGateMaxCoverage = 0.75;
// ... and at least this fraction of the span they bound (mostly contiguous).
inline constexpr double kGateMinContiguity = 0.6;
// A span reaching this fraction of the record runs to its end (the last window is shorter).
inline constexpr double kGateToEnd = 0.95;
// Onset search: the hypothesis' gain per window over this many windows ...
inline constexpr int kOnsetWindows = 40;
// ... changes at a point with a two-sample |t| beyond this: a clear step, not the
// fluctuation of the window gains ...
inline constexpr double kOnsetMinT = 4.0;
// ... with the quiet side gaining under this fraction of the active side.
inline constexpr double kOnsetQuietFraction = 0.25;
// Only the best input-side hypotheses are searched for an onset (each refit is a full fit).
inline constexpr int kOnsetHypotheses = 3;

// --- Operating-point steps (onset.cpp find_level_shift) ---
// A gain change fitted from a level step is kept over one from a change point of its own
// scoring up to this much more: the step is independent evidence of when the gain changed,
// while the change point was chosen on the data it is scored on (two parameters' penalty,
// the span's two ends).
inline constexpr double kStepOnsetMarginPct = 2 * kPenaltyPctPerParameter;
// A step's |d_k| must exceed this many robust spreads of d (drift and noise move d smoothly
// and everywhere, a step only near one k) ...
inline constexpr double kLevelShiftSpreads = 10.0;
// ... and this fraction of the model output's std: large against the input-driven response.
inline constexpr double kLevelShiftOfOutputStd = 0.5;
// A grid event (bus_frequency.hpp) is such a step of the grid's share at this many spreads:
// the share is the frequency through a few lags, with no effect's slow part in it, only the
// wander's. On droopsim seeds 1-3 the frequency's 2 s window differences reached 2.2-4.5
// robust spreads on the 33 records with the wander alone (3x the wander, or the nuisances),
// 3.9-11.9 at events of 20-50 mHz; 6 keeps every wander out and the events above 25 mHz in.
inline constexpr double kGridEventSpreads = 6.0;
// The step-gain test (locate.hpp StepGain): the gain after a level step differs from before
// it by more than this many standard deviations (the sign and direction tests' bound) ...
inline constexpr double kStepGainZ = 5.0;
// The step-gain and coupling fits (residual_stats.hpp gls_fit) whiten the residual by an AR
// model of this order: 0.2 s at 100 Hz, the span of the colour a transducer's lag and a
// grid's wander leave in it.
inline constexpr int kWhitenOrder = 20;
// ... and by what the level's step implies, within this many (a 99.7 % interval).
inline constexpr double kStepGainAgreeSds = 3.0;
// The test fires when the change agrees with the level's and the level's reading is at least
// this many times as likely as an unchanged gain: the ratio of the two normal likelihoods,
// exp((z^2 - z_level^2) / 2), z_level the change's distance from the level's in sd (Jeffreys'
// "strong" evidence). An operating-point step that leaves the gain as it was passes with
// probability at most 1.6 % whatever its size (the worst, a level ratio 2.1 sd from 1, needs
// z > 2.15); any |z| beyond kStepGainZ that agrees passes (ratio >= e^8). gensim seed 5 g019,
// a transducer gain 0.920 from 60 s: response x0.926 +- 0.032, z = -2.3, ratio 15.
inline constexpr double kStepGainLikelihoodRatio = 10.0;

// The coupling test (locate_coupling.cpp) tries RC from this, in steps of sqrt(2) (RC within
// 19 % of one of them) ... 2 s puts the coupling's corner (0.08 Hz) inside a commissioning
// test's band, where the frequency test already sees it.
inline constexpr double kCouplingRcFromS = 2.0;
// ... up to the record's duration over this: a slower coupling's part of the residual is a
// few slow swings, which a drift makes as well.
inline constexpr double kCouplingRcsPerRecord = 6.0;
// It fires when the coefficient is within kStepGainAgreeSds of the coupling's -1 and that
// reading is this many times as likely as none. Over the 684 records of droopsim seeds 1, 9,
// 10, 13 and 14 and gensim seeds 5-7, no null and no linear effect but a coupling reaches
// e^6.0 (about 400; a drift, a lag behind a drift); the weakest coupling found by no other
// test, gensim seed 6 g069 (RC 15 s), reads e^18.0.
inline constexpr double kCouplingLikelihoodRatio = 1e4;

// --- Where an input-side nonlinearity sits (placement.cpp) ---
// The in-loop place's front lag T_f (the path from the bias to the nonlinearity: a
// governor's output filter and actuator servo, 20 ms to a few hundred ms) is searched
// between these: below 5 ms it is the input place, above 2 s the nonlinearity would act on
// a signal the excitation hardly moves.
inline constexpr double kFrontLagMinS = 0.005;
inline constexpr double kFrontLagMaxS = 2.0;
// A fitted front lag (or a PI loop's integral time) at this fraction of its upper bound or
// more stopped at the bound (placement.hpp place_credible).
inline constexpr double kFrontLagAtBound = 0.98;
// An in-loop limiter's recovery_s at this fraction of its bound or more stopped there
// (effects/common.hpp recovery_credible).
inline constexpr double kAtRecoveryBound = 0.98;
// Its starting points: an actuator (50 ms) and a governor's filtered output (300 ms).
inline constexpr double kFrontLagSeedsS[] = {0.05, 0.3};
// The feedback place's gain c: the output's nonlinear part fed back, as a share of the
// force the model's own static stiffness (1/G0) makes; above 1.5 the loop would hold more
// than the whole restoring force (and its fixed point stops converging).
inline constexpr double kFeedbackGainMax = 1.5;
inline constexpr double kFeedbackGainSeeds[] = {0.3, -0.3};
// The feedback place's loop is solved by fixed-point iteration over the whole record: at
// most this many passes, until the output changes by less than this share of its rms.
// Each pass moves this share of the way (under-relaxed: a lightly damped mode makes the
// plain iteration overshoot).
inline constexpr int kFeedbackPasses = 16;
inline constexpr double kFeedbackRelaxation = 0.6;
inline constexpr double kFeedbackTolerance = 1e-4;

// --- After the governor's PI, in its loop (placement.hpp, pi_loop) ---
// The PI's integral time: from a fast integrating actuator loop (20 ms, two samples) to a
// slow trim (20 s, a sixth of a short record); a governor's is typically 0.1-2 s.
inline constexpr double kPiIntegralMinS = 0.02;
inline constexpr double kPiIntegralMaxS = 20.0;
// Starting integral times: a fast and a slow governor.
inline constexpr double kPiIntegralSeedsS[] = {0.25, 1.5};
// The governor's output filter (with the actuator's own lag): from none (5 ms, half a
// sample) to 0.5 s (slower than any governor's output stage), started at 50 ms.
inline constexpr double kPiFilterMinS = 0.005;
inline constexpr double kPiFilterMaxS = 0.5;
inline constexpr double kPiFilterSeedS = 0.05;
// The signal after the PI is put in the bias's units (its bias-% equivalent, the unit of a
// limit, a play or a slew rate there) by the ratio of the two rms taken above this
// first-order high-pass's corner (2 s: 0.08 Hz). Below it the reconstruction is not the
// governor's: rebuilt from the model's output through a fitted feedback whose static share
// is not 1, the error keeps a DC part that the PI's integrator turns into a slow wander a
// real loop removes, and over the whole band that wander set the scale (droopsim's slew
// limits and plays after the PID read 25-83 % low, seed 2; gensim's PI loop, whose
// reconstruction is right, within 16 %). With the high-pass: droopsim within 12 % but the
// two records behind 3x the grid's wander (-38 %, -23 %), gensim within 18 % (from the
// exact scripts of docs/droopsim.md, "Units after the PI").
inline constexpr double kPiScaleHighPassS = 2.0;

// --- Inside the governor's loop, its feedback fitted (governor_loop.hpp) ---
// The feedback h = (a + s T_d) / (1 + s T_h) on G' = G / G0. The static share a: +-2,
// twice the unity loop's either way (a droop governor's loop, seen from the bias, holds a
// positive static share: on droopsim a lag in it fitted a = -0.5 to -1.7); the derivative
// time T_d: 0 (a power loop) to 0.5 s. A droop governor sees speed, the derivative of power
// through the synchronising torque: T_d ~ 1 / (K_s w_base droop) = 1 / (1.5 * 314 * 0.04)
// ~ 0.05 s (droopsim's lags, delay and slew limit fitted 50-85 ms); ten times that is the
// most a set on a grid has. A negative derivative is no governor's: fitted free, it stood in
// for a gain change or a damping change on gensim's power loop. T_h from 5 ms (under a
// 50 Hz sample: no filter, the place's credible lower end) to 2 s.
inline constexpr double kLoopStaticMin = -2.0;
inline constexpr double kLoopStaticMax = 2.0;
inline constexpr double kLoopDerivativeMaxS = 0.5;
inline constexpr double kLoopFilterMinS = 0.005;
inline constexpr double kLoopFilterMaxS = 2.0;
// Starting feedbacks {a, T_d, T_h}: a power loop (a slow and a fast filter) and a speed loop.
inline constexpr double kLoopSeeds[][3] = {{1.0, 0.0, 0.1}, {0.0, 0.06, 0.04}, {1.0, 0.0, 0.01}};
// The speed loop among them: the error-loop places with a fitted feedback start there only
// (their unity loop is the error and pi_loop places' own).
inline constexpr int kSpeedLoopSeed = 1;
// A fitted share at this fraction of its bound or more stopped there (a stand-in for some
// other shape, place_credible).
inline constexpr double kLoopAtBound = 0.98;

// --- The grid's share through a recorded bus frequency (bus_frequency.hpp) ---
// The bus frequency is the grid's (a disturbance) only when its coherence with the bias,
// averaged over the excited band (Welch, kBusFrequencySegments segments), stays below this: an
// islanded set's frequency is its own power's answer to the bias, which a regression on it would
// take from the model. Independent signals average 1/15 (~0.07) by chance; 0.3 is four times that
// and leaves room for a weak grid the set moves a little.
inline constexpr double kBusFrequencyMaxBiasCoherence = 0.3;
// Segments of the coherence estimate, and the excited band: bins where the bias's spectrum
// is at least this fraction of its peak.
inline constexpr int kBusFrequencySegments = 15;
inline constexpr double kBusFrequencyBandShare = 0.1;
// The grid's share is fitted on the frequency and on it through first-order lags of these
// time constants (the governor's, the engine's and the air path's answer to the droop) and
// its rate of change (the rotor's inertia follows the grid's), lagged by the first.
inline constexpr double kBusFrequencyLagsS[] = {0.2, 0.6, 2.0};
// ... with coefficients fitted above this high-pass's corner (20 s: 0.008 Hz), where a
// transducer's drift (tens of seconds) has little of its power and a grid's wander (seconds)
// most of its own: slow regressors fitted to the whole band take a drift by chance.
inline constexpr double kBusFrequencyHighPassS = 20.0;

// The frequency referred to the governor's input (bus_frequency.cpp refer_to_input): fitted
// in the band between a 20 s high-pass (a transducer's drift, as above) and two 0.53 s lags
// (0.3 Hz: below the governor's and the swing's own dynamics, where the grid's answer is the
// model's response to a droop's bias; on droopsim a = -49 to -50 % per Hz against the true
// -50 behind the grid's wander or an event, -30 to -40 where the wander is 4 mHz).
inline constexpr std::pair<double, double> kReferredBandS{20.0, 0.53};
// ... used only when a is a speed droop a set can have (2-10 %: diesel sets run 3-5 %; a
// larger a is the effect's own residual taken for the grid's) ...
inline constexpr std::pair<double, double> kReferredDroopPct{2.0, 10.0};
// ... measured to a tenth (z 10) ...
inline constexpr double kReferredMinZ = 10.0;
// ... and moving the governor's input by at least this share of the bias's rms: less, and
// an effect inside the loop sees nearly the bias alone either way.
inline constexpr double kReferredMinShare = 0.3;

}  // namespace rig::diagnose::thresholds
