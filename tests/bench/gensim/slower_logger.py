#!/usr/bin/python3
"""Copies of benchmark case folders as a slower logger would have written them: every k-th
row of recording.csv, the sidecar's sample rate divided by k, the model, truth and oracle as
they are. Then diagnoses each copy and compares the verdict word with the 100 Hz run's.

    /usr/bin/python3 tests/bench/gensim/slower_logger.py --cases /tmp/gensim-s7 \\
        --results /tmp/gensim-s7/results.json --every 2 --out /tmp/gensim-s7-50hz \\
        --rig build/bin/rig

--cases: the folders of a run_bench.py run (--out); --results: that run's per-case JSON.
Prints each case whose verdict word changed, then the right verdict words among the
detectable cases at both rates (the first effect of a pair only) and the nulls kept `none`.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

import numpy as np

LAGS = {"extra_lag", "sensor_lag"}


def right_word(truth, verdict):
    want = truth.split("+")[0]
    if want in LAGS:
        return verdict in LAGS
    if want == "hysteresis":
        return verdict in ("hysteresis", "backlash")
    return verdict == want


def copy_case(src, dst, every):
    os.makedirs(dst, exist_ok=True)
    rows = np.loadtxt(os.path.join(src, "recording.csv"), delimiter=",", skiprows=1)[::every]
    np.savetxt(os.path.join(dst, "recording.csv"), rows, delimiter=",", header="t,u,y",
               comments="", fmt=["%.2f", "%.6f", "%.4f"])
    with open(os.path.join(src, "recording.json")) as f:
        side = json.load(f)
    side["sample_rate_hz"] = side["sample_rate_hz"] / every
    with open(os.path.join(dst, "recording.json"), "w") as f:
        json.dump(side, f, indent=1)
    for name in ("model.json", "truth.json", "oracle.json"):
        if os.path.exists(os.path.join(src, name)):
            shutil.copy(os.path.join(src, name), os.path.join(dst, name))


def diagnose(rig, case):
    start = time.monotonic()
    proc = subprocess.run([rig, "diagnose", "--recording", os.path.join(case, "recording.csv"),
                           "--model", os.path.join(case, "model.json"), "--out",
                           os.path.join(case, "diag"), "--force"], capture_output=True, text=True)
    elapsed = time.monotonic() - start
    if proc.returncode not in (0, 1):
        return None, elapsed, proc.stderr.strip()
    with open(os.path.join(case, "diag", "report.json")) as f:
        return json.load(f)["verdict"], elapsed, ""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", required=True, help="case folders of a run_bench.py run")
    ap.add_argument("--results", required=True, help="that run's per-case results JSON")
    ap.add_argument("--every", type=int, default=2, help="keep every k-th row (2: 50 Hz)")
    ap.add_argument("--out", required=True, help="where the copies go")
    ap.add_argument("--rig", default="build/bin/rig")
    a = ap.parse_args()
    with open(a.results) as f:
        base = {c["id"]: c for c in json.load(f)["cases"]}
    right_fast = right_slow = detectable = nulls = nulls_kept = failures = 0
    times = []
    for cid in sorted(base):
        c = base[cid]
        dst = os.path.join(a.out, cid)
        copy_case(os.path.join(a.cases, cid), dst, a.every)
        verdict, elapsed, error = diagnose(a.rig, dst)
        times.append(elapsed)
        if verdict is None:
            failures += 1
            print(f"{cid} FAILED: {error}")
            continue
        if c["effect"] == "none":
            nulls += 1
            nulls_kept += verdict == "none"
            continue
        if not (c.get("oracle") or {}).get("detectable"):
            continue
        detectable += 1
        fast, slow = right_word(c["effect"], c["verdict"]), right_word(c["effect"], verdict)
        right_fast += fast
        right_slow += slow
        if fast != slow:
            print(f"{cid} {c['effect']} ({c['concealment']}): {c['verdict']} -> {verdict}")
    times.sort()
    print(f"1 row in {a.every}: right verdict word {right_slow}/{detectable} "
          f"(full rate {right_fast}/{detectable}); nulls none {nulls_kept}/{nulls}; "
          f"failures {failures}; median {times[len(times) // 2]:.1f} s, worst {times[-1]:.1f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
