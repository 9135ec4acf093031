#!/usr/bin/env python3
"""The live page (--http) end to end: `rig commission --emulate --clock realtime` serving it,
headless Chromium driven over the DevTools protocol (cdp.py) as the browser, and plain HTTP
requests as a second, independent client.

Checked: a page opened mid-test shows the history so far within 1 s; its values change over
time; block estimates and the Bode plot appear; the Stop button without the token (and a
request with a wrong one) is refused and the test goes on; with the token the test ends as an
operator abort (exit 4, bias ramped to baseline, enable cleared) and the page shows it. A
screenshot of the page goes to the work directory.

Environment: RIG_BIN_DIR (build/bin), LIVE_WORK_DIR (keep the files there). About 1 minute.
"""
import json, os, re, shutil, subprocess, sys, time
import unittest
import urllib.error
import urllib.request
from pathlib import Path

HERE = Path(__file__).resolve().parent
BIN = Path(os.environ.get("RIG_BIN_DIR", HERE.parents[2] / "build" / "bin"))
RIG = str(BIN / "rig")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import scratch  # noqa: E402  (the work folder, removed on success)

WORK = scratch.work_dir("LIVE_WORK_DIR", "live-test-")
sys.path.insert(0, str(HERE))
from cdp import Chromium  # noqa: E402

# 3 s steady state, 5 s pilot, then excitation with 10.24 s blocks for at least 60 s: the
# test is still exciting when the page has seen its first estimates.
PROFILE = """[steady_state]
duration_s = 3.0
[pilot]
duration_s = 5.0
[mmfm]
block_size = 1024
min_duration_s = 60.0
max_duration_s = 90.0
[sweep]
enabled = false
"""
HISTORY_DEADLINE_S = 1.0  # the figure: a page opened mid-test shows the history


def http(method, url, token=None, timeout=5):
    req = urllib.request.Request(url, method=method, data=b"" if method == "POST" else None)
    if token is not None:
        req.add_header("X-Rig-Token", token)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def wait_for_line(path, pattern, timeout_s):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        m = re.search(pattern, path.read_text() if path.exists() else "")
        if m:
            return m
        time.sleep(0.05)
    raise AssertionError(f"no line matching {pattern!r} in {path}: "
                         f"{path.read_text() if path.exists() else '(none)'}")


class LivePageTest(unittest.TestCase):
    def setUp(self):
        WORK.mkdir(parents=True, exist_ok=True)
        self.out = WORK / "commission"
        shutil.rmtree(self.out, ignore_errors=True)
        test = WORK / "rt.toml"
        test.write_text(PROFILE)
        self.log = WORK / "rig.log"
        self.log_file = open(self.log, "w")
        self.rig = subprocess.Popen(
            [RIG, "commission", "--emulate", "--clock", "realtime", "--seed", "2", "--quiet",
             "--test", str(test), "--out", str(self.out), "--http", "127.0.0.1:0"],
            stdout=subprocess.DEVNULL, stderr=self.log_file)
        m = wait_for_line(self.log, r"live page (http://127\.0\.0\.1:\d+/) \(stop token "
                                    r"([0-9a-f]{32})\)", 30)
        self.url, self.token = m.group(1), m.group(2)
        self.browser = None

    def tearDown(self):
        if self.browser:
            self.browser.close()
        if self.rig.poll() is None:
            self.rig.kill()
            self.rig.wait()
        self.log_file.close()

    def test_page_follows_the_test_and_stops_it_only_with_the_token(self):
        # Mid-test: 6 s of test time recorded before the page opens.
        time.sleep(6)
        self.browser = b = Chromium()
        b.navigate(self.url)
        status, body = http("GET", self.url + "state")
        t_now = json.loads(body)["state"]["t_s"]
        shown, waited = b.wait_for(
            f"Number(document.body.dataset.lastT) >= {t_now - 0.5} && document.body.dataset.samples",
            5.0)
        print(f"page opened at test time {t_now:.1f} s showed {shown} samples up to it after "
              f"{waited:.2f} s")
        self.assertTrue(shown, "the page never showed the history so far")
        self.assertLess(waited, HISTORY_DEADLINE_S)
        self.assertGreater(int(shown), 10 * (t_now - 1))  # ~10 samples per second of test

        # It moves: more samples, a later time, a phase.
        before = b.evaluate("({n: +document.body.dataset.samples, t: +document.body.dataset.lastT})")
        time.sleep(2)
        after = b.evaluate("({n: +document.body.dataset.samples, t: +document.body.dataset.lastT,"
                           " phase: document.body.dataset.phase, err: document.body.dataset.jsError})")
        self.assertIsNone(after.get("err"))
        self.assertGreater(after["n"], before["n"] + 10)
        self.assertGreater(after["t"], before["t"] + 1.5)
        self.assertIn(after["phase"], ("pilot", "excite"))

        # Block estimates with their errors, and the model's Bode plot.
        n_est, _ = b.wait_for("+document.body.dataset.estimates >= 2 && "
                              "document.body.dataset.estimates", 40)
        self.assertTrue(n_est, "no block estimate reached the page")
        bode_points = b.evaluate("C.c_mag.data[0].length")
        self.assertGreater(bode_points, 50)
        gain_text = b.evaluate("C.c_gain.data[1].length")
        self.assertGreaterEqual(gain_text, 2)
        shot = WORK / "live_page.png"
        b.screenshot(str(shot))
        self.assertGreater(shot.stat().st_size, 20000)
        print(f"screenshot: {shot}")

        # Stop without the token, and with a wrong one: refused, the test goes on.
        b.evaluate("document.getElementById('token').value=''; "
                   "document.getElementById('stop').click(); 0")
        refused, _ = b.wait_for("document.body.dataset.stopStatus", 5)
        self.assertEqual(refused, "403")
        self.assertEqual(http("POST", self.url + "stop")[0], 403)
        self.assertEqual(http("POST", self.url + "stop", token="0" * 32)[0], 403)
        # Nothing else on the server changes anything.
        for path in ("start", "excitation", "limits"):
            self.assertIn(http("POST", self.url + path, token=self.token)[0], (404, 405))
        time.sleep(1)
        self.assertIsNone(self.rig.poll(), "the rig stopped without the token")
        self.assertEqual(json.loads(http("GET", self.url + "state")[1])["state"]["phase"],
                         "excite")

        # With the token: an operator abort, exit 4, ramped down, the page shows the end.
        b.evaluate("document.body.dataset.stopStatus=''; "
                   f"document.getElementById('token').value='{self.token}'; "
                   "document.getElementById('stop').click(); 0")
        accepted, _ = b.wait_for("document.body.dataset.stopStatus", 5)
        self.assertEqual(accepted, "202")
        outcome, _ = b.wait_for("document.body.dataset.outcome", 30)
        self.assertEqual(self.rig.wait(30), 4, self.log.read_text())
        self.assertEqual(outcome, "4")
        b.screenshot(str(WORK / "live_page_stopped.png"))
        report = json.loads((self.out / "report.json").read_text())
        self.assertEqual(report["safety"]["trip"]["cause"], "external")
        self.assertTrue(report["ramp_down"]["cleared"])
        self.assertFalse(report["model_written"])
        rows = (self.out / "recording.csv").read_text().strip().splitlines()
        header = rows[0].split(",")
        last = dict(zip(header, rows[-1].split(",")))
        self.assertAlmostEqual(float(last["bias_echo"]), 0.0, places=3)


class MonitorPageTest(unittest.TestCase):
    """rig monitor --http: the page shows this run's trends with the earlier runs' from the
    history, and its Stop is the normal end of a monitor (exit 0, report written)."""

    def test_monitor_page_shows_the_history_and_stops_normally(self):
        WORK.mkdir(parents=True, exist_ok=True)
        base = WORK / "baseline"
        subprocess.run([RIG, "commission", "--emulate", "--seed", "1", "--quiet", "--force",
                        "--out", str(base)], check=True, capture_output=True, timeout=600)
        history = WORK / "history.sqlite"
        history.unlink(missing_ok=True)
        common = [RIG, "monitor", "--emulate", "--seed", "5", "--baseline",
                  str(base / "model.json"), "--history", str(history), "--learn", "300",
                  "--quiet", "--force"]
        subprocess.run(common + ["--duration", "700", "--out", str(WORK / "monitor-1")],
                       check=True, capture_output=True, timeout=600)
        log = WORK / "monitor-2.log"
        with open(log, "w") as f:
            rig = subprocess.Popen(common + ["--duration", "20000", "--out",
                                             str(WORK / "monitor-2"), "--http", "0"],
                                   stdout=subprocess.DEVNULL, stderr=f)
            try:
                m = wait_for_line(log, r"live page (http://127\.0\.0\.1:\d+/) \(stop token "
                                       r"([0-9a-f]{32})\)", 30)
                b = Chromium()
                try:
                    b.navigate(m.group(1))
                    trends, _ = b.wait_for("+document.body.dataset.trends >= 4 && "
                                           "TR.gain_db && TR.gain_db.x.length > 60 && "
                                           "document.body.dataset.trends", 60)
                    self.assertTrue(trends, "no trends on the monitor's page: " + str(b.evaluate(
                        "JSON.stringify([document.body.dataset, Object.keys(TR).map("
                        "k => [k, TR[k].x.length])])")))
                    # The earlier run (history time 0 to 700 s) and this one (after it).
                    first_h, last_h = b.evaluate("[Math.min(...TR.gain_db.x), "
                                                 "Math.max(...TR.gain_db.x)]")
                    self.assertLess(first_h, 700 / 3600)
                    self.assertGreater(last_h, 700 / 3600)
                    self.assertEqual(b.evaluate("document.body.dataset.phase"), "monitor")
                    b.screenshot(str(WORK / "monitor_page.png"))
                    b.evaluate(f"document.getElementById('token').value='{m.group(2)}';"
                               "document.getElementById('stop').click(); 0")
                    outcome, _ = b.wait_for("document.body.dataset.outcome", 60)
                    self.assertEqual(outcome, "0")
                finally:
                    b.close()
                self.assertEqual(rig.wait(60), 0, log.read_text())
            finally:
                if rig.poll() is None:
                    rig.kill()
                    rig.wait()
        self.assertTrue((WORK / "monitor-2" / "report.html").exists())


if __name__ == "__main__":
    scratch.main(WORK, "LIVE_WORK_DIR")
