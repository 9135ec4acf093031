#!/usr/bin/python3
"""`rig diagnose` on a few concealed cases from gensim (tests/bench/gensim), the genset
simulator written apart from plantsim: each case is simulated from its seed, diagnosed by
the rig binary, and judged against gensim's own truth.

    RIG_BIN_DIR=build/bin /usr/bin/python3 tests/integration/diagnose/gensim_cases_test.py

The full benchmark (83 cases per seed, with the oracle) is tests/bench/gensim/run_bench.py;
these are the cases that pin a fixed behaviour:
  * an actuator slew limit behind a 12 kW transducer drift (benchmark seed 1, g022): its
    pair with the drift must start from the limit's own seeds, not only from its single's
    fit made without the drift (which stopped at a 2 s front lag and was out-scored by a
    damping change);
  * an actuator hysteresis (Bouc-Wen, gensim's form) behind the transducer's declared AC
    coupling (benchmark seed 2, g043): only after the governor's PI, where the loop's
    integrator keeps working against it, does it fit better than a rack limit on the bias;
  * a rack stop behind the grid's wander (benchmark seed 1, g074), which the input tests
    miss behind it: found by pairing the input-side effects with the dominant drift, after
    the governor's PI with its integrator held at the stop;
  * a rack stop behind a 20 kW drift (seed 5, g027) whose input tests failed while the
    drift alone scores most: paired with the drift (a drift does not explain a failed input
    test), `saturation`;
  * a shaft mode that moved half-way (seed 4, g054), which no input test sees: found by the
    blind search of every input-side effect, named by what it adds;
  * an undeclared AC coupling of the transducer behind a drift (benchmark seed 4, g070) and
    a small one (seed 6, g069), which the frequency and cross-correlation tests miss: found
    by the coupling test (the residual follows the model's output through the coupling's
    low-pass);
  * a combustion lag (seed 4, g005) whose best Bouc-Wen stand-in stops at its most rounded
    shape: a lag, not a loop;
  * a combustion lag (seed 6, g005) that fits best inside the governor's loop with the
    loop's feedback at its bound: a lag, not a play after the PI;
  * a fuel dead time (benchmark seed 1, g000): a linear effect, as a guard;
  * a transducer gain change half-way (seed 5, g019), whose level step the response after
    it agrees with, though by less than 5 sd from no change: `gain_change`, not a load step;
  * a transducer drift under 0.2 % of the level that raises the fit by 20 points (seed 6,
    g065): `drift`, not the set's operating noise;
  * a null case with the set's operating nuisances (benchmark seed 1, g082): `none`;
  * a transducer's 8 % gain error on a 600 s record (seed 3's g015 at ten minutes), where
    the grid's wander keeps the fit's gain under the verdict's 0.2 points: named all the
    same, its residual no longer correlated with the input.
"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench", "gensim"))
import cases as cs  # noqa: E402
import genset as g  # noqa: E402

PARAM_TOL = 0.20  # the "parameter within 20 %"


def rig() -> str:
    return os.path.join(os.environ.get("RIG_BIN_DIR", "build/bin"), "rig")


def diagnose_case(effect, size, concealment, seed, work):
    """Simulates the case into work/case, runs rig diagnose, returns (truths, report)."""
    case = cs.make_case("test", effect, size, concealment, seed)
    sim = g.simulate(case["u"], case["p"], seed=case["seed"], onset_s=case["onset_s"],
                     p_after=case["p_after"])
    d = os.path.join(work, "case")
    cs.write_case(case, sim["y"][:, 0], d)
    out = os.path.join(work, "diag")
    proc = subprocess.run([rig(), "diagnose", "--recording", os.path.join(d, "recording.csv"),
                           "--model", os.path.join(d, "model.json"), "--out", out],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise AssertionError(f"rig diagnose exit {proc.returncode}: {proc.stderr.strip()}")
    with open(os.path.join(out, "report.json")) as f:
        rep = json.load(f)
    rep["test_y_mean"] = float(sim["y"][:, 0].mean())  # the recording's operating level
    return case["truths"], rep


class GensimCases(unittest.TestCase):
    def run_case(self, *args):
        with tempfile.TemporaryDirectory() as work:
            truths, rep = diagnose_case(*args, work)
        seed = args[3]
        print(f"{args[0]} {args[2]} seed {seed}: verdict {rep['verdict']}", flush=True)
        return truths, rep, seed

    def test_slew_limit_behind_a_drift_is_a_rate_limit_in_the_loop(self):
        truths, rep, seed = self.run_case("rate_limit", "large", "drift", 837884)
        self.assertEqual(rep["verdict"], "rate_limit", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        limit = next(e for e in h["effects"] if e["effect"] == "rate_limit")
        self.assertIn(limit["place"], ("in_loop", "pi_loop"), rep["explanation"])
        self.assertIn("drift", [e["effect"] for e in h["effects"]], rep["explanation"])
        truth = truths[0]["truth"]
        got = limit["params"]["rate_limit_per_s"]
        self.assertLess(abs(got - truth) / truth, PARAM_TOL, f"seed {seed}: {got} vs {truth}")
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_an_actuator_hysteresis_behind_a_coupling_sits_after_the_pi(self):
        _, rep, seed = self.run_case("hysteresis", "large", "coupled", 511066)
        self.assertEqual(rep["verdict"], "hysteresis", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertEqual(h["effects"][0]["place"], "pi_loop", rep["explanation"])
        self.assertIn("after the governor's PI", rep["explanation"])
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_a_rack_stop_behind_the_grids_wander_is_found_by_its_fit(self):
        _, rep, seed = self.run_case("saturation+drift", "large", "pair", 718527)
        self.assertEqual(rep["verdict"], "saturation", f"seed {seed}: {rep['explanation']}")
        self.assertFalse(rep["location"]["input_mismatch"], rep["explanation"])
        h = rep["hypotheses"][rep["chosen"]]
        self.assertEqual([e["effect"] for e in h["effects"]], ["saturation", "drift"])
        self.assertIn("found no mismatch beside the disturbance", rep["explanation"])
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_a_rack_stop_behind_a_drift_the_input_tests_saw_is_paired_with_it(self):
        # Seed 5 g027: the input tests fail, the drift alone scores most and its residual
        # passes the cross-correlation test; a drift does not explain a failed input test,
        # so the input-side effects are paired with it (the map at the output alone was
        # named before, no pair having been fitted).
        _, rep, seed = self.run_case("saturation", "large", "drift", 974186)
        self.assertTrue(rep["location"]["input_mismatch"], rep["explanation"])
        best = next(h for h in rep["hypotheses"] if len(h["effects"]) == 1)
        self.assertEqual([e["effect"] for e in best["effects"]], ["drift"], best)
        self.assertEqual(rep["verdict"], "saturation", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertIn("drift", [e["effect"] for e in h["effects"]], rep["explanation"])
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_a_moved_mode_no_input_test_sees_is_found_by_the_blind_search(self):
        _, rep, seed = self.run_case("resonance", "large", "partial", 364132)
        self.assertFalse(rep["location"]["input_mismatch"], rep["explanation"])
        self.assertEqual(rep["verdict"], "resonance", f"seed {seed}: {rep['explanation']}")
        self.assertIn("fitted all the same", rep["explanation"])
        h = rep["hypotheses"][rep["chosen"]]
        self.assertGreaterEqual(h["score"], 3.0, rep["explanation"])

    def test_undeclared_couplings_are_found_by_the_coupling_test(self):
        # Behind a drift (seed 4 g070, RC 4 s; the drift test does not fire beside it) and
        # small (seed 6 g069, RC 15 s, about 2 points of fit): the residual follows the
        # model's output through the coupling's low-pass with the coefficient -1 it gives,
        # where the frequency and cross-correlation tests see nothing.
        for args in (("ac_coupling", "large", "drift", 996512),
                     ("ac_coupling", "small", "small", 454136)):
            _, rep, seed = self.run_case(*args)
            c = rep["location"]["coupling"]
            self.assertTrue(c["fires"], f"seed {seed}: {c}")
            self.assertLess(abs(c["coefficient"] + 1.0), 3.0 * c["coefficient_sd"], c)
            self.assertTrue(rep["location"]["input_mismatch"], rep["explanation"])
            self.assertEqual(rep["verdict"], "ac_coupling", f"seed {seed}: {rep['explanation']}")
            self.assertIn("as an AC coupling of the output leaves it", rep["explanation"])
            h = rep["hypotheses"][rep["chosen"]]
            self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_a_combustion_lag_is_a_lag_not_a_rounded_loop(self):
        _, rep, seed = self.run_case("extra_lag", "large", "plain", 976243)
        self.assertIn(rep["verdict"], ("extra_lag", "sensor_lag"),
                      f"seed {seed}: {rep['explanation']}")

    def test_a_combustion_lag_is_not_a_play_where_the_loop_lag_stops_at_its_bound(self):
        # Seed 6's g005: the 90 ms lag fits best inside the governor's loop, but there its
        # feedback's static share stops at the bound of 2; a play after the PI then beat the
        # lag at the input by 1.4 points, without a level or direction effect of its own, and
        # was named `backlash`.
        truths, rep, seed = self.run_case("extra_lag", "large", "plain", 369067)
        self.assertIn(rep["verdict"], ("extra_lag", "sensor_lag"),
                      f"seed {seed}: {rep['explanation']}")
        loop = next(h for h in rep["hypotheses"]
                    if [(e["effect"], e["place"]) for e in h["effects"]]
                    == [("extra_lag", "governor_loop")])
        play = next(h for h in rep["hypotheses"] if h["effects"][0]["effect"] == "backlash")
        self.assertGreaterEqual(loop["params"]["loop_static_share"], 0.98 * 2.0,
                                "the loop's lag no longer stops at its bound: not this case")
        self.assertGreater(loop["score"], play["score"], "not the case of this test")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])
        got = h["effects"][0]["params"]["time_constant_s"]
        self.assertLess(abs(got / truths[0]["truth"] - 1.0), PARAM_TOL, rep["explanation"])

    def test_damper_windings_beside_a_transducer_lag_are_named_as_the_pair(self):
        # Seed 7's g075: the best single is a resonance at its damping bound (the swing mode
        # re-damped and a broad mode standing in for the lag), which no verdict names; it
        # explained the residual, so no pair was searched, and the lag alone was named. The
        # forward pair then put the lag in the governor's loop at its feedback's bound.
        truths, rep, seed = self.run_case("load_damping+sensor_lag", "large", "pair", 3735)
        h = rep["hypotheses"][rep["chosen"]]
        named = sorted("lag" if e["effect"] in ("extra_lag", "sensor_lag") else e["effect"]
                       for e in h["effects"])
        self.assertEqual(named, ["lag", "load_damping"], f"seed {seed}: {rep['explanation']}")
        top = rep["hypotheses"][0]
        if len(top["effects"]) == 1:  # the stand-in, if no pair beat it
            self.assertEqual(top["effects"][0]["effect"], "resonance", "not the case of this test")
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])
        for t in truths:
            e = next(e for e in h["effects"]
                     if ("lag" if e["effect"].endswith("_lag") else e["effect"])
                     == ("lag" if t["effect"].endswith("_lag") else t["effect"]))
            got = e["params"][t["rig_param"]]
            self.assertLess(abs(got / t["truth"] - 1.0), PARAM_TOL,
                            f"{t['effect']}: {got} vs {t['truth']}; {rep['explanation']}")

    def test_a_longer_fuel_dead_time_is_a_dead_time(self):
        truths, rep, seed = self.run_case("dead_time", "large", "plain", 473189)
        self.assertEqual(rep["verdict"], "dead_time", f"seed {seed}: {rep['explanation']}")

    def test_a_transducer_gain_error_on_a_ten_minute_record_is_named(self):
        # Seed 3's g015 simulated at 600 s: the grid's wander dominates the residual, and the
        # 8 % gain error adds 0.4 points of fit, a score under the 0.2 asked after its
        # penalty, while the residual's correlation with the input, 5 times its bound before,
        # is within it after (`unexplained` before).
        saved = cs.DURATION_S
        cs.DURATION_S = 600.0
        try:
            truths, rep, seed = self.run_case("gain_change", "large", "plain", 159739)
        finally:
            cs.DURATION_S = saved
        self.assertTrue(rep["location"]["input_mismatch"], rep["explanation"])
        self.assertEqual(rep["verdict"], "gain_change", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertLess(h["score"], 0.2, rep["explanation"])
        self.assertIn("no longer correlated with the input", rep["explanation"])
        got = h["effects"][0]["params"]["gain_ratio"]
        self.assertLess(abs(got / truths[0]["truth"] - 1.0), PARAM_TOL, rep["explanation"])

    def test_a_transducer_gain_change_half_way_is_told_from_a_load_step(self):
        # Seed 7's g019: the CT ratio x0.92 from 60 s steps the level by -8 %; the response
        # after the step is x0.942 +- 0.018 of that before (z = -3.2, under the bound of 5;
        # the sd was 0.029 before the fit whitened the residual), 73 times likelier as the
        # level's change than as none. The gain raises the validation fit by 0.25 points,
        # its parameter's cost: the level's step fixed it (`unexplained`, and `none` before).
        truths, rep, seed = self.run_case("gain_change", "large", "partial", 467935)
        sg = rep["location"]["level_shift"]["step_gain"]
        self.assertTrue(sg["fires"], rep["explanation"])
        self.assertLess(abs(sg["z"]), 5.0, "no longer the case this test is about")
        self.assertEqual(rep["verdict"], "gain_change", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])
        self.assertIn("the level's step fixed its value", rep["explanation"])
        got = h["effects"][0]["params"]["gain_ratio"]
        self.assertLess(abs(got / truths[0]["truth"] - 1.0), PARAM_TOL, rep["explanation"])

    def test_a_rack_stop_from_half_way_behind_a_drift_is_found_from_its_onset(self):
        # Seed 7's g029: a rack stop from 60 s behind the record's drift. Over the whole
        # record the stop beside the drift adds 1.6 points to the drift alone (3 asked);
        # gated from the onset its own gain per window shows over the drift's, 3.1.
        _, rep, seed = self.run_case("saturation", "large", "partial", 504548)
        self.assertFalse(rep["location"]["input_mismatch"], rep["explanation"])
        self.assertEqual(rep["verdict"], "saturation", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertEqual([e["effect"] for e in h["effects"]], ["saturation", "drift"])
        self.assertTrue(50.0 < h["active_span_s"][0] < 75.0, h["active_span_s"])
        self.assertGreater(h["validation_fit_after"], h["validation_fit_before"])

    def test_a_drift_within_the_transducers_accuracy_that_the_fit_shows_is_named(self):
        # Seed 6's g065: a 20 kW, 60 s transducer zero drift whose 120 s realisation stays
        # under 0.2 % of the level (once `none`: the set's operating noise), yet modelling it
        # raises the validation fit by about 20 points, 10 or more being asked.
        _, rep, seed = self.run_case("drift", "large", "plain", 418054)
        self.assertEqual(rep["verdict"], "drift", f"seed {seed}: {rep['explanation']}")
        h = rep["hypotheses"][rep["chosen"]]
        self.assertGreaterEqual(h["validation_fit_after"] - h["validation_fit_before"], 10.0)
        worst_half = h["derived"]["drift_rms_worst_half"]
        self.assertLess(worst_half, 0.002 * abs(rep["test_y_mean"]),
                        "no longer within the transducer's accuracy: not the case of this test")

    def test_operating_nuisances_alone_are_none(self):
        _, rep, seed = self.run_case("none", "large", "nuisances", 770071)
        self.assertEqual(rep["verdict"], "none", f"seed {seed}: {rep['explanation']}")


if __name__ == "__main__":
    unittest.main(verbosity=2)
