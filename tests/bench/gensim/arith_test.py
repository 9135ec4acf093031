#!/usr/bin/python3
"""gensim's two arithmetics (arith.py) give the same record: a single parameter set steps in
plain floats, a batch in numpy columns (the oracle's grids). Each case is simulated alone
and as both columns of a two-column batch (the batch's columns carry the same parameters as
arrays; and alone with every parameter a one-element array); the records must agree: the
rack within 1e-9 pu, y (quantised to 0.5 kW) equal on every row. Covers the governor's
deadband, the Bouc-Wen hysteresis, the linkage play and the slew limit from an onset (the
parameter switch), the torque ripple and the AC coupling.

    /usr/bin/python3 tests/bench/gensim/arith_test.py
"""
import os
import sys
import time
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases as cs  # noqa: E402
import genset as g  # noqa: E402

ROWS = 1200           # 12 s of record after 1 s of settling
BATCHED = ("kp", "d_g")  # made per-column arrays: the record is then stepped in numpy


def as_batch(p):
    return dict(p, **{k: np.array([p[k], p[k]]) for k in BATCHED}) if p else p


class Arithmetic(unittest.TestCase):
    def check(self, effect, concealment, seed):
        case = cs.make_case("t", effect, "large", concealment, seed)
        onset = 6.0 if case["onset_s"] is not None else None  # inside the short record
        kw = dict(seed=case["seed"], onset_s=onset, settle_s=1.0)
        u = case["u"][:ROWS]
        t0 = time.time()
        one = g.simulate(u, case["p"], p_after=case["p_after"], **kw)
        t1 = time.time()
        two = g.simulate(u, as_batch(case["p"]), p_after=as_batch(case["p_after"]), **kw)
        t2 = time.time()
        print(f"{effect} {concealment}: floats {t1 - t0:.2f} s, numpy columns {t2 - t1:.2f} s",
              flush=True)
        for col in range(2):
            self.assertLess(np.max(np.abs(one["rack"][:, 0] - two["rack"][:, col])), 1e-9)
            self.assertLess(np.max(np.abs(one["pe"][:, 0] - two["pe"][:, col])), 1e-9)
            np.testing.assert_array_equal(one["y"][:, 0], two["y"][:, col])
        self.assertGreater(np.std(one["y"]), 1.0)  # the record moves
        # every parameter a one-element array: still a single set, stepped in floats
        arrays = {k: np.array([v]) for k, v in case["p"].items() if not isinstance(v, str)}
        alone = g.simulate(u, dict(case["p"], **arrays), p_after=case["p_after"], **kw)
        np.testing.assert_array_equal(one["y"], alone["y"])

    def test_governor_deadband(self):
        self.check("deadband", "plain", 13)

    def test_bouc_wen_hysteresis(self):
        self.check("hysteresis", "plain", 11)

    def test_linkage_play_from_an_onset(self):
        self.check("backlash", "partial", 12)

    def test_slew_limit_from_an_onset(self):
        self.check("rate_limit", "partial", 14)

    def test_torque_ripple(self):
        self.check("periodic_disturbance", "plain", 16)

    def test_ac_coupling(self):
        self.check("ac_coupling", "plain", 15)


if __name__ == "__main__":
    unittest.main()
