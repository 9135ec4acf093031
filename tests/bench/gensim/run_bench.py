#!/usr/bin/python3
"""The gensim benchmark of `rig diagnose`: concealed cases from a simulator written apart
from plantsim, each judged detectable or not by the oracle, diagnosed by the rig, scored.

    /usr/bin/python3 tests/bench/gensim/run_bench.py --rig build/bin/rig [--seed 1]
        [--quick] [--plant-bench build/bin/bench_diagnose_plant] [--plant-seeds 2]
        [--out DIR] [--json results.json] [--excitation prbs]

Prints every case (id, truth, concealment, oracle, verdict, parameter error, validation fit),
the confusion matrix per effect and per concealment, the share right among detectable
cases, the null rate, the parameter within 20 %, the fit improvement; writes per-case JSON.
With --plant-bench the plantsim benchmark runs too and its cases get the same tables
(plantsim has no oracle: every case counts as detectable there).

Right: the verdict names the true effect (extra_lag and sensor_lag count as one, as in the
plantsim benchmark; hysteresis is also right as backlash, the vocabulary's nearest fitted
word); a pair when the chosen hypothesis holds both and nothing else (a pair's verdict names
its input-side effect only); `effect+drift` is right behind the drift concealment (the drift
is really there).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases as cs  # noqa: E402
import effects as fx  # noqa: E402
import genset as g  # noqa: E402
import oracle  # noqa: E402

PARAM_TOL_PCT = 20.0


def norm(name):
    return fx.lag_class(name)


DISTURBANCE_WORDS = ("drift", "periodic_disturbance")


def is_right(truth_effect, verdict, concealment, named=()):
    """named: the chosen hypothesis's effects (a pair's verdict names its input-side effect
    only, "the disturbance listed with it"): a pair is scored on them, a single on the verdict
    as in the plantsim benchmark."""
    if truth_effect == "none":
        return verdict == "none"
    want = {norm(e) for e in truth_effect.split("+")}
    got = {norm(e) for e in verdict.split("+")}
    if len(want) > 1 and verdict in named:   # a disturbance listed beside a pair, as a single's
        got = {norm(e) for e in named if norm(e) in want or e not in DISTURBANCE_WORDS}
    if concealment == "drift" and "drift" not in want:
        got.discard("drift")
    if "hysteresis" in want and "backlash" in got:
        got = (got - {"backlash"}) | {"hysteresis"}
    return got == want


def param_errors(case, report):
    """Error (%) of the rig's parameter of each true effect its verdict names, where
    comparable (a chosen pair may carry an effect the verdict does not name)."""
    out = {}
    ch = report.get("chosen")
    if ch is None:
        return out
    hyp = report["hypotheses"][ch]
    named = {norm(v) for v in report["verdict"].split("+")}
    if len(case["truths"]) > 1:
        named |= {norm(e["effect"]) for e in hyp.get("effects", [])}
    for t in case["truths"]:
        if t["truth"] is None or norm(t["effect"]) not in named:
            continue
        for e in hyp.get("effects", []):
            if norm(e["effect"]) == norm(t["effect"]) and t["rig_param"] in e["params"]:
                out[t["effect"]] = 100.0 * (e["params"][t["rig_param"]] - t["truth"]) / t["truth"]
    return out


def simulated_case(spec, d, reuse, excitation="gaussian"):
    """The case's recording in d and its oracle verdict: simulated, or with reuse read back
    from an earlier run's d (the same case list: same --seed)."""
    cached = os.path.join(d, "oracle.json")
    if reuse and os.path.exists(cached):
        truth = json.load(open(os.path.join(d, "truth.json")))
        if (truth.get("seed") == spec["seed"] and truth.get("effect") == spec["effect"]
                and truth.get("excitation", "gaussian") == excitation):
            return dict(truths=truth["truths"]), json.load(open(cached)), 0.0
    case = cs.make_case(spec["id"], spec["effect"], spec["size"], spec["concealment"], spec["seed"],
                        excitation)
    p, p_after, _ = oracle.plan(case)
    t0 = time.time()
    sim = g.simulate(case["u"], p, seed=case["seed"], onset_s=case["onset_s"], p_after=p_after)
    orc = oracle.judge(case, sim["y"])
    sim_s = time.time() - t0
    cs.write_case(case, sim["y"][:, 0], d)
    with open(cached, "w") as f:
        json.dump(orc, f, default=float)
    return case, orc, sim_s


def run_case(spec, rig, work, reuse=False, excitation="gaussian"):
    d = os.path.join(work, spec["id"])
    case, orc, sim_s = simulated_case(spec, d, reuse, excitation)
    t0 = time.time()
    proc = subprocess.run(["nice", "-n", "10", rig, "diagnose", "--recording",
                           os.path.join(d, "recording.csv"), "--model",
                           os.path.join(d, "model.json"), "--out", os.path.join(d, "diag"),
                           "--force"], capture_output=True, text=True)
    rig_s = time.time() - t0
    row = dict(spec, truths=case["truths"], oracle=orc, sim_s=round(sim_s, 1),
               rig_s=round(rig_s, 2))
    if proc.returncode != 0:
        row.update(verdict="error", error=(proc.stderr or proc.stdout).strip()[-300:])
    else:
        rep = json.load(open(os.path.join(d, "diag", "report.json")))
        row["verdict"] = rep["verdict"]
        ch = rep.get("chosen")
        h = rep["hypotheses"][ch] if ch is not None else None
        row["vfit_before"] = h["validation_fit_before"] if h else rep.get("validation_fit_before")
        row["vfit_after"] = h["validation_fit_after"] if h else None
        row["params"] = h["params"] if h else {}
        row["named"] = [e["effect"] for e in h.get("effects", [])] if h else []
        row["param_err_pct"] = param_errors(case, rep)
    row["right"] = is_right(spec["effect"], row["verdict"], spec["concealment"],
                            row.get("named", ()))
    return row


PLANT_LINE = re.compile(r"^\s+(\S+)\s+seed\s+(\d+)\s+(\S+)\s+->\s+(\S+)\s+(ok |BAD)\s+truth\s+(\S+)"
                        r"\s+err\s+(\S+)\s+%\s+vfit\s+(\S+)\s+->\s+(\S+)\s+%")


def plant_rows(text):
    rows = []
    for line in text.splitlines():
        m = PLANT_LINE.match(line)
        if not m:
            continue
        eff, seed, con, verdict, ok, _, err, vb, va = m.groups()
        err = float(err)
        rows.append(dict(id=f"p{len(rows):03d}", effect=eff, concealment=con, seed=int(seed),
                         verdict=verdict, right=ok.strip() == "ok",
                         oracle=dict(detectable=eff != "none"),
                         param_err_pct={} if np.isnan(err) else {eff: err},
                         vfit_before=float(vb), vfit_after=float(va)))
    return rows


def tables(rows, title):
    print(f"\n== {title}: {len(rows)} cases ==")
    eff_rows = [r for r in rows if r["effect"] != "none"]
    nulls = [r for r in rows if r["effect"] == "none"]
    print("confusion per effect (true effect: right/detectable of total | verdicts; "
          "* = judged undetectable by the oracle):")
    for eff in sorted({r["effect"] for r in rows}):
        rs = [r for r in rows if r["effect"] == eff]
        det = [r for r in rs if r["oracle"]["detectable"] or eff == "none"]
        counts = {}
        for r in rs:
            key = r["verdict"] + ("" if r["oracle"]["detectable"] or eff == "none" else "*")
            counts[key] = counts.get(key, 0) + 1
        print(f"  {eff:<38} {sum(r['right'] for r in det):>2}/{len(det):<2} of {len(rs):<2} | "
              + " ".join(f"{k}:{v}" for k, v in sorted(counts.items())))
    print("per concealment (right/detectable of total; verdict kinds among the wrong):")
    for con in sorted({r["concealment"] for r in rows}):
        rs = [r for r in eff_rows if r["concealment"] == con]
        if not rs:
            continue
        det = [r for r in rs if r["oracle"]["detectable"]]
        wrong = [r for r in det if not r["right"]]
        kinds = {"none": 0, "unexplained": 0, "other effect": 0}
        for r in wrong:
            kinds[r["verdict"] if r["verdict"] in ("none", "unexplained") else "other effect"] += 1
        print(f"  {con:<10} {sum(r['right'] for r in det):>2}/{len(det):<2} of {len(rs):<2} | "
              + " ".join(f"{k}:{v}" for k, v in kinds.items()))
    cons = [c for c in cs.CONCEALMENTS + ("pair",) if any(r["concealment"] == c for r in rows)]
    cons += sorted({r["concealment"] for r in eff_rows} - set(cons))
    print("effect x concealment (right/detectable; '.' none detectable, blank: no case):")
    print(" " * 40 + "".join(f"{c[:9]:>10}" for c in cons))
    for eff in sorted({r["effect"] for r in eff_rows}):
        cells = []
        for c in cons:
            rs = [r for r in eff_rows if r["effect"] == eff and r["concealment"] == c]
            det = [r for r in rs if r["oracle"]["detectable"]]
            cells.append("" if not rs else "." if not det else
                         f"{sum(r['right'] for r in det)}/{len(det)}")
        print(f"  {eff:<38}" + "".join(f"{x:>10}" for x in cells))
    for con in sorted({r["concealment"] for r in nulls}):
        rs = [r for r in nulls if r["concealment"] == con]
        print(f"  null {con:<5} {sum(r['right'] for r in rs)}/{len(rs)} none | "
              + " ".join(sorted(r["verdict"] for r in rs)))
    det = [r for r in eff_rows if r["oracle"]["detectable"]]
    right = [r for r in det if r["right"]]
    errs = [abs(e) for r in right for e in r.get("param_err_pct", {}).values()]
    better = [r for r in right if r.get("vfit_after") is not None
              and r["vfit_after"] > r["vfit_before"]]
    pct = lambda a, b: 100.0 * a / b if b else float("nan")  # noqa: E731
    print(f"right where detectable: {len(right)}/{len(det)} ({pct(len(right), len(det)):.1f} %)"
          f"  [target >= 90 %]; right of all effect cases {sum(r['right'] for r in eff_rows)}"
          f"/{len(eff_rows)}")
    print(f"null: {sum(r['right'] for r in nulls)}/{len(nulls)} none "
          f"({pct(sum(r['right'] for r in nulls), len(nulls)):.1f} %)  [target >= 95 %]")
    print(f"parameter within {PARAM_TOL_PCT:.0f} %: {sum(e <= PARAM_TOL_PCT for e in errs)}"
          f"/{len(errs)} compared (median {np.median(errs) if errs else float('nan'):.1f} %)")
    print(f"validation fit improved: {len(better)}/{len(right)} right cases")
    return dict(right_detectable=[len(right), len(det)], null=[sum(r["right"] for r in nulls),
                len(nulls)], param_within=[sum(e <= PARAM_TOL_PCT for e in errs), len(errs)],
                fit_improved=[len(better), len(right)])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", default="build/bin/rig", help="the rig executable")
    ap.add_argument("--seed", type=int, default=1, help="case list and record seeds")
    ap.add_argument("--quick", action="store_true", help="about 11 cases (~2 min)")
    ap.add_argument("--only", help="run only cases of this effect (or none)")
    ap.add_argument("--out", default="/tmp/gensim-bench", help="case folders")
    ap.add_argument("--json", help="per-case results (default OUT/results.json)")
    ap.add_argument("--plant-bench", help="bench_diagnose_plant executable (plantsim side)")
    ap.add_argument("--plant-seeds", type=int, default=2)
    ap.add_argument("--plant-output", help="a saved bench_diagnose_plant output to tabulate")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the recordings and oracle verdicts an earlier run left in --out "
                         "(same --seed): only `rig diagnose` runs")
    ap.add_argument("--rescore", help="tabulate an earlier results.json again, run nothing")
    ap.add_argument("--excitation", default="gaussian", choices=("gaussian", "prbs"),
                    help="the bias: the rig's Gaussian one, or a PRBS of the same rms (cases.py)")
    a = ap.parse_args()
    if a.rescore:
        doc = json.load(open(a.rescore))
        for r in doc["cases"]:
            r["right"] = is_right(r["effect"], r["verdict"], r["concealment"], r.get("named", ()))
        tables(doc["cases"], f"gensim (seed {doc['seed']})")
        if doc.get("plantsim_cases"):
            tables(doc["plantsim_cases"], "plantsim (bench_diagnose_plant)")
        return
    specs = cs.case_list(a.seed, quick=a.quick)
    if a.only:
        specs = [s for s in specs if a.only in s["effect"].split("+") or a.only == s["effect"]]
    print(f"gensim benchmark: seed {a.seed}, {a.excitation} bias, {len(specs)} cases of "
          f"{cs.DURATION_S:.0f} s at "
          f"{1 / g.DT:.0f} Hz, rig {a.rig}; oracle: gain >= {oracle.MIN_GAIN} points and "
          f"F test p < {oracle.ALPHA}")
    t_start = time.time()
    rows = []
    for spec in specs:
        r = run_case(spec, a.rig, a.out, a.reuse, a.excitation)
        o = r["oracle"]
        errs = " ".join(f"{k} {v:+.1f}%" for k, v in r.get("param_err_pct", {}).items())
        vb, va = r.get("vfit_before"), r.get("vfit_after")
        print(f"  {r['id']} {r['effect']:<34} {r['size']:<5} {r['concealment']:<9} "
              f"oracle {'det ' if o['detectable'] else 'UND '}{o['gain']:+6.1f} -> "
              f"{r['verdict']:<30} {'ok ' if r['right'] else 'BAD'} {errs:<22} vfit "
              f"{vb if vb is None else round(vb, 1)} -> {va if va is None else round(va, 1)} "
              f"({r['sim_s']:.0f}+{r['rig_s']:.1f} s)", flush=True)
        rows.append(r)
    summary = dict(gensim=tables(rows, f"gensim (seed {a.seed})"))
    plant = []
    text = None
    if a.plant_output:
        text = open(a.plant_output).read()
    elif a.plant_bench:
        cmd = ["nice", "-n", "10", a.plant_bench, "--seeds", str(a.plant_seeds), "--threads", "1"]
        if a.quick:
            cmd += ["--duration", "150"]
        print("\nplantsim side: " + " ".join(cmd), flush=True)
        text = subprocess.run(cmd, capture_output=True, text=True).stdout
    if text:
        plant = plant_rows(text)
        summary["plantsim"] = tables(plant, "plantsim (bench_diagnose_plant)")
    print(f"\nwall time {time.time() - t_start:.0f} s")
    path = a.json or os.path.join(a.out, "results.json")
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump(dict(seed=a.seed, quick=a.quick, summary=summary, cases=rows,
                       plantsim_cases=plant), f, indent=1, default=float)
    print(f"per-case results: {path}")


if __name__ == "__main__":
    main()
