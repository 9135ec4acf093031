#!/usr/bin/python3
"""In what units does `rig diagnose` report a limit, a play or a slew rate after the
governor's PI, and do they match the simulator's own?

    /usr/bin/python3 tests/bench/droopsim/experiments/pi_units.py [--rc S] CASE_DIR [...]

CASE_DIR: a case folder of droopsim's or gensim's run_bench.py after the rig ran on it
(recording.csv, model.json, truth.json, diag/report.json). For a chosen rate_limit,
backlash, deadband or saturation at the `pi_loop` or `governor_pi` place it rebuilds the
place's signal a = C e the rig's way (e = u - h(z0 / G0), z0 the model's response to the
bias, C the fitted PI and output filter, h the fitted feedback: docs/diagnose.md,
"Placement") and prints the rig's value against the simulator's truth, with the value
rescaled to two other definitions of the bias-% equivalent:

  rms   k = std(u) / std(a) over the whole band
  hp    both rms above a first-order high-pass of RC seconds (--rc, default 2)

and the factor between them. It cannot tell which of the two the report used: give
--report-scale (rms or hp, default hp) for the rig that wrote diag/report.json. Simulators'
truths are in their own convention (droopsim and gensim alike: the plant's value over the
rack's rms per % of bias's rms). An experiment, not the product (docs/droopsim.md, "Units
after the PI").
"""
import argparse
import json
import os

import numpy as np
from scipy import signal

KEYS = {"rate_limit": "rate_limit_per_s", "backlash": "half_width", "deadband": "half_width",
        "saturation": "upper_limit"}


def rebuilt_signal(case_dir, e, u, t):
    m = json.load(open(os.path.join(case_dir, "model.json")))
    dt = t[1] - t[0]
    num, den = np.array(m["num"]), np.array(m["den"])
    g0 = num[-1] / den[-1]
    _, z, _ = signal.lsim((num, den), u, t)
    nd = int(round(m.get("delay_s", 0.0) / dt))
    z = np.concatenate([np.zeros(nd), z[:len(z) - nd]]) / g0
    p = e["params"]
    if e["place"] == "governor_pi":
        _, hz, _ = signal.lsim(([p["loop_derivative_s"], p["loop_static_share"]],
                                [p["loop_filter_s"], 1.0]), z, t)
    else:
        hz = z
    err = u - hz
    x = err + (dt / p["integral_time_s"]) * np.cumsum(err)
    q = np.exp(-dt / p["filter_lag_s"])
    return signal.lfilter([1 - q], [1, -q], x)


def high_pass(x, dt, rc):
    q = np.exp(-dt / rc)
    return signal.lfilter([q, -q], [1, -q], x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--rc", type=float, default=2.0, help="high-pass RC, s")
    ap.add_argument("--report-scale", choices=("rms", "hp"), default="hp")
    a = ap.parse_args()
    for d in a.cases:
        truth = json.load(open(os.path.join(d, "truth.json")))["truths"][0]
        rep = json.load(open(os.path.join(d, "diag", "report.json")))
        if rep.get("chosen") is None or truth["effect"] not in KEYS:
            continue
        key = KEYS[truth["effect"]]
        e = next((x for x in rep["hypotheses"][rep["chosen"]]["effects"]
                  if key in x["params"]), None)
        if e is None or e["place"] not in ("pi_loop", "governor_pi"):
            print(f"{os.path.basename(d)} {truth['effect']}: not after the PI")
            continue
        rec = np.genfromtxt(os.path.join(d, "recording.csv"), delimiter=",", names=True)
        t, u = rec["t"], rec["u"] - rec["u"].mean()
        sig = rebuilt_signal(d, e, u, t)
        dt = t[1] - t[0]
        k_rms = u.std() / sig.std()
        k_hp = high_pass(u, dt, a.rc).std() / high_pass(sig, dt, a.rc).std()
        got = e["params"][key]
        as_rms = got * (k_rms / k_hp if a.report_scale == "hp" else 1.0)
        as_hp = got * (k_hp / k_rms if a.report_scale == "rms" else 1.0)
        tv = truth["truth"]
        print(f"{os.path.basename(d)} {truth['effect']:<11} {e['place']:<12} truth {tv:.4g}  "
              f"rms {as_rms:.4g} ({100 * (as_rms / tv - 1):+.0f} %)  "
              f"hp {as_hp:.4g} ({100 * (as_hp / tv - 1):+.0f} %)  k_hp/k_rms {k_hp / k_rms:.2f}")


if __name__ == "__main__":
    main()
