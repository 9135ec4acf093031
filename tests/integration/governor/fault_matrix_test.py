#!/usr/bin/env python3
"""Fault matrix: `rig commission --link` against the independent governor (governor_server.py).

For each case the governor server is started on an ephemeral port with one fault mode, the rig
runs a short commissioning test against it in real time, and the case is judged from the
SERVER's write log (what the governor actually received and accepted), the rig's exit code, its
stderr and its recording.csv. See README.md in this folder for what each case asserts.

Usage:
    python3 fault_matrix_test.py                 # every case
    python3 fault_matrix_test.py nan late        # some cases (or GOVERNOR_CASES=nan,late)
    python3 fault_matrix_test.py --list          # the cases and what they expect

Environment:
    RIG_BIN_DIR        where `rig` is (default /work/main/build/bin)
    GOVERNOR_CASES     comma-separated case names (as positional arguments)
    GOVERNOR_PYTHON    the interpreter for the server (default: the first of this interpreter,
                       /usr/bin/python3 and python3 that imports pymodbus)
    GOVERNOR_JOBS      cases run side by side (default 4; 1: one after another)
    GOVERNOR_WORK_DIR  keep every case's files here (default: a temporary folder, kept only
                       when a case fails)

Only the standard library is used here (unittest); the server needs pymodbus 3.0.
The last line printed is `N passed, M failed`.
"""

from __future__ import annotations

import concurrent.futures
import csv
import io
import json
import math
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import unittest
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
SERVER = HERE / "governor_server.py"
RIG_BIN_DIR = Path(os.environ.get("RIG_BIN_DIR", "/work/main/build/bin"))

# Exit codes, DESIGN.md section 4.
EXIT_PASS, EXIT_ACCEPTANCE, EXIT_CONFIG, EXIT_FAULT, EXIT_SAFETY = 0, 1, 2, 3, 4

# Profiles (docs/test-file.md). The sweep is off, so a clean run ends with 0 (or 1, if the rig
# judges the comparison insufficient without a sweep); the excitation stops between 20 and 40 s.
PROFILE = """\
# governor fault matrix: short real-time profile
[steady_state]
duration_s = 5.0

[pilot]
duration_s = 5.0

[mmfm]
block_size = 1024
min_duration_s = 20.0
max_duration_s = 40.0

[sweep]
enabled = false

[safety]
ramp_pct_per_s = 2.0
"""

# When the faults strike, in s after the rig's first enable: during the pilot's excitation
# (the supervisor's soft start has raised the amplitude to about 0.7 of the pilot's), where the
# excitation (seed 1, the same in every run) is near a peak of about 0.4 %, so the governor
# holds a clearly nonzero bias when the fault strikes and the rig has to bring it back.
FAULT_AT_S = 7.1

# (f) After an "at" fault has struck, no accepted write may move the bias the governor applies
# by more than this (% of rated): the way back to baseline is a ramp (2 %/s, 0.02-0.04 % per
# write), started from the largest value the governor may hold (DESIGN.md section 8 layer 3).
# Judged from the server's first input read with the fault on: the write in flight before it is
# the tick's excitation sample (one moved 0.107 % in a CI run), not a reaction to the fault.
MAX_STEP_PCT = 0.1
# A server stall that can carry the set out of the band on its own: 0.1 s with 1 % held. A held
# bias u drives the power towards K u (46 kW per %) with the 2 Hz mode's (zeta 0.1) 73 %
# overshoot: up to 80 kW, three quarters of the 105 kW band, added to wherever the excitation
# had the power (0.4 of the band at most in clean runs).
HELD_STALL_S = 0.1
HELD_BIAS_PCT = 1.0

# Stderr must name the cause: one regular expression per kind of cause (case-insensitive).
LINK_LOST_RE = r"connect|reset|closed|lost|broken pipe|refused|end of file|eof"


@dataclass
class Case:
    fault: str                        # governor_server --fault
    expect_exit: set[int]             # allowed exit codes
    cause: str | None = None          # regex a stderr line must match (None: clean run)
    max_bias_pct: float = 5.0         # no bias written may exceed this in magnitude
    fault_at: float = FAULT_AT_S
    timeout_s: float = 150.0
    clean: bool = False               # a clean run: no heartbeat loss at the governor
    no_bias_before_honoured: bool = False
    ramp_check: bool = True           # (f), for faults that strike at --fault-at
    note: str = ""


CASES: dict[str, Case] = {
    "nominal": Case("none", {EXIT_PASS, EXIT_ACCEPTANCE}, clean=True, ramp_check=False,
                    note="honest governor: exit 0 or 1 (sweep off), never a trip"),
    "quiet": Case("quiet", {EXIT_PASS, EXIT_ACCEPTANCE}, clean=True, ramp_check=False,
                  note="noise 0.04 % of P0: a quiet set is not a fault"),
    "honoured_late": Case("honoured_late", {EXIT_PASS, EXIT_ACCEPTANCE}, fault_at=1.5,
                          clean=True, no_bias_before_honoured=True, ramp_check=False,
                          note="bias honoured 1.5 s after enable: the rig waits for bit 2 and "
                               "the echo before exciting, then runs normally"),
    "bias_ignored": Case("bias_ignored", {EXIT_FAULT}, max_bias_pct=1.0, ramp_check=False,
                         cause=r"bias.*(not|never|no longer).*(active|acknowledg|honou?r|echo)"
                               r"|echo|acknowledg|bit ?2",
                         note="enable never honoured: stop before the amplitude grows"),
    "scaled": Case("scaled=3", {EXIT_FAULT}, cause=r"echo|applied|departs|mismatch",
                   ramp_check=False,
                   note="governor applies 3x the bias, echo shows it: echo departs, trip"),
    "revoked": Case("revoked", {EXIT_FAULT},
                    cause=r"bias.*(not|no longer).*active|bit ?2|echo|revok|local",
                    note="governor takes the bias back mid-test (bit 2 clears, echo 0)"),
    "exception06": Case("exception06", {EXIT_FAULT}, cause=r"exception.*6|busy",
                        note="writes answer exception 06 for 2 s"),
    "refuse_writes": Case("refuse_writes=4", {EXIT_FAULT},
                          cause=r"exception|illegal|failure|refus",
                          note="writes to holding 0 answer exception 04 for 2 s"),
    "late": Case("late=1.5", {EXIT_FAULT}, cause=r"time(d)? ?out|timeout|late",
                 note="every answer 1.5 s late for 2 s"),
    "drop_connection": Case("drop_connection", {EXIT_FAULT}, cause=LINK_LOST_RE,
                            note="connections closed once; the rig must reconnect to ramp down"),
    "drop_listener": Case("drop_listener=2", {EXIT_FAULT}, cause=LINK_LOST_RE,
                          note="not listening for 2 s; the rig must reconnect to ramp down"),
    "frozen_counter": Case("frozen_counter", {EXIT_FAULT}, cause=r"stale|counter",
                           note="sample counter stops: stale samples"),
    "nan": Case("nan", {EXIT_FAULT},
                cause=r"\bnan\b|not.?finite|non.?finite|not available",
                note="power reads INT32_MIN (not available)"),
    "plant_fault": Case("plant_fault", {EXIT_FAULT}, cause=r"plant.?fault|bit ?4",
                        note="status bit 4 (plant fault)"),
    "power_jump": Case("power_jump=8", {EXIT_SAFETY}, cause=r"band",
                       note="power steps +8 % of P0: band trip"),
    "absurd": Case("absurd=power", {EXIT_FAULT, EXIT_SAFETY},
                   cause=r"band|implausible|absurd|range|plausib",
                   note="power reads 2e9 W: a sample outside the band (4, section 8 layer 3) "
                        "or an implausible reading (3, plant fault); either is allowed"),
}


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------
def server_python() -> str:
    cands = [os.environ.get("GOVERNOR_PYTHON"), sys.executable, "/usr/bin/python3",
             shutil.which("python3")]
    for c in cands:
        if not c:
            continue
        try:
            r = subprocess.run([c, "-c", "import pymodbus"], capture_output=True, timeout=30)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if r.returncode == 0:
            return c
    raise RuntimeError("no Python with pymodbus found (install python3-pymodbus, or set "
                       "GOVERNOR_PYTHON)")


class Server:
    """governor_server.py as a child process on an ephemeral port."""

    def __init__(self, python: str, fault: str, fault_at: float, log: Path, extra=()):
        self.log = log
        self.stderr_path = log.with_suffix(".stderr")
        self._stderr = open(self.stderr_path, "w")
        self.proc = subprocess.Popen(
            [python, str(SERVER), "--port", "0", "--log", str(log), "--fault", fault,
             "--fault-at", str(fault_at), *extra],
            stdout=subprocess.PIPE, stderr=self._stderr, text=True)
        deadline = time.monotonic() + 20.0
        self.port = None
        while time.monotonic() < deadline:
            line = self.proc.stdout.readline()
            if not line:
                break
            m = re.match(r"PORT (\d+)", line)
            if m:
                self.port = int(m.group(1))
                break
        if self.port is None:
            self.stop()
            raise RuntimeError(f"governor server did not start: {self.stderr_path.read_text()}")

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._stderr.close()

    def records(self) -> list[dict]:
        out = []
        with open(self.log, encoding="utf-8") as f:
            for line in f:
                line = line.strip()
                if line:
                    out.append(json.loads(line))
        return out


def check_recording(path: Path) -> list[str]:
    """(d): header, numeric rows of one width, no half row at the end."""
    if not path.exists():
        return [f"(d) {path.name} missing"]
    data = path.read_bytes()
    if not data:
        return [f"(d) {path.name} is empty"]
    problems = []
    if not data.endswith(b"\n"):
        problems.append(f"(d) {path.name} ends in a half row (no final newline)")
    rows = list(csv.reader(io.StringIO(data.decode("utf-8", errors="replace"))))
    header = rows[0]
    for col in ("t", "u", "y"):
        if col not in header:
            problems.append(f"(d) header lacks column {col!r}: {header}")
    body = rows[1:]
    if not body:
        problems.append("(d) no data rows")
    for i, row in enumerate(body, start=2):
        if len(row) != len(header):
            problems.append(f"(d) row {i} has {len(row)} fields, header {len(header)}")
            break
        try:
            vals = [float(x) for x in row]
        except ValueError:
            problems.append(f"(d) row {i} not numeric: {row}")
            break
        if not all(math.isfinite(v) for v in vals):
            problems.append(f"(d) row {i} not finite: {row}")
            break
    return problems


def writes_of(records: list[dict]) -> list[dict]:
    return [r for r in records if r.get("ev") == "write"]


def fmt_write(w: dict | None) -> str:
    if w is None:
        return "none"
    return (f"t={w['t']:.3f}s fc{w['fc']} @{w['addr']} {w['values']} -> {w['result']}"
            + (f" exc {w['exc']}" if "exc" in w else ""))


@dataclass
class Outcome:
    name: str
    exit_code: int | None = None
    wall_s: float = 0.0
    problems: list[str] = field(default_factory=list)
    facts: list[str] = field(default_factory=list)
    workdir: Path | None = None


RESULTS: list[Outcome] = []
# Cases started ahead of their test (main, GOVERNOR_JOBS at a time): name -> Future[Outcome].
STARTED: dict = {}
# Cases run side by side. Each is real time and mostly waits (about 15 % of one core for the rig
# and its server together), so four at once stay far from the 2 cores while the matrix runs
# alone (RUN_SERIAL). 1 runs them one after another.
DEFAULT_JOBS = 4


def run_case(name: str, case: Case, python: str, root: Path) -> Outcome:
    out = Outcome(name)
    d = root / name
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    out.workdir = d
    test_file = d / "test.toml"
    test_file.write_text(PROFILE)
    server = Server(python, case.fault, case.fault_at, d / "governor.jsonl")
    rig_out = d / "out"
    uri = f"modbus+tcp://127.0.0.1:{server.port}?unit=1"
    cmd = [str(RIG_BIN_DIR / "rig"), "commission", "--link", uri, "--test", str(test_file),
           "--out", str(rig_out), "--quiet"]
    (d / "command.txt").write_text(" ".join(cmd) + "\n")
    t0 = time.monotonic()
    timed_out = False
    with open(d / "rig.stdout", "w") as so, open(d / "rig.stderr", "w") as se:
        rig = subprocess.Popen(cmd, stdout=so, stderr=se)
        try:
            rc = rig.wait(timeout=case.timeout_s)
        except subprocess.TimeoutExpired:
            timed_out = True
            rig.send_signal(signal.SIGINT)  # operator abort: the rig ramps down
            try:
                rc = rig.wait(timeout=15)
            except subprocess.TimeoutExpired:
                rig.kill()
                rc = rig.wait()
    out.wall_s = time.monotonic() - t0
    out.exit_code = rc
    time.sleep(0.3)  # let late answers and the last state line land in the log
    server.stop()
    recs = server.records()
    stderr = (d / "rig.stderr").read_text(errors="replace")
    stdout = (d / "rig.stdout").read_text(errors="replace")
    p = out.problems

    if timed_out:
        p.append(f"rig did not finish within {case.timeout_s:.0f} s (sent SIGINT)")

    # (a) exit code. A clean run may end in a band trip only when the server itself stalled
    # holding a large bias: the plant then ran on with the bias held, as a governor whose
    # communication hangs would, and tripping is the rig's right answer (never the default).
    stalls = [r for r in recs if r.get("ev") == "stall"]
    held = [r for r in stalls if r["behind_s"] >= HELD_STALL_S and abs(r["held_pct"]) >= HELD_BIAS_PCT]
    if stalls:
        worst = max(stalls, key=lambda r: r["behind_s"])
        out.facts.append(f"server stalls: {len(stalls)}, longest {worst['behind_s']} s holding "
                         f"{worst['held_pct']} %")
    band_trip = rc == EXIT_SAFETY and "out_of_band" in stdout + stderr
    if case.clean and band_trip and held:
        out.facts.append(f"band trip after the server stalled {held[0]['behind_s']} s holding "
                         f"{held[0]['held_pct']} % at t={held[0]['t']}: accepted")
    elif rc not in case.expect_exit:
        p.append(f"(a) exit {rc}, expected {sorted(case.expect_exit)}")

    writes = writes_of(recs)
    accepted = [w for w in writes if w["result"] == "ok"]
    fault_on = next((r["t"] for r in recs if r.get("ev") == "fault_on"), None)
    first_enable = next((r["t"] for r in recs if r.get("ev") == "enable"), None)
    out.facts.append(f"writes {len(writes)} (accepted {len(accepted)}), enable at "
                     f"{first_enable}, fault at {fault_on}")

    # (b) the governor is left at baseline: the last accepted bias is 0 and the last accepted
    # control word has enable cleared (a refused or unanswered write does not count).
    last_bias = next((w for w in reversed(accepted) if "bias_pct" in w), None)
    last_ctrl = next((w for w in reversed(accepted) if "enable" in w), None)
    if last_bias is not None and last_bias["bias_pct"] != 0.0:
        p.append(f"(b) last accepted bias {last_bias['bias_pct']} %, not 0: {fmt_write(last_bias)}")
    if last_ctrl is not None and last_ctrl["enable"]:
        p.append(f"(b) last accepted control word keeps enable set: {fmt_write(last_ctrl)}")
    final = next((r for r in reversed(recs) if r.get("ev") == "final"), None)
    if final is not None:
        out.facts.append(f"final holding {final['holding']} applied {final['applied_pct']} % "
                         f"hb_lost {final['hb_lost']}")
    if fault_on is not None and last_ctrl is not None and last_ctrl["t"] < fault_on:
        out.facts.append("no control write accepted after the fault")

    # (c) one clear stderr line naming the cause
    # Paths name the case (e.g. .../revoked/out): take them out before looking for the cause.
    stderr = stderr.replace(str(d), "<dir>")
    stdout = stdout.replace(str(d), "<dir>")
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    if case.cause is not None:
        rx = re.compile(case.cause, re.IGNORECASE)
        hits = [ln for ln in lines if rx.search(ln)]
        if not hits:
            where = ""
            so_hits = [ln for ln in stdout.splitlines() if rx.search(ln)]
            if so_hits:
                where = f" (stdout has it: {so_hits[0].strip()[:160]!r})"
            p.append(f"(c) no stderr line names the cause /{case.cause}/; stderr: "
                     f"{(lines[:2] or ['<empty>'])}{where}")
        elif len(lines) > 10:
            p.append(f"(c) stderr has {len(lines)} lines, not one clear error line")
        else:
            out.facts.append(f"stderr: {hits[0].strip()[:200]}")
    else:
        summary = next((ln for ln in stdout.splitlines() if ln.strip()), "")
        out.facts.append(f"stdout: {summary.strip()[:200]}")

    # (d) readable recording
    p.extend(check_recording(rig_out / "recording.csv"))

    # (e) bias bounds over every write request received, accepted or not
    biases = [(abs(w["bias_pct"]), w) for w in writes if "bias_pct" in w]
    if biases:
        mx, mw = max(biases, key=lambda x: x[0])
        out.facts.append(f"max |bias| written {mx:.3f} %")
        if mx > case.max_bias_pct + 1e-9:
            p.append(f"(e) a bias of {mx:.3f} % was written (limit {case.max_bias_pct} %): "
                     f"{fmt_write(mw)}")

    # (f) no step at the governor after the fault: the rig ramps from what the governor holds.
    # Judged from the first input read the server answered with the fault on: a write the rig
    # sent before that (its tick's excitation write, in flight when the fault struck) cannot
    # be a reaction to a fault it had no way to see.
    fault_read = next((r["t"] for r in recs if r.get("ev") == "fault_read"), fault_on)
    if case.ramp_check and fault_on is not None:
        early = [w for w in accepted if fault_on <= w["t"] and w["t_rx"] < fault_read]
        if early:
            out.facts.append(f"{len(early)} write(s) sent before the rig could read the fault "
                             f"(first fault read at t={fault_read})")
        steps = [(abs(w["applied_after_pct"] - w["applied_before_pct"]), w) for w in accepted
                 if w["t_rx"] >= fault_read and "applied_after_pct" in w]
        if steps:
            mx, mw = max(steps, key=lambda x: x[0])
            out.facts.append(f"largest applied-bias step by a write after the fault {mx:.3f} %")
            if mx > MAX_STEP_PCT + 1e-9:
                p.append(f"(f) a write after the fault stepped the applied bias by {mx:.3f} % "
                         f"({mw['applied_before_pct']} -> {mw['applied_after_pct']} %), more "
                         f"than a ramp ({MAX_STEP_PCT} %): {fmt_write(mw)}")
        # ... and on the way down the rig never commands a bias farther from zero than the
        # governor's holding register 0 holds when the write takes effect (plus one excitation
        # or ramp step): a governor that resumes once the heartbeat changes again would apply it.
        # Judged in the order the governor processed the writes, refused ones included.
        held = 0.0
        raised = None
        for w in writes:
            if w["result"] == "deferred" or "bias_pct" not in w:
                continue
            if (w["t_rx"] >= fault_read and abs(w["bias_pct"]) > abs(held) + MAX_STEP_PCT + 1e-9
                    and raised is None):
                raised = (held, w)
            if w["result"] == "ok":
                held = w["bias_pct"]
        if raised is not None:
            p.append(f"(f) after the fault the rig raised the bias to {raised[1]['bias_pct']} % "
                     f"while the governor held {raised[0]} %: {fmt_write(raised[1])}")

    # Clean runs: the rig kept the heartbeat alive (section 8 layer 5) the whole time.
    if case.clean:
        hb = [r for r in recs if r.get("ev") == "heartbeat_lost"]
        if hb:
            p.append(f"heartbeat lost at the governor at t={hb[0]['t']:.3f} s "
                     f"(no write changed holding 1 for {hb[0]['since_change_s']} s)")

    # Layer 0: no excitation before the governor acknowledges the bias.
    if case.no_bias_before_honoured:
        honour_t = fault_on
        early = [w for w in accepted if w.get("bias_pct", 0.0) != 0.0
                 and (honour_t is None or w["t_rx"] < honour_t)]
        if early:
            p.append(f"nonzero bias written before the governor honoured the enable "
                     f"(at {honour_t}): {len(early)} writes, first {fmt_write(early[0])}")

    return out


# --------------------------------------------------------------------------------------------
# a quick self-check of the server against the register map (no rig involved)
# --------------------------------------------------------------------------------------------
class RawModbus:
    def __init__(self, port: int):
        self.s = socket.create_connection(("127.0.0.1", port), timeout=3)
        self.tid = 0

    def _req(self, pdu: bytes) -> bytes:
        self.tid = (self.tid + 1) & 0xFFFF
        self.s.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, 1) + pdu)
        hdr = self._recv(7)
        tid, _, length, _ = struct.unpack(">HHHB", hdr)
        body = self._recv(length - 1)
        assert tid == self.tid, (tid, self.tid)
        return body

    def _recv(self, n: int) -> bytes:
        b = b""
        while len(b) < n:
            c = self.s.recv(n - len(b))
            if not c:
                raise ConnectionError("closed")
            b += c
        return b

    def read_inputs(self):
        r = self._req(struct.pack(">BHH", 4, 0, 10))
        assert r[0] == 4, r
        return list(struct.unpack(">10H", r[2:22]))

    def write(self, addr: int, values: list[int]) -> int:
        """0 on success, else the exception code."""
        r = self._req(struct.pack(">BHHB", 16, addr, len(values), 2 * len(values))
                      + struct.pack(f">{len(values)}H", *[v & 0xFFFF for v in values]))
        return 0 if r[0] == 16 else r[1]

    def read_holding(self, addr: int, n: int):
        r = self._req(struct.pack(">BHH", 3, addr, n))
        return r[1] if r[0] & 0x80 else 0

    def close(self):
        self.s.close()


def decode(regs):
    pw = (regs[0] << 16) | regs[1]
    pw = pw - (1 << 32) if pw & 0x80000000 else pw
    echo = regs[5] - 0x10000 if regs[5] & 0x8000 else regs[5]
    return {"p_kw": pw / 1000.0, "speed": regs[2] / 10, "freq": regs[3] / 1000,
            "echo": echo / 1000, "status": regs[6], "t_s": ((regs[7] << 16) | regs[8]) / 1000,
            "counter": regs[9]}


class ServerSelfCheck(unittest.TestCase):
    """The server itself honours the register map and governor rules (judged without the rig)."""

    def test_server_map(self):
        root = Path(tempfile.mkdtemp(prefix="governor_selfcheck_"))
        srv = Server(PYTHON, "none", 20.0, root / "g.jsonl", extra=("--noise-kw", "0"))
        try:
            c = RawModbus(srv.port)
            a = decode(c.read_inputs())
            self.assertAlmostEqual(a["p_kw"], 3500.0, delta=0.01)
            self.assertEqual(a["status"] & 0b11111, 0b00011)  # running, breaker, nothing else
            self.assertAlmostEqual(a["speed"], 600.0, delta=1.0)
            self.assertAlmostEqual(a["freq"], 50.0, delta=0.01)
            self.assertEqual(c.read_holding(100, 1), 2)  # no lockstep register: exception 02
            self.assertEqual(c.write(0, [2000, 1, 1]), 0)  # bias 2 %, heartbeat, enable
            hb = 1
            t0 = time.monotonic()
            while time.monotonic() - t0 < 3.0:  # keep the heartbeat for 3 s (mode decays)
                hb += 1
                self.assertEqual(c.write(0, [6000, hb]), 0)  # 6 % commanded: clamped to 5
                time.sleep(0.01)
            b = decode(c.read_inputs())
            self.assertEqual(b["status"] & 0b1100, 0b0100)  # bias active, heartbeat fine
            self.assertAlmostEqual(b["echo"], 5.0, places=3)
            self.assertAlmostEqual(b["p_kw"], 3500.0 + 5 * 46.0, delta=8.0)
            self.assertGreater((b["counter"] - a["counter"]) & 0xFFFF, 2500)  # 1 kHz ticks
            time.sleep(0.7)  # heartbeat stops: bias dropped, bit 3 set, bit 2 clear
            d = decode(c.read_inputs())
            self.assertEqual(d["status"] & 0b1100, 0b1000)
            self.assertEqual(d["echo"], 0.0)
            self.assertEqual(c.write(0, [0, hb + 1, 0]), 0)
            e = decode(c.read_inputs())
            self.assertEqual(e["status"] & 0b1100, 0)
            c.close()
        finally:
            srv.stop()
        recs = srv.records()
        w = writes_of(recs)
        self.assertEqual(w[0]["values"], [2000, 1, 1])
        self.assertTrue(w[0]["enable"])
        self.assertTrue(any(r["ev"] == "heartbeat_lost" for r in recs))
        shutil.rmtree(root, ignore_errors=True)

    def _with_fault(self, fault, body):
        root = Path(tempfile.mkdtemp(prefix="governor_selfcheck_"))
        srv = Server(PYTHON, fault, 0.3, root / "g.jsonl")
        try:
            c = RawModbus(srv.port)
            self.assertEqual(c.write(0, [0, 1, 1]), 0)  # enable: the fault strikes 0.3 s later
            body(c, srv)
            c.close()
        finally:
            srv.stop()
        recs = srv.records()
        shutil.rmtree(root, ignore_errors=True)
        return recs

    def test_server_faults(self):
        def busy(c, srv):
            time.sleep(0.4)
            self.assertEqual(c.write(0, [100, 2]), 6)

        recs = self._with_fault("exception06", busy)
        self.assertEqual(writes_of(recs)[-1]["result"], "exception")

        def refuse(c, srv):
            time.sleep(0.4)
            self.assertEqual(c.write(0, [100, 2]), 4)
            self.assertEqual(c.write(2, [0]), 0)  # holding 2 alone is still accepted

        self._with_fault("refuse_writes", refuse)

        def nan(c, srv):
            time.sleep(0.4)
            self.assertEqual(decode(c.read_inputs())["p_kw"], -2147483.648)

        self._with_fault("nan", nan)

        def frozen(c, srv):
            time.sleep(0.4)
            a = decode(c.read_inputs())["counter"]
            time.sleep(0.1)
            self.assertEqual(decode(c.read_inputs())["counter"], a)

        self._with_fault("frozen_counter", frozen)

        def listener(c, srv):
            time.sleep(0.4)
            with self.assertRaises(OSError):  # the connection is closed ...
                c.read_inputs()
            with self.assertRaises(OSError):  # ... and nothing listens for 1 s ...
                RawModbus(srv.port)
            time.sleep(1.0)
            d = RawModbus(srv.port)  # ... then the same port again
            d.read_inputs()
            d.close()

        recs = self._with_fault("drop_listener=1", listener)
        self.assertEqual([r["ev"] for r in recs if r["ev"] in ("listen", "listener_closed")][:3],
                         ["listen", "listener_closed", "listen"])


class FaultMatrix(unittest.TestCase):
    root: Path = None

    def _run(self, name):
        case = CASES[name]
        pending = STARTED.pop(name, None)
        out = pending.result() if pending else run_case(name, case, PYTHON, self.root)
        RESULTS.append(out)
        status = "PASS" if not out.problems else "FAIL"
        print(f"[{status}] {name:16s} exit {out.exit_code}  {out.wall_s:5.1f} s  "
              f"({case.fault}; expect {sorted(case.expect_exit)})", flush=True)
        for f in out.facts:
            print(f"         . {f}", flush=True)
        for pr in out.problems:
            print(f"         ! {pr}", flush=True)
        if out.problems:
            self.fail(f"{name}: " + "; ".join(out.problems))


def make_case_test(name):
    def t(self):
        self._run(name)
    t.__name__ = f"test_{name}"
    t.__doc__ = f"{name}: {CASES[name].note}"
    return t


def main(argv: list[str]) -> int:
    global PYTHON
    if "--list" in argv:
        for n, c in CASES.items():
            print(f"{n:16s} --fault {c.fault:18s} exit {sorted(c.expect_exit)}  {c.note}")
        return 0
    names = [a for a in argv if not a.startswith("-")]
    env_cases = os.environ.get("GOVERNOR_CASES", "")
    names += [n.strip() for n in env_cases.split(",") if n.strip()]
    unknown = [n for n in names if n not in CASES and n != "server"]
    if unknown:
        print(f"unknown case(s): {', '.join(unknown)}; known: server, {', '.join(CASES)}",
              file=sys.stderr)
        return 2
    selected = names or ["server", *CASES]
    rig = RIG_BIN_DIR / "rig"
    if any(n in CASES for n in selected) and not os.access(rig, os.X_OK):
        print(f"{rig}: not found or not executable (set RIG_BIN_DIR)", file=sys.stderr)
        print("0 passed, 1 failed")
        return 1
    PYTHON = server_python()
    keep_env = os.environ.get("GOVERNOR_WORK_DIR")
    root = Path(keep_env) if keep_env else Path(tempfile.mkdtemp(prefix="governor_matrix_"))
    root.mkdir(parents=True, exist_ok=True)
    FaultMatrix.root = root
    print(f"governor fault matrix: rig {rig}, server python {PYTHON}, files in {root}",
          flush=True)

    jobs = max(1, int(os.environ.get("GOVERNOR_JOBS", DEFAULT_JOBS)))
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=jobs) if jobs > 1 else None
    if pool:
        for n in selected:
            if n in CASES:
                STARTED[n] = pool.submit(run_case, n, CASES[n], PYTHON, root)
        print(f"{len(STARTED)} cases, {jobs} at a time", flush=True)

    suite = unittest.TestSuite()
    for n in selected:
        if n == "server":
            suite.addTest(ServerSelfCheck("test_server_map"))
            suite.addTest(ServerSelfCheck("test_server_faults"))
        else:
            setattr(FaultMatrix, f"test_{n}", make_case_test(n))
            suite.addTest(FaultMatrix(f"test_{n}"))
    result = unittest.TextTestRunner(verbosity=1, stream=sys.stdout).run(suite)
    if pool:
        pool.shutdown(wait=True)
    failed = len(result.failures) + len(result.errors)
    passed = result.testsRun - failed
    if RESULTS:
        print("\ncase             exit  wall   result")
        for o in RESULTS:
            print(f"{o.name:16s} {str(o.exit_code):>4s} {o.wall_s:5.1f}s  "
                  f"{'pass' if not o.problems else 'FAIL: ' + ' | '.join(o.problems)}")
    if failed == 0 and not keep_env:
        shutil.rmtree(root, ignore_errors=True)
    else:
        print(f"files kept in {root}")
    print(f"{passed} passed, {failed} failed", flush=True)
    return 0 if failed == 0 else 1


PYTHON = sys.executable

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
