#!/usr/bin/env python3
"""`rig monitor` end to end: plantsim in lockstep with injected faults and load changes, the
history read back with the sqlite3 command-line client, Ctrl-C as the normal end, a history
continued by a second run and drawn by --report, bad input, and a run against the independent
pymodbus governor (tests/integration/governor/governor_server.py) judged from its own log.

Environment: RIG_BIN_DIR (build/bin), MONITOR_WORK_DIR (keep every run's files there).
Ends with the unittest summary; about 4 minutes on 2 cores.
"""
import json, os, shutil, signal, subprocess, sys, time
import unittest
from pathlib import Path

HERE = Path(__file__).resolve().parent
BIN = Path(os.environ.get("RIG_BIN_DIR", HERE.parents[2] / "build" / "bin"))
RIG = str(BIN / "rig")
sys.path.insert(0, str(HERE.parent / "governor"))
import fault_matrix_test as gov  # noqa: E402  (the independent governor's launcher)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import scratch  # noqa: E402  (the work folder, removed on success)

WORK = scratch.work_dir("MONITOR_WORK_DIR", "monitor-test-")
LEARN = "300"  # shorter than the default 600 s: a CI budget; the bench uses the default
FAULT_T = 480.0


def sql(db, query):
    """The sqlite3 command-line client (an independent reader of the history)."""
    exe = shutil.which("sqlite3")
    if exe is None:
        raise unittest.SkipTest("sqlite3 command-line client not installed")
    r = subprocess.run([exe, "-json", str(db), query], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        raise AssertionError(f"sqlite3 failed: {r.stderr}")
    return json.loads(r.stdout) if r.stdout.strip() else []


def monitor(name, *args, duration=None, seed=5, baseline=None):
    out = WORK / name
    if out.exists():
        shutil.rmtree(out)
    cmd = [RIG, "monitor", "--emulate", "--seed", str(seed), "--baseline",
           str(baseline or MonitorTest.baseline), "--out", str(out), "--quiet", "--learn", LEARN]
    if duration is not None:
        cmd += ["--duration", str(duration)]
    cmd += list(args)
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    alarms = [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]
    return p, alarms, out


class MonitorTest(unittest.TestCase):
    baseline = None

    @classmethod
    def setUpClass(cls):
        WORK.mkdir(parents=True, exist_ok=True)
        out = WORK / "commission"
        subprocess.run([RIG, "commission", "--emulate", "--seed", "1", "--out", str(out),
                        "--quiet", "--force"], check=True, capture_output=True, timeout=600)
        cls.baseline = out / "model.json"

    def test_two_injectors_out_are_found_and_named(self):
        p, alarms, out = monitor("injector", "--fault",
                                 f"engine.injectors_out=2@t={FAULT_T:g}", duration=FAULT_T + 300)
        self.assertIn(p.returncode, (0, 4), p.stderr)  # 4: the ripple keeps tripping the band
        self.assertTrue(alarms, p.stderr)
        first = alarms[0]
        self.assertGreaterEqual(first["t_s"], FAULT_T)
        self.assertLess(first["t_s"] - FAULT_T, 300.0)
        self.assertEqual(first["cause"], "injector/cylinder loss")
        self.assertEqual(first["class"], "multiplicative")
        rows = sql(out / "monitor.db", "select cause, fault_class, confidence from alarms")
        self.assertEqual(rows[0]["cause"], "injector/cylinder loss")
        self.assertGreater(rows[0]["confidence"], 0.5)
        trips = sql(out / "monitor.db", "select count(*) as n from events where kind='trip'")
        self.assertGreaterEqual(trips[0]["n"], 1)

    def test_transducer_gain_error_is_a_sensor_fault(self):
        p, alarms, out = monitor("gain", "--fault", f"meas.gain=1.1@t={FAULT_T:g}",
                                 duration=FAULT_T + 300)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertTrue(alarms, p.stderr)
        self.assertEqual(alarms[0]["cause"], "power transducer gain error")
        self.assertLess(alarms[0]["t_s"] - FAULT_T, 300.0)

    def test_damping_change_moves_only_the_damping(self):
        p, alarms, out = monitor("damping", "--fault", f"alt.d_pu=6@t={FAULT_T:g}",
                                 duration=FAULT_T + 200)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertTrue(alarms, p.stderr)
        a = alarms[0]
        self.assertEqual(a["cause"], "alternator damping change")
        z = a["evidence"]["z"]
        self.assertEqual(max(z, key=lambda k: abs(z[k])), "damping")
        # The damping's trend left its thresholds; the others' stayed inside theirs.
        db = out / "monitor.db"
        for name, moved in (("damping_pct", True), ("gain_db", False), ("frequency_pct", False),
                            ("delay_ms", False)):
            rows = sql(db, f"select count(*) as n from series where name='{name}' and t_s > "
                           f"{FAULT_T} and t_s <= {a['t_s']} and lo is not null and "
                           f"(value < lo or value > hi)")
            if moved:
                self.assertGreater(rows[0]["n"], 0, name)
            else:
                self.assertEqual(rows[0]["n"], 0, name)

    def test_no_alarm_without_a_fault_through_load_changes_and_drift(self):
        p, alarms, out = monitor("free", "--fault", "meas.drift_kw=8@t=0",
                                 "--fault", "op.power_kw=3750@t=900",
                                 "--fault", "op.power_kw=3600@t=1800,ramp=120",
                                 duration=2700, seed=7)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(alarms, [], p.stderr)
        kinds = [r["kind"] for r in sql(out / "monitor.db", "select kind from events")]
        self.assertIn("trip", kinds)          # the +250 kW step leaves the 3 % band
        self.assertIn("load change", kinds)   # and is recognised as a load change
        self.assertIn("re-baselined", kinds)

    def test_sigint_is_the_normal_end_and_a_history_continues(self):
        hist = WORK / "continued.db"
        if hist.exists():
            hist.unlink()
        out = WORK / "sigint"
        if out.exists():
            shutil.rmtree(out)
        rig = subprocess.Popen([RIG, "monitor", "--emulate", "--seed", "3", "--baseline",
                                str(self.baseline), "--out", str(out), "--history", str(hist),
                                "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
        time.sleep(6.0)
        rig.send_signal(signal.SIGINT)
        _, err = rig.communicate(timeout=120)
        self.assertEqual(rig.returncode, 0, err)
        runs = sql(hist, "select exit_code, outcome, ended_utc from runs")
        self.assertEqual(runs[0]["exit_code"], 0)
        self.assertIn("operator", runs[0]["outcome"])
        self.assertTrue(runs[0]["ended_utc"])
        # The governor's enable was cleared at the end (plantsim's own log).
        self.assertTrue((out / "report.html").exists())
        # A second run continues the same history: its time axis starts where the first ended.
        p, _, out2 = monitor("second", "--history", str(hist), duration=120)
        self.assertEqual(p.returncode, 0, p.stderr)
        runs = sql(hist, "select id, offset_s from runs order by id")
        self.assertEqual(len(runs), 2)
        first_end = sql(hist, "select max(history_s) as m from events where run_id=1")[0]["m"]
        self.assertGreaterEqual(runs[1]["offset_s"], first_end)
        rep = WORK / "report"
        if rep.exists():
            shutil.rmtree(rep)
        r = subprocess.run([RIG, "monitor", "--report", str(hist), "--out", str(rep)],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 0, r.stderr)
        doc = json.loads((rep / "report.json").read_text())
        self.assertEqual(len(doc["runs"]), 2)
        self.assertTrue((rep / "report.html").exists())

    def test_bad_input_is_refused_with_one_line(self):
        cases = [
            (["--band-pct", "2.5", "--trip-band-pct", "2"], "--band-pct"),
            (["--history", str(HERE / "monitor_test.py")], "not a monitor history"),
        ]
        for extra, words in cases:
            p, _, out = monitor("bad", *extra, duration=10)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn(words, p.stderr)
        p = subprocess.run([RIG, "monitor", "--emulate", "--out", str(WORK / "bad2"),
                            "--baseline", str(WORK / "missing.json")], capture_output=True,
                           text=True, timeout=60)
        self.assertEqual(p.returncode, 2)
        self.assertIn("missing.json", p.stderr)

    def test_independent_governor_sees_a_bounded_bias_and_a_clean_end(self):
        python = gov.server_python()
        log = WORK / "governor.jsonl"
        server = gov.Server(python, "none", 1000.0, log)
        out = WORK / "governor"
        if out.exists():
            shutil.rmtree(out)
        try:
            p = subprocess.run([RIG, "monitor", "--link",
                                f"modbus+tcp://127.0.0.1:{server.port}?unit=1", "--baseline",
                                str(self.baseline), "--out", str(out), "--quiet", "--duration",
                                "40", "--learn", "60"], capture_output=True, text=True,
                               timeout=300)
        finally:
            server.stop()
        self.assertEqual(p.returncode, 0, p.stderr)
        writes = [r for r in server.records() if r.get("ev") == "write"]
        biases = [r["bias_pct"] for r in writes if r.get("bias_pct") is not None]
        self.assertTrue(biases)
        # The monitoring excitation stays small: far inside the 5 % clamp.
        self.assertLess(max(abs(b) for b in biases), 1.5)
        accepted = [r for r in writes if r.get("result") == "ok"]
        last_bias = [r for r in accepted if r.get("bias_pct") is not None][-1]
        last_enable = [r for r in accepted if r.get("enable") is not None][-1]
        self.assertEqual(last_bias["bias_pct"], 0.0)
        self.assertFalse(last_enable["enable"])


if __name__ == "__main__":
    scratch.main(WORK, "MONITOR_WORK_DIR")
