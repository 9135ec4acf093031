#!/usr/bin/python3
"""How long `rig diagnose` takes on long gensim records (the issue's speed figure: 10-minute
100 Hz recordings with a JSON model, 2 cores), beside the same cases at the benchmark's
120 s as the reference measured in the same run.

    /usr/bin/python3 tests/bench/gensim/speed_long.py --rig build/bin/rig [--duration 600]
        [--out /tmp/gensim-long] [--reuse]

Ten cases (two nulls, a drift, and input-side effects plain, behind drift, behind the declared
coupling and from half-way), seeds 11-20. Prints per case the verdict and the wall time at
both lengths, then the median and worst and their ratio. plantsim's figure is
`bench_diagnose_plant --seeds 1 --duration 600`; gensim's records cost more (their actuator
effects are tried at every place, and the drift of every case puts pairs in the search).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases as cs  # noqa: E402
import genset as g  # noqa: E402

REF_S = cs.DURATION_S  # the benchmark's record length, the reference
SPECS = (("none", "plain"), ("drift", "plain"), ("backlash", "drift"), ("rate_limit", "plain"),
         ("hysteresis", "coupled"), ("static_nonlinearity", "plain"), ("dead_time", "plain"),
         ("none", "nuisances"), ("saturation", "partial"), ("resonance", "plain"))


def make(effect, concealment, seed, duration_s, out, reuse):
    if reuse and os.path.exists(os.path.join(out, "recording.csv")):
        return
    cs.DURATION_S = duration_s  # the record's length (and a partial effect's onset, half-way)
    case = cs.make_case(f"L{seed}", effect, "large", concealment, seed)
    r = g.simulate(case["u"], case["p"], seed=seed, onset_s=case["onset_s"],
                   p_after=case["p_after"])
    cs.write_case(case, r["y"][:, 0], out)


def diagnose(rig, d):
    t0 = time.time()
    subprocess.run([rig, "diagnose", "--recording", os.path.join(d, "recording.csv"), "--model",
                    os.path.join(d, "model.json"), "--out", os.path.join(d, "diag"), "--force"],
                   check=True, capture_output=True)
    wall = time.time() - t0
    return json.load(open(os.path.join(d, "diag", "report.json")))["verdict"], wall


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", default="build/bin/rig")
    ap.add_argument("--duration", type=float, default=600.0, help="long record, s")
    ap.add_argument("--out", default="/tmp/gensim-long")
    ap.add_argument("--reuse", action="store_true", help="keep records already simulated")
    a = ap.parse_args()
    rows = []
    for k, (effect, con) in enumerate(SPECS):
        seed = 11 + k
        times = {}
        for dur in (REF_S, a.duration):
            d = os.path.join(a.out, f"{effect}-{con}-{int(dur)}s")
            make(effect, con, seed, dur, d, a.reuse)
            times[dur] = diagnose(a.rig, d)
        (v_ref, t_ref), (v_long, t_long) = times[REF_S], times[a.duration]
        rows.append((t_ref, t_long))
        print(f"  {effect:20s} {con:9s} seed {seed}: 120 s {v_ref:20s} {t_ref:5.1f} s | "
              f"{a.duration:.0f} s {v_long:20s} {t_long:5.1f} s", flush=True)
    ref = [r[0] for r in rows]
    long = [r[1] for r in rows]
    print(f"{a.duration:.0f} s records: median {statistics.median(long):.1f} s, worst "
          f"{max(long):.1f} s; {REF_S:.0f} s: median {statistics.median(ref):.1f} s, worst "
          f"{max(ref):.1f} s; ratio of medians {statistics.median(long) / statistics.median(ref):.2f}")


if __name__ == "__main__":
    main()
