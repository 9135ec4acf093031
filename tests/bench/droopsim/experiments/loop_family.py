#!/usr/bin/python3
"""Which form of a linear change inside the governor's loop fits a droopsim case, knowing only
the model handed over (the closed loop G, bias -> power)?

    /usr/bin/python3 tests/bench/droopsim/experiments/loop_family.py CASE_DIR [CASE_DIR ...]

CASE_DIR: a case folder of run_bench.py or cases.py (recording.csv, recording.json,
model.json, truth.json, oracle.json when judged). For each, the validation gain (points, the
rig's scoring: warm-up, 8 blocks, even estimate / odd validate, offset fitted) of:

  series_lag     G / (1 + s T)                       (extra_lag at the input, as the rig has it)
  series_delay   G e^{-s tau} (Pade 3/3)             (dead_time at the input)
  loop_unity     G F / (1 - G' (1 - F))              F = 1/(1 + s T), G' = G / G0: the lag
                                                     inside a unity power loop (the rig's
                                                     `error` place's form, made linear)
  lag_in_loop    G F / (1 - G' h (1 - F))            h = (a + b s T_h) / (1 + s T_h): the loop's
                                                     feedback fitted, a static share (power
                                                     feedback, a PI on power) and a derivative
                                                     share (speed feedback, a droop governor)
  delay_in_loop  the same with F = e^{-s tau} (Pade 3/3)

The model's own dead time stays outside the loop. The rig's figures for the same case are in
CASE_DIR/diag/report.json when run_bench.py ran it. An experiment, not the product: it says
whether the fitted loop is worth building into `rig diagnose` (docs/droopsim.md).
"""
import json
import math
import os
import sys
import warnings

import numpy as np
from scipy import optimize, signal
from scipy.interpolate import pade

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import oracle  # noqa: E402


def load(d):
    m = json.load(open(os.path.join(d, "model.json")))
    rec = np.loadtxt(os.path.join(d, "recording.csv"), delimiter=",", skiprows=1)
    side = json.load(open(os.path.join(d, "recording.json")))
    return m, rec[:, 0], rec[:, 1], rec[:, 2], side.get("coupling_rc_s"), side


def simulator(t, u, delay, rc):
    dt = t[1] - t[0]
    n = len(u)
    # The delayed input, linearly interpolated (first-order hold), zero before the start.
    ud = np.interp(np.arange(n) * dt - delay, np.arange(n) * dt, u - u.mean(), left=0.0)
    if rc:
        cn, cd, _ = signal.cont2discrete(([rc, 0.0], [rc, 1.0]), dt, method="foh")
        cn, cd = np.squeeze(cn), np.squeeze(cd)

    def sim(num, den):
        nd, dd, _ = signal.cont2discrete((num, den), dt, method="foh")
        z = signal.lfilter(np.squeeze(nd), np.squeeze(dd), ud)
        return signal.lfilter(cn, cd, z) if rc else z
    return sim


def pade_delay(tau, order=3):
    c = [(-tau) ** k / math.factorial(k) for k in range(2 * order + 1)]
    with warnings.catch_warnings():  # ill-conditioned for a delay of a fraction of a ms
        warnings.simplefilter("ignore")
        p, q = pade(c, order)
    return np.array(p.coeffs) / q.coeffs[-1], np.array(q.coeffs) / q.coeffs[-1]


def forms(num, den):
    g0 = num[-1] / den[-1]

    def loop(nf, df, nh, dh):
        # G F / (1 - G' h (1 - F)) = N nf G0 dh / (G0 D df dh - N nh (df - nf))
        nn = g0 * np.polymul(num, np.polymul(nf, dh))
        dd = np.polysub(g0 * np.polymul(den, np.polymul(df, dh)),
                        np.polymul(num, np.polymul(nh, np.polysub(df, nf))))
        return nn, dd

    def lag(t_s):
        return np.array([1.0]), np.array([t_s, 1.0])

    def fitted_h(p):
        a, b, t_h = p
        return np.array([b * t_h, a]), np.array([t_h, 1.0])

    hs = [[1.0, 0.0, 0.1], [0.0, 1.5, 0.04], [1.0, 0.0, 0.01]]
    return {
        "series_lag": (lambda p: (num, np.polymul(den, [p[0], 1.0])), [[0.02], [0.05]],
                       [0.001], [1.0]),
        "series_delay": (lambda p: (np.polymul(num, pade_delay(p[0])[0]),
                                    np.polymul(den, pade_delay(p[0])[1])),
                         [[0.01], [0.03]], [0.0005], [0.3]),
        "loop_unity": (lambda p: loop(*lag(p[0]), [1.0], [1.0]), [[0.02], [0.05]], [0.001],
                       [1.0]),
        "lag_in_loop": (lambda p: loop(*lag(p[0]), *fitted_h(p[1:])),
                        [[0.03] + h for h in hs], [0.001, -0.5, -5.0, 0.005],
                        [1.0, 2.0, 5.0, 2.0]),
        "delay_in_loop": (lambda p: loop(*pade_delay(p[0]), *fitted_h(p[1:])),
                          [[0.02] + h for h in hs], [0.0005, -0.5, -5.0, 0.005],
                          [0.3, 2.0, 5.0, 2.0]),
    }


def run(d):
    m, t, u, y, rc, _ = load(d)
    num, den = np.array(m["num"], float), np.array(m["den"], float)
    sim = simulator(t, u, m["delay_s"], rc)
    est, val = oracle.blocks(len(y), m)

    def val_fit(z):
        return oracle._fit(y, z, est, val)[1]

    def resid(form, p):
        z = sim(*form(p))
        return (y - z - np.mean((y - z)[est]))[est]

    base = val_fit(sim(num, den))
    truth = json.load(open(os.path.join(d, "truth.json")))
    orc = os.path.join(d, "oracle.json")
    gain = json.load(open(orc)).get("gain") if os.path.exists(orc) else None
    print(f"== {d}: {truth['effect']} ({truth.get('concealment')}), truth "
          f"{[x.get('truth') for x in truth['truths']]}, oracle gain {gain}")
    for name, (form, starts, lo, hi) in forms(num, den).items():
        best = None
        for s in starts:
            try:
                r = optimize.least_squares(lambda q: resid(form, q), s, bounds=(lo, hi),
                                           diff_step=1e-3)
            except (ValueError, np.linalg.LinAlgError):
                continue
            if best is None or r.cost < best.cost:
                best = r
        if best is None:
            print(f"  {name:14s} failed")
            continue
        g = val_fit(sim(*form(best.x))) - base
        print(f"  {name:14s} {np.array2string(best.x, precision=4):40s} gain {g:6.2f} points "
              f"(score {g - 0.25 * len(best.x):6.2f})")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for case_dir in sys.argv[1:]:
        run(case_dir)
