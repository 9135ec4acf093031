// Effects from an onset (docs/diagnose.md, steps 3 and 4): a periodic disturbance that starts
// during the record is fitted from its onset, and a play from an onset is evidenced by the
// direction test on its own span, where the whole record's test dilutes it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/evidence.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;

// A line from half-way, a third of the output's rms: over the whole record a sinusoid of one
// amplitude fits it at a third of its size (droopsim seed 8 d062, a ripple from 100 s of 150,
// scored -0.11 points so); from its onset it is the line.
TEST(Onset, ALineFromHalfWayIsFittedFromItsOnset) {
  DiagnoseInput in = null_record(61);
  const Eigen::Index n = in.y.size(), half = n / 2;
  const double f_hz = 6.25, amplitude = 0.3 * rms(in.y);
  for (Eigen::Index k = half; k < n; ++k)
    in.y(k) +=
        amplitude * std::sin(2.0 * std::numbers::pi * f_hz * static_cast<double>(k) * in.dt_s);
  const DiagnoseResult r = diagnose(in, DiagnoseOptions{});
  ASSERT_EQ(r.verdict, "periodic_disturbance") << r.explanation;
  EXPECT_EQ(r.problem.active_from, 0);  // the record is not located in time: the line's own span
  const HypothesisFit& h = *r.chosen();
  const double half_s = static_cast<double>(half) * in.dt_s;
  EXPECT_NEAR(static_cast<double>(h.active_from) * in.dt_s, half_s, 0.1 * half_s);
  EXPECT_NEAR(h.effects[0].params[0], f_hz, 0.01 * f_hz);
}

// A play from half-way: the whole record's direction test (set here to a diluted z) leaves it
// without evidence and a gain change is named; on its own span the test shows it (gensim seed
// 5 g044, a hysteresis from 60 s of 120: |z| 2.7 over the record). Spanned over the whole
// record, the hypothesis has no span of its own and no second test.
TEST(Onset, APlayFromAnOnsetIsShownByTheDirectionTestOnItsSpan) {
  DiagnoseResult r;
  DiagnoseInput in = null_record(67);
  int blocks = 0;
  Eigen::Index warm = 0;
  r.problem = prepare_problem(in, &blocks, &warm);
  Problem& pr = r.problem;
  const Eigen::Index n = pr.y.size(), half = n / 2;
  const double width = 0.3 * rms(pr.u);
  const Eigen::VectorXd played = backlash(pr.u, width);
  pr.y.tail(n - half) +=
      (model::simulate(pr.tf, played, pr.dt_s) - model::simulate(pr.tf, pr.u, pr.dt_s))
          .tail(n - half);
  r.baseline_yhat = model_output(pr, {}).yhat;
  r.location = locate(pr, r.baseline_yhat);
  r.location.input_mismatch = true;
  r.location.amp.direction_z = 1.0;  // the whole record's test diluted
  HypothesisFit play, gain;
  play.effects = {AppliedEffect{Effect::kBacklash, {width}, Place::kInput, {}}};
  play.score = 5.0;
  play.active_from = half;
  play.active_to = pr.active_to;
  gain.effects = {AppliedEffect{Effect::kGainChange, {0.8}, Place::kInput, {}}};
  gain.score = 4.0;
  gain.active_from = pr.active_from;
  gain.active_to = pr.active_to;
  r.hypotheses = {play, gain};
  EXPECT_EQ(choose(r, thresholds::kMinGainPct), 1);  // no evidence on the record
  test_direction_on_spans(r);
  EXPECT_GE(std::abs(r.hypotheses[0].span_direction_z), thresholds::kDirectionEvidenceZ);
  EXPECT_EQ(choose(r, thresholds::kMinGainPct), 0);
  r.hypotheses[0].active_from = pr.active_from;  // no span of its own: no second test
  r.hypotheses[0].span_direction_z = 0.0;
  test_direction_on_spans(r);
  EXPECT_EQ(r.hypotheses[0].span_direction_z, 0.0);
  EXPECT_EQ(choose(r, thresholds::kMinGainPct), 1);
}

}  // namespace
}  // namespace rig::diagnose
