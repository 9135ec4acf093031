#!/usr/bin/python3
"""The droopsim benchmark of `rig diagnose`: concealed cases from a third simulator (a
droop-governed set, written apart from gensim and plantsim), each judged detectable or not
by the oracle, diagnosed by the rig, scored with gensim's scoring rules.

    /usr/bin/python3 tests/bench/droopsim/run_bench.py --rig build/bin/rig --seed 1 \
        --out /tmp/droopsim-s1 [--quick] [--only EFFECT] [--reuse] [--rescore RESULTS.json]

Right (gensim's is_right): the verdict names the true effect; extra_lag and sensor_lag count
as one; hysteresis is right as backlash; a pair needs both, unless the oracle finds one of
its members undetectable beside the other (oracle.members): then it is scored as the single
of the detectable one, and the whole-pair count is printed beside the headline. Parameter errors and the tables
are gensim's (param_errors, tables), imported.
"""
import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cases as cs  # noqa: E402
import effects as fx  # noqa: E402
import oracle  # noqa: E402
import plant as pl  # noqa: E402

# gensim's scoring, loaded after droopsim's own cases/effects/oracle so that its
# `import cases, effects, oracle` resolve to these (is_right uses effects.lag_class, tables
# cases.CONCEALMENTS).
_spec = importlib.util.spec_from_file_location("gensim_run_bench",
                                               os.path.join(HERE, "..", "gensim", "run_bench.py"))
_grb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_grb)
is_right, param_errors, tables = _grb.is_right, _grb.param_errors, _grb.tables


def simulated_case(spec, d, reuse):
    cached = os.path.join(d, "oracle.json")
    if reuse and os.path.exists(cached):
        truth = json.load(open(os.path.join(d, "truth.json")))
        orc = json.load(open(cached))
        judged = "members" in orc or len(truth["truths"]) < 2
        if truth.get("seed") == spec["seed"] and truth.get("effect") == spec["effect"] and judged:
            add_bus_frequency(spec, d)
            return dict(truths=truth["truths"]), orc, 0.0
    case = cs.make_case(spec["id"], spec["effect"], spec["concealment"], spec["seed"])
    p, p_after, _ = oracle.plan(case)
    t0 = time.time()
    sim = pl.simulate(case["u"], p, seed=case["seed"], onset_s=case["onset_s"], p_after=p_after)
    orc = oracle.judge(case, sim["y"], cs.model_doc())
    cs.write_case(case, sim["y"][:, 0], sim["freq_hz"], d)
    with open(cached, "w") as f:
        json.dump(orc, f, default=float)
    return case, orc, time.time() - t0


def add_bus_frequency(spec, d):
    """A recording written before the bus frequency was recorded gets its column (the same
    draws: y is unchanged)."""
    with open(os.path.join(d, "recording.csv")) as f:
        if "freq_hz" in f.readline():
            return
    case = cs.make_case(spec["id"], spec["effect"], spec["concealment"], spec["seed"])
    y = np.loadtxt(os.path.join(d, "recording.csv"), delimiter=",", skiprows=1)[:, 2]
    cs.write_recording(case, y, pl.bus_frequency(len(y), case["p"], seed=case["seed"]), d)


def run_case(spec, rig, work, reuse=False, bus_frequency=True):
    d = os.path.join(work, spec["id"])
    case, orc, sim_s = simulated_case(spec, d, reuse)
    t0 = time.time()
    cmd = ["nice", "-n", "10", rig, "diagnose", "--recording", os.path.join(d, "recording.csv"),
           "--model", os.path.join(d, "model.json"), "--out", os.path.join(d, "diag"), "--force"]
    proc = subprocess.run(cmd + ([] if bus_frequency else ["--bus-frequency", "none"]),
                          capture_output=True, text=True)
    rig_s = time.time() - t0
    row = dict(spec, truths=case["truths"], oracle=orc, sim_s=round(sim_s, 1),
               rig_s=round(rig_s, 2), rc=proc.returncode,
               stderr=(proc.stderr or "").strip()[-600:])
    rep_path = os.path.join(d, "diag", "report.json")
    if proc.returncode != 0 or not os.path.exists(rep_path):
        row.update(verdict="error", error=((proc.stderr or "") + (proc.stdout or "")).strip()[-600:])
    else:
        rep = json.load(open(rep_path))
        row["verdict"] = rep["verdict"]
        ch = rep.get("chosen")
        h = rep["hypotheses"][ch] if ch is not None else None
        row["vfit_before"] = h["validation_fit_before"] if h else rep.get("validation_fit_before")
        row["vfit_after"] = h["validation_fit_after"] if h else None
        row["params"] = h["params"] if h else {}
        row["named"] = [e["effect"] for e in h.get("effects", [])] if h else []
        row["places"] = [e.get("place") for e in h.get("effects", [])] if h else []
        row["param_err_pct"] = param_errors(case, rep)
        row["elapsed_s"] = rep.get("elapsed_s")
    score(row)
    return row


def score(row):
    """right: gensim's is_right, except that a pair one of whose members the oracle finds
    undetectable (oracle.members) is scored as the single of its detectable member; the
    whole-pair rule is kept in right_whole_pair."""
    args = (row["verdict"], row["concealment"], row.get("named", ()))
    row["right_whole_pair"] = is_right(row["effect"], *args)
    det = [e for e, m in row["oracle"].get("members", {}).items() if m["detectable"]]
    single = len(det) == 1 and row["oracle"]["detectable"]
    row["right"] = row["right_whole_pair"] or single and is_right(det[0], *args)
    row["scored_as"] = det[0] if single else row["effect"]


def pair_members(rows):
    """The pairs scored on one member, and the count under the whole-pair rule."""
    det = [r for r in rows if r["effect"] != "none" and r["oracle"]["detectable"]]
    single = [r for r in det if r.get("scored_as", r["effect"]) != r["effect"]]
    print("\npairs with a member the oracle finds undetectable (scored on the other): " +
          (", ".join(f"{r['id']} {r['effect']} -> {r['scored_as']} ("
                     + " ".join(f"{e} {m['gain']:+.1f}" for e, m in r["oracle"]["members"].items())
                     + f") {'ok' if r['right'] else 'BAD'}" for r in single) or "none"))
    whole = sum(r["right_whole_pair"] for r in det)
    print(f"right where detectable with every pair needing both members: {whole}/{len(det)}")
    return whole


def wrong_list(rows):
    print("\nwrong where detectable (id, truth, concealment, oracle gain -> verdict [places], "
          "fit before -> after):")
    for r in rows:
        if r["effect"] != "none" and r["oracle"]["detectable"] and not r["right"] \
                or r["effect"] == "none" and not r["right"]:
            print(f"  {r['id']} {r['effect']:<32} {r['concealment']:<9} {r['oracle']['gain']:+6.1f}"
                  f" -> {r['verdict']} {r.get('places', '')} {r.get('vfit_before')} -> "
                  f"{r.get('vfit_after')}")
    und = [r for r in rows if r["effect"] != "none" and not r["oracle"]["detectable"]]
    print("undetectable (not counted): " + ", ".join(
        f"{r['id']} {r['effect']}/{r['concealment']} {r['oracle']['gain']:+.1f} -> {r['verdict']}"
        for r in und))
    errs = [r for r in rows if r["verdict"] == "error" or r.get("stderr")]
    for r in errs:
        print(f"  rig output {r['id']} (exit {r.get('rc')}): {r.get('error') or r.get('stderr')}")


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", required=True, help="the rig executable")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", help="only cases of this effect (or none)")
    ap.add_argument("--out", default="/tmp/droopsim-bench")
    ap.add_argument("--json", help="per-case results (default OUT/results.json)")
    ap.add_argument("--reuse", action="store_true", help="reuse recordings and oracle verdicts")
    ap.add_argument("--rescore", help="tabulate an earlier results.json, run nothing")
    ap.add_argument("--no-bus-frequency", action="store_true",
                    help="tell the rig not to use the recorded bus frequency (freq_hz)")
    a = ap.parse_args()
    if a.rescore:
        doc = json.load(open(a.rescore))
        for r in doc["cases"]:
            score(r)
        tables(doc["cases"], f"droopsim (seed {doc['seed']})")
        pair_members(doc["cases"])
        wrong_list(doc["cases"])
        return
    specs = cs.case_list(a.seed, quick=a.quick)
    if a.only:
        specs = [s for s in specs if a.only in s["effect"].split("+") or a.only == s["effect"]]
    chk = cs.model_doc()["source"]["check"]
    print(f"droopsim benchmark: seed {a.seed}, {len(specs)} cases of {cs.DURATION_S:.0f} s at "
          f"{1 / pl.DT:.0f} Hz, rig {a.rig}"
          f"{' told not to use the bus frequency' if a.no_bus_frequency else ''}; model order {chk['order']}, check "
          f"{chk['max_err_db']:.4f} dB {chk['max_err_deg']:.4f} deg; oracle: gain >= "
          f"{oracle.MIN_GAIN} points and F test p < {oracle.ALPHA}", flush=True)
    t_start = time.time()
    rows = []
    for spec in specs:
        r = run_case(spec, a.rig, a.out, a.reuse, not a.no_bus_frequency)
        o = r["oracle"]
        errs = " ".join(f"{k} {v:+.1f}%" for k, v in r.get("param_err_pct", {}).items())
        vb, va = r.get("vfit_before"), r.get("vfit_after")
        size = " ".join(f"{t['size']:.3g}" for t in r["truths"])
        print(f"  {r['id']} {r['effect']:<32} {size:<11} {r['concealment']:<9} oracle "
              f"{'det ' if o['detectable'] else 'UND '}{o['gain']:+6.1f} -> {r['verdict']:<28} "
              f"{'ok ' if r['right'] else 'BAD'} {errs:<22} vfit "
              f"{vb if vb is None else round(vb, 1)} -> {va if va is None else round(va, 1)} "
              f"({r['sim_s']:.0f}+{r['rig_s']:.1f} s)", flush=True)
        rows.append(r)
    summary = tables(rows, f"droopsim (seed {a.seed})")
    summary["right_whole_pair"] = pair_members(rows)
    wrong_list(rows)
    rs = sorted(r["rig_s"] for r in rows)
    print(f"\nrig diagnose time per case: median {rs[len(rs) // 2]:.1f} s, max {rs[-1]:.1f} s; "
          f"wall time {time.time() - t_start:.0f} s")
    path = a.json or os.path.join(a.out, "results.json")
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump(dict(seed=a.seed, quick=a.quick, summary=summary, cases=rows), f, indent=1,
                  default=float)
    print(f"per-case results: {path}")


if __name__ == "__main__":
    main()
