#!/usr/bin/env python3
"""rig identify's fit table across records and loads, on emulated commissioning tests.

For each load (the Stornoway preset at 3.5 MW and the same plant at 2 MW), three
commissioning tests with noise seeds S, S+1, S+2 (Gaussian excitation 120-180 s):
  * estimate on the first, choose the structure on the second, score every structure on
    the third: how far the chosen one is behind the best on the third (the rule's promise:
    within 1 point);
  * the chosen model's figures (gain, fn, zeta, dead time) at each load, their difference
    and the run-to-run spread at that load (the spread of the three single-record models),
    so that the load effect is told from the noise;
  * each load's model validated on the other load's record: the fit lost by crossing loads.

Usage: fit_table_bench.py [--rig build/bin/rig] [--plantsim build/bin/plantsim] [--seed 1]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

# The commissioning test of rig identify's tests (Gaussian excitation 120-180 s).
PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "integration",
                       "identify", "gaussian_commissioning.toml")
LOADS_KW = (3500, 2000)  # the preset's operating point and a lighter one (thesis 5-3)
CHOICE_MARGIN_PCT = 1.0


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    return p.stdout


def plant_toml(plantsim, work, load_kw):
    """The preset written out by plantsim, at another operating point."""
    text = re.sub(r"^power_kw = [0-9.]+", f"power_kw = {load_kw}", run([plantsim, "--list-params"]),
                  count=1, flags=re.M)
    path = os.path.join(work, f"plant_{load_kw}.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def commission(args, work, plant, seed, name):
    out = os.path.join(work, name)
    run([args.rig, "commission", "--emulate", "--preset", plant, "--seed", str(seed), "--quiet",
         "--force", "--test", PROFILE, "--out", out])
    return os.path.join(out, "recording.csv")


def identify(args, work, name, *extra):
    out = os.path.join(work, "id_" + name)
    return json.loads(run([args.rig, "identify", *extra, "--json", "--force", "--out", out]))


def figures(rep):
    d = rep["derived"] or {}
    return {"gain": d.get("gain"), "fn_hz": d.get("fn_hz"), "zeta": d.get("zeta"),
            "delay_s": rep["delay"]["value_s"]}


def choice_check(args, work, recs, load):
    on_b = identify(args, work, f"{load}_b", "--recording", recs[0], "--validation", recs[1])
    on_c = identify(args, work, f"{load}_c", "--recording", recs[0], "--validation", recs[2])
    rows = {r["name"]: r for r in on_c["fit_table"]["rows"] if r["ok"]}
    best = max(rows.values(), key=lambda r: r["validation_fit_pct"])
    chosen = on_b["structure"]["name"]
    behind = best["validation_fit_pct"] - rows[chosen]["validation_fit_pct"]
    print(f"  {load} kW: chosen on B {chosen} ({on_b['validation_fit_pct']:.2f} %); on C "
          f"{rows[chosen]['validation_fit_pct']:.2f} %, best on C {best['name']} "
          f"({best['validation_fit_pct']:.2f} %): {behind:.2f} points behind "
          f"({'within' if behind <= CHOICE_MARGIN_PCT else 'NOT within'} {CHOICE_MARGIN_PCT:g})")
    return on_b, behind


def spread(args, work, recs, load, structure_order):
    """The three single-record models of one load (chosen order, MMFM+OE, delay estimated)."""
    out = []
    for i, rec in enumerate(recs):
        rep = identify(args, work, f"{load}_single{i}", "--recording", rec, "--order",
                       structure_order, "--method", "mmfm+oe")
        out.append(figures(rep))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", default="build/bin/rig")
    ap.add_argument("--plantsim", default="build/bin/plantsim")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="rig_fit_table_bench_")
    print(f"== rig identify fit table: seeds {args.seed}..{args.seed + 2} per load, loads "
          f"{LOADS_KW} kW, work {work} ==")
    recs, chosen = {}, {}
    for load in LOADS_KW:
        plant = plant_toml(args.plantsim, work, load)
        recs[load] = [commission(args, work, plant, args.seed + i, f"run_{load}_{i}")
                      for i in range(3)]
        print(f"  {load} kW: recorded seeds {args.seed}..{args.seed + 2}", file=sys.stderr)
    print("Estimate on A, choose on B, score on C:")
    for load in LOADS_KW:
        chosen[load], _ = choice_check(args, work, recs[load], load)
    print("Load effect (2/0 +Td, MMFM+OE, one record each; mean +- sd over the 3 seeds):")
    per_load = {load: spread(args, work, recs[load], load, "2/0") for load in LOADS_KW}
    for key in ("gain", "fn_hz", "zeta", "delay_s"):
        cells = []
        for load in LOADS_KW:
            v = [f[key] for f in per_load[load]]
            cells.append((statistics.mean(v), statistics.stdev(v)))
        diff = cells[1][0] - cells[0][0]
        sd = max(c[1] for c in cells)
        verdict = "a load effect" if abs(diff) > 3 * sd else "within the spread"
        print(f"  {key:8s} " + "  ".join(f"{l} kW {m:.4g} +- {s:.2g}" for l, (m, s) in
                                          zip(LOADS_KW, cells)) +
              f"   difference {diff:+.4g} ({100 * diff / cells[0][0]:+.2f} %), {verdict}")
    print("Across loads (on each load's B record: its own load's model from A against the other "
          "load's; fit % depends on the record's signal-to-noise ratio, so only fits on the same "
          "record are compared):")
    for b, a in (LOADS_KW, LOADS_KW[::-1]):
        own = identify(args, work, f"same_{b}", "--recording", recs[b][0], "--validation",
                       recs[b][1], "--order", "2/0")
        other = identify(args, work, f"cross_{a}_{b}", "--recording", recs[a][0],
                         "--validation", recs[b][1], "--order", "2/0")
        print(f"  {b} kW record: {b} kW model {own['validation_fit_pct']:.2f} %, {a} kW model "
              f"{other['validation_fit_pct']:.2f} % "
              f"({other['validation_fit_pct'] - own['validation_fit_pct']:+.2f} points)")


if __name__ == "__main__":
    main()
