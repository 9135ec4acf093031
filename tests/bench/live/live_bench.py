#!/usr/bin/env python3
"""Does the live page cost the realtime loop anything? One `rig commission --emulate --clock
realtime --http` run with the page alternately closed and open (headless Chromium redrawing
it at 10 Hz), WINDOW seconds each, closed first; the loop's lateness per cycle comes from the
feed's own timing messages (every cycle's lateness in microseconds), pooled per window.

  live_bench.py --rig build/bin/rig [--window 60] [--pairs 2] [--seed 2] [--out DIR]
                [--monitor-hours H --baseline MODEL.json]

Printed: per window, cycles, lateness p50/p99/max; then p99 open minus p99 closed (the
issue's figure: within 0.1 ms) and the same as a ratio. The first 5 s after opening or closing
are left out of both (Chromium starting up or exiting is not the page's steady cost).
--monitor-hours H (instead): `rig monitor --emulate` (lockstep) with --http until H hours of
plant time have passed, then a page is opened: printed, the time until it shows the history
so far (the issue's figure: within 1 s), how many samples it holds and over what span (the
feed thins old samples), and the trend points per tracked value.
Needs Debian's chromium and python3-websocket (run with /usr/bin/python3).
"""
import argparse, json, os, re, shutil, subprocess, sys, tempfile, threading, time
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "integration" / "live"))
from cdp import Chromium  # noqa: E402

SETTLE_S = 5.0


def profile(total_s):
    return f"""[steady_state]
duration_s = 3.0
[pilot]
duration_s = 5.0
[mmfm]
block_size = 1024
min_duration_s = {total_s:.0f}
max_duration_s = {total_s + 30:.0f}
[sweep]
enabled = false
"""


def follow(url, sink, stop):
    """Reads the event stream (a plain HTTP client) and keeps the timing messages."""
    with urllib.request.urlopen(url + "events", timeout=30) as r:
        kind = None
        for raw in r:
            if stop.is_set():
                return
            line = raw.decode().rstrip("\n")
            if line.startswith("event: "):
                kind = line[7:]
            elif line.startswith("data: ") and kind == "timing":
                m = json.loads(line[6:])
                sink.append((time.monotonic(), m["cycles_us"]))


def quantile(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, max(0, int(-(-q * len(v) // 1)) - 1))] if v else float("nan")


def state(url):
    with urllib.request.urlopen(url + "state", timeout=10) as r:
        return json.load(r)


def serve(cmd, work):
    log = open(work / "rig.log", "w")
    rig = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=log)
    for _ in range(600):
        m = re.search(r"live page (http://\S+/) \(stop token (\w+)\)",
                      (work / "rig.log").read_text())
        if m:
            return rig, log, m.group(1), m.group(2)
        time.sleep(0.1)
    sys.exit("rig did not serve a page: " + (work / "rig.log").read_text())


def monitor_history(a, work):
    """A page opened on a monitor that has run for --monitor-hours of plant time."""
    out = work / "monitor"
    shutil.rmtree(out, ignore_errors=True)
    rig, log, url, token = serve(
        [a.rig, "monitor", "--emulate", "--seed", str(a.seed), "--baseline", a.baseline,
         "--quiet", "--duration", str(a.monitor_hours * 3600 * 2), "--out", str(out),
         "--http", "0"], work)
    target_s = a.monitor_hours * 3600
    t0 = time.monotonic()
    while (s := state(url)["state"]) is None or s["t_s"] < target_s:
        time.sleep(2)
    print(f"monitor at {s['t_s'] / 3600:.2f} h of plant time after "
          f"{time.monotonic() - t0:.0f} s of wall time; opening the page", flush=True)
    b = Chromium()
    b.navigate(url)
    t_now = state(url)["state"]["t_s"]
    shown, waited = b.wait_for(f"+document.body.dataset.lastT >= {t_now - 60} && "
                               "document.body.dataset.samples", 60)
    span = b.evaluate("[S.t[0], S.t[S.t.length - 1], Object.keys(TR).length, "
                      "TR.gain_db ? TR.gain_db.x.length : 0]")
    print(f"page showed the history after {waited:.2f} s (target within 1 s): {shown} samples "
          f"over {span[0] / 3600:.2f}-{span[1] / 3600:.2f} h, {span[2]} tracked values, "
          f"{span[3]} gain points")
    b.close()
    urllib.request.urlopen(urllib.request.Request(url + "stop", data=b"", method="POST",
                                                  headers={"X-Rig-Token": token}), timeout=10)
    print(f"monitor exit {rig.wait(300)}")
    log.close()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rig", default="build/bin/rig")
    ap.add_argument("--window", type=float, default=60.0)
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--out", default=None)
    ap.add_argument("--monitor-hours", type=float, default=0.0)
    ap.add_argument("--baseline", default=None)
    a = ap.parse_args()
    work = Path(a.out or tempfile.mkdtemp(prefix="live-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    if a.monitor_hours > 0:
        if not a.baseline:
            sys.exit("--monitor-hours needs --baseline MODEL.json")
        return monitor_history(a, work)
    test = work / "bench.toml"
    total = 2 * a.pairs * a.window + 30
    test.write_text(profile(total))
    log = open(work / "rig.log", "w")
    out = work / "run"
    shutil.rmtree(out, ignore_errors=True)
    rig = subprocess.Popen([a.rig, "commission", "--emulate", "--clock", "realtime", "--seed",
                            str(a.seed), "--quiet", "--test", str(test), "--out", str(out),
                            "--http", "0"], stdout=subprocess.DEVNULL, stderr=log)
    url = None
    for _ in range(300):
        m = re.search(r"live page (http://\S+/)", (work / "rig.log").read_text())
        if m:
            url = m.group(1)
            break
        time.sleep(0.1)
    if url is None:
        sys.exit("rig did not serve a page: " + (work / "rig.log").read_text())
    timing, stop = [], threading.Event()
    threading.Thread(target=follow, args=(url, timing, stop), daemon=True).start()
    print(f"seed {a.seed}, windows of {a.window:.0f} s, page redrawn at 10 Hz when open; "
          f"work {work}", flush=True)
    time.sleep(12)  # steady state and pilot over
    windows = []
    for i in range(2 * a.pairs):
        open_page = i % 2 == 1
        browser = Chromium() if open_page else None
        if browser:
            browser.navigate(url)
        t0 = time.monotonic()
        time.sleep(a.window)
        windows.append(("open" if open_page else "closed", t0 + SETTLE_S, time.monotonic()))
        if browser:
            print(f"  page showed {browser.evaluate('document.body.dataset.samples')} samples",
                  flush=True)
            browser.close()
    stop.set()
    rig.terminate()
    rig.wait(60)
    log.close()
    pooled = {"open": [], "closed": []}
    for state, start, end in windows:
        lat = [us / 1e3 for t, cycles in timing if start + 2.5 <= t <= end for us in cycles]
        pooled[state] += lat
        print(f"  {state:6s} {len(lat):6d} cycles  lateness p50 {quantile(lat, .5):.3f} ms  "
              f"p99 {quantile(lat, .99):.3f} ms  max {max(lat, default=float('nan')):.3f} ms")
    p99 = {k: quantile(v, .99) for k, v in pooled.items()}
    print(f"lateness p99: page open {p99['open']:.3f} ms, closed {p99['closed']:.3f} ms; "
          f"open - closed {p99['open'] - p99['closed']:+.3f} ms (target within 0.1 ms), ratio "
          f"{p99['open'] / p99['closed']:.2f}")


if __name__ == "__main__":
    main()
