#!/usr/bin/env python3
"""An independent electronic-governor emulator serving the Modbus TCP map of DESIGN.md section 6.

It is written from the register map alone (not from plantsim) so that `rig commission --link`
can be tested against a second, independent implementation of the governor side, with faults
a real governor or its network can produce. Every write request it receives is logged as one
JSON object per line (`--log`); the log, not the rig's own report, is what the fault-matrix
test judges.

Register map (unit id: any; holding via 03/06/16/23, input via 04):

  holding 0  bias, int16, 0.001 % of rated power per bit
  holding 1  heartbeat; if it has not changed for 500 ms while enabled the applied bias drops
             to zero as a step and status bit 3 is set (latched until enable is cleared)
  holding 2  control word, bit 0 = enable external bias
  (no holding 100: this is a real-time governor; other addresses answer exception 02)
  input 0-1  electrical power, int32 W, high word first (INT32_MIN = not available)
  input 2    engine speed, uint16, 0.1 rpm
  input 3    bus frequency, uint16, 0.001 Hz
  input 4    terminal voltage, uint16, 1 V
  input 5    applied bias echo, int16, 0.001 %  (the bias actually applied)
  input 6    status: bit0 running, bit1 breaker closed, bit2 bias active, bit3 heartbeat lost,
             bit4 plant fault
  input 7-8  plant time, uint32 ms, high word first
  input 9    sample counter, uint16, +1 per plant tick

Plant: P = P0 + G(s) u + noise, G(s) = K wn^2 / (s^2 + 2 zeta wn s + wn^2) e^(-s Td) with
K = rated/100 kW per % of bias, wn = 2 pi 2 Hz, zeta = 0.1, Td = 60 ms; integrated exactly
(zero-order hold) by a thread at --tick-hz (default 1 kHz) in wall time.

Written against pymodbus 3.0.x (Debian 12's python3-pymodbus 3.0.0): a ModbusTcpServer
object supplies the decoder, framer and datastore context; the listening socket is managed
here (so that it can be closed and reopened), and a ModbusConnectedRequestHandler subclass
overrides execute() to log every request and apply the fault modes.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import math
import random
import signal
import sys
import threading
import time
from collections import deque

def _stub_serial_asyncio() -> None:
    """pymodbus 3.0's server module imports serial_asyncio (python3-serial-asyncio, only a
    Recommends of Debian's python3-pymodbus, so absent after --no-install-recommends) even for
    TCP. This server never opens a serial port: a stub module lets the import succeed."""
    try:
        import serial_asyncio  # noqa: F401
    except ImportError:
        import types

        stub = types.ModuleType("serial_asyncio")

        def create_serial_connection(*_a, **_k):
            raise RuntimeError("serial_asyncio is not installed (stub from governor_server)")

        stub.create_serial_connection = create_serial_connection
        sys.modules["serial_asyncio"] = stub


_stub_serial_asyncio()

try:
    import pymodbus
    from pymodbus.datastore import ModbusServerContext
    from pymodbus.interfaces import IModbusSlaveContext
    from pymodbus.pdu import ExceptionResponse
    from pymodbus.server.async_io import ModbusConnectedRequestHandler, ModbusTcpServer
except ImportError as exc:  # pragma: no cover
    sys.stderr.write(f"governor_server: pymodbus is required ({exc}); on Debian: "
                     "apt-get install python3-pymodbus, run with /usr/bin/python3\n")
    sys.exit(2)

INT32_MIN = -(2**31)
INT32_MAX = 2**31 - 1

# Status bits (DESIGN.md section 6).
ST_RUNNING = 1 << 0
ST_BREAKER = 1 << 1
ST_BIAS_ACTIVE = 1 << 2
ST_HB_LOST = 1 << 3
ST_PLANT_FAULT = 1 << 4

HOLDING_COUNT = 3   # holding 0..2
INPUT_COUNT = 10    # input 0..9

WRITE_FCS = {6, 16, 23}
# The plant falling this far behind wall time is logged as a `stall` (the bias was held).
STALL_LOG_S = 0.05

# name -> (strikes at: "start" | "fault_at", default value, default duration in s (None: for
# the rest of the run; 0: one-shot action), help)
FAULTS = {
    "none": ("start", None, None, "honest governor"),
    "exception06": ("fault_at", None, 2.0,
                    "every write answers exception 06 (server busy) and is not applied"),
    "late": ("fault_at", 1.5, 2.0,
             "every request (read or write) is answered VALUE s late (default 1.5); a write "
             "takes effect when it is answered"),
    "frozen_counter": ("fault_at", None, None, "input 9 (sample counter) stops moving"),
    "power_jump": ("fault_at", 8.0, None, "power steps by +VALUE % of P0 (default 8)"),
    "drop_connection": ("fault_at", None, None,
                        "every client connection is closed once; the server keeps listening"),
    "drop_listener": ("fault_at", 2.0, None,
                      "connections closed and the port not listening for VALUE s (default 2)"),
    "nan": ("fault_at", None, None, "power reads INT32_MIN (not available)"),
    "absurd": ("fault_at", "power", None,
               "VALUE=power: power reads 2e9 W; speed: speed reads 0; freq: frequency reads 0"),
    "refuse_writes": ("fault_at", 4, 2.0,
                      "writes touching holding 0 answer exception VALUE (default 4, server "
                      "device failure; 1 = illegal function) and are not applied"),
    "bias_ignored": ("start", None, None,
                     "enable never honoured: bit 2 never set, echo 0, power does not respond"),
    "honoured_late": ("fault_at", None, None,
                      "enable honoured only from --fault-at on (bit 2 clear, echo 0 before)"),
    "scaled": ("start", 3.0, None,
               "applies bias * VALUE (default 3); the echo shows what is applied"),
    "quiet": ("start", None, None, "measurement noise 0.04 % of P0 rms (1.4 kW)"),
    "plant_fault": ("fault_at", None, None, "status bit 4 (plant fault) set"),
    "revoked": ("fault_at", None, None,
                "governor takes the bias back (local control): bit 2 clears, echo 0, the "
                "applied bias steps to 0 while enable stays set"),
}


def now() -> float:
    return time.monotonic()


class JsonLog:
    """One JSON object per line, flushed per line, shared by the threads."""

    def __init__(self, path: str | None, t0: float):
        self._f = open(path, "a", encoding="utf-8") if path else None
        self._lock = threading.Lock()
        self.t0 = t0

    def t(self, at: float | None = None) -> float:
        return round((now() if at is None else at) - self.t0, 6)

    def write(self, obj: dict) -> None:
        if self._f is None:
            return
        line = json.dumps(obj, separators=(",", ":"))
        with self._lock:
            self._f.write(line + "\n")
            self._f.flush()

    def close(self) -> None:
        with self._lock:
            if self._f:
                self._f.close()
                self._f = None


def to_u16(v: int) -> int:
    return v & 0xFFFF


def from_i16(v: int) -> int:
    v &= 0xFFFF
    return v - 0x10000 if v & 0x8000 else v


class Plant:
    """Second-order plus dead time bias-to-power response, ZOH-discretised."""

    def __init__(self, gain: float, fn_hz: float, zeta: float, dead_time_s: float, dt: float):
        wn = 2.0 * math.pi * fn_hz
        a = [[0.0, 1.0], [-wn * wn, -2.0 * zeta * wn]]
        b = [0.0, gain * wn * wn]
        # Phi = e^(A dt), Gamma = int_0^dt e^(A s) ds B, by their (fast converging) series.
        phi = [[1.0, 0.0], [0.0, 1.0]]
        psi = [[dt, 0.0], [0.0, dt]]  # int_0^dt e^(A s) ds
        term = [[1.0, 0.0], [0.0, 1.0]]
        for k in range(1, 30):
            term = [[sum(term[i][m] * a[m][j] for m in range(2)) * dt / k for j in range(2)]
                    for i in range(2)]
            for i in range(2):
                for j in range(2):
                    phi[i][j] += term[i][j]
                    psi[i][j] += term[i][j] * dt / (k + 1)
        self.phi = phi
        self.gamma = [psi[0][0] * b[0] + psi[0][1] * b[1], psi[1][0] * b[0] + psi[1][1] * b[1]]
        self.x = [0.0, 0.0]
        n = max(0, int(round(dead_time_s / dt)))
        self.delay = deque([0.0] * n)

    def step(self, u: float) -> float:
        if self.delay:
            self.delay.append(u)
            u = self.delay.popleft()
        x0, x1 = self.x
        p = self.phi
        self.x = [p[0][0] * x0 + p[0][1] * x1 + self.gamma[0] * u,
                  p[1][0] * x0 + p[1][1] * x1 + self.gamma[1] * u]
        return self.x[0]


class Governor:
    """Registers, governor rules, plant thread and faults. All state under one lock."""

    def __init__(self, args, log: JsonLog):
        self.args = args
        self.log = log
        self.lock = threading.RLock()
        self.fault = args.fault_name
        spec = FAULTS[self.fault]
        self.fault_starts = spec[0]
        self.fault_value = args.fault_value if args.fault_value is not None else spec[1]
        self.fault_for = args.fault_for if args.fault_for is not None else spec[2]
        self.rated_kw = args.rated_kw
        self.p0_kw = args.p0_kw
        self.noise_kw = args.noise_kw
        if self.fault == "quiet":
            self.noise_kw = 0.0004 * self.p0_kw
        self.dt = 1.0 / args.tick_hz
        gain = args.gain_kw_per_pct if args.gain_kw_per_pct is not None else self.rated_kw / 100.0
        self.plant = Plant(gain, args.fn_hz, args.zeta, args.dead_time_ms / 1000.0, self.dt)
        self.rng = random.Random(args.seed)
        self.holding = [0, 0, 0]
        self.inputs = [0] * INPUT_COUNT
        self.counter = 0
        self.plant_t0 = now()
        self.enabled = False
        self.first_enable: float | None = None
        self.hb_last_change = now()
        self.hb_lost = False
        self.honoured = False
        self.applied_pct = 0.0
        self.y_kw = 0.0
        self.power_kw = self.p0_kw
        self.reads = 0
        self.writes = 0
        self.fault_was_active = False
        self.fault_read_logged = False  # the first input read served with the fault on
        self.last_write_applied = (0.0, 0.0)
        self.ticks = 0
        self.next_tick_t = self.plant_t0 + self.dt
        self.noise = (0.0, 0.0, 0.0)
        self._stop = threading.Event()
        self._publish(0.0)

    # ---- fault timing -------------------------------------------------------------------
    def fault_time(self) -> float | None:
        """Absolute (monotonic) time the fault strikes, None before the first enable."""
        if self.fault == "none":
            return None
        if self.fault_starts == "start":
            return self.plant_t0
        if self.first_enable is None:
            return None
        return self.first_enable + self.args.fault_at

    def fault_active(self, at: float | None = None) -> bool:
        ft = self.fault_time()
        if ft is None:
            return False
        if self.fault in ("drop_connection", "drop_listener"):
            return False  # one-shot network actions (fault_actions), not a data fault
        at = now() if at is None else at
        if at < ft:
            return False
        return self.fault_for is None or at < ft + self.fault_for

    def is_(self, name: str, at: float | None = None) -> bool:
        return self.fault == name and self.fault_active(at)

    # ---- governor rules -------------------------------------------------------------------
    def _update_rules(self, t: float) -> None:
        enable = bool(self.holding[2] & 1)
        if enable and not self.enabled:
            # Rising edge: arm, restart the heartbeat window.
            self.hb_lost = False
            self.hb_last_change = t
            if self.first_enable is None:
                self.first_enable = t
            self.log.write({"t": self.log.t(t), "ev": "enable", "first": self.first_enable == t})
        elif not enable and self.enabled:
            self.hb_lost = False
            self.log.write({"t": self.log.t(t), "ev": "disable"})
        self.enabled = enable
        if enable and not self.hb_lost and t - self.hb_last_change > self.args.heartbeat_ms / 1000.0:
            self.hb_lost = True
            self.log.write({"t": self.log.t(t), "ev": "heartbeat_lost",
                            "since_change_s": round(t - self.hb_last_change, 4)})
        honoured = enable and not self.hb_lost
        if self.fault == "bias_ignored":
            honoured = False
        if self.fault == "honoured_late" and not self.fault_active(t):
            honoured = False
        if self.is_("revoked", t):
            honoured = False
        self.honoured = honoured
        if honoured:
            cmd = from_i16(self.holding[0]) * 0.001
            if self.fault == "scaled":
                cmd *= float(self.fault_value)
            c = self.args.clamp_pct
            self.applied_pct = max(-c, min(c, cmd))
        else:
            self.applied_pct = 0.0

    def _publish(self, t_rel: float, new_sample: bool = True) -> None:
        """Input registers from the plant state; new_sample: a plant tick (fresh noise)."""
        if new_sample:
            self.noise = (self.rng.gauss(0.0, self.noise_kw) if self.noise_kw > 0 else 0.0,
                          self.rng.gauss(0.0, 0.05), self.rng.gauss(0.0, 0.001))
        p = self.p0_kw + self.y_kw + self.noise[0]
        if self.is_("power_jump"):
            p += float(self.fault_value) / 100.0 * self.p0_kw
        self.power_kw = p
        w = int(round(p * 1000.0))
        w = max(INT32_MIN + 1, min(INT32_MAX, w))
        speed = 600.0 + self.noise[1]
        freq = 50.0 + self.noise[2]
        if self.is_("nan"):
            w = INT32_MIN
        if self.is_("absurd"):
            what = str(self.fault_value)
            if what == "power":
                w = 2_000_000_000
            elif what == "speed":
                speed = 0.0
            elif what == "freq":
                freq = 0.0
        status = ST_RUNNING | ST_BREAKER
        if self.honoured:
            status |= ST_BIAS_ACTIVE
        if self.hb_lost:
            status |= ST_HB_LOST
        if self.is_("plant_fault"):
            status |= ST_PLANT_FAULT
        ms = int(t_rel * 1000.0) & 0xFFFFFFFF
        uw = w & 0xFFFFFFFF
        self.inputs = [
            (uw >> 16) & 0xFFFF, uw & 0xFFFF,
            max(0, min(0xFFFF, int(round(speed * 10.0)))),
            max(0, min(0xFFFF, int(round(freq * 1000.0)))),
            11000,
            to_u16(int(round(self.applied_pct * 1000.0))),
            status,
            (ms >> 16) & 0xFFFF, ms & 0xFFFF,
            self.counter & 0xFFFF,
        ]

    def advance_to(self, t: float) -> None:
        """Run every plant tick due by wall time t (lock held). Tick k is due at t0 + k dt.

        The plant thread calls this at the tick rate; every read and write calls it first too,
        so an answer always reflects wall time even if the thread was not scheduled for a while
        (a loaded machine): the counter then jumps, it never lags."""
        behind_s = t - self.next_tick_t
        if behind_s >= STALL_LOG_S:
            # Not scheduled for a while (a loaded machine): the plant ran on with the bias held.
            # Logged so that a band trip it causes is not taken for the rig's own doing.
            self.log.write({"t": self.log.t(t), "ev": "stall", "behind_s": round(behind_s, 4),
                            "held_pct": round(self.applied_pct, 3)})
        while self.next_tick_t <= t:
            self._update_rules(self.next_tick_t)
            self.y_kw = self.plant.step(self.applied_pct)
            self.ticks += 1
            if not self.is_("frozen_counter", self.next_tick_t):
                self.counter = (self.counter + 1) & 0xFFFF
            self._publish(self.ticks * self.dt)
            self.next_tick_t = self.plant_t0 + (self.ticks + 1) * self.dt
        self._fault_transitions(t)

    def run_plant(self) -> None:
        """Plant thread: ticks at --tick-hz in wall time; catches up after a late wake-up."""
        next_state = self.plant_t0
        while not self._stop.is_set():
            t = now()
            with self.lock:
                self.advance_to(t)
                if self.args.state_interval > 0 and t >= next_state:
                    self.log.write(self.state_record("state", t))
                    next_state += self.args.state_interval
                    if next_state < t:
                        next_state = t + self.args.state_interval
                delay = self.next_tick_t - now()
            if delay > 0:
                time.sleep(delay)

    def _fault_transitions(self, t: float) -> None:
        active = self.fault_active(t)
        if active and not self.fault_was_active:
            self.log.write({"t": self.log.t(t), "ev": "fault_on", "fault": self.fault,
                            "value": self.fault_value, "for_s": self.fault_for})
        elif not active and self.fault_was_active:
            self.log.write({"t": self.log.t(t), "ev": "fault_off", "fault": self.fault})
        self.fault_was_active = active

    def state_record(self, ev: str, t: float | None = None) -> dict:
        return {"t": self.log.t(t), "ev": ev, "holding": list(self.holding),
                "bias_cmd_pct": round(from_i16(self.holding[0]) * 0.001, 3),
                "enable": self.enabled, "honoured": self.honoured, "hb_lost": self.hb_lost,
                "applied_pct": round(self.applied_pct, 3), "status": self.inputs[6],
                "power_kw": round(self.power_kw, 2), "y_kw": round(self.y_kw, 3),
                "counter": self.counter, "reads": self.reads, "writes": self.writes}

    def stop(self) -> None:
        self._stop.set()

    # ---- register access (from the asyncio thread) ------------------------------------------
    def read_inputs(self, address: int, count: int) -> list[int]:
        with self.lock:
            t = now()
            self.advance_to(t)
            self.reads += 1
            if self.fault_was_active and not self.fault_read_logged:
                # The first read that can tell the rig about the fault: a write it sends
                # before this one cannot be a reaction to it (fault_matrix_test (f)).
                self.fault_read_logged = True
                self.log.write({"t": self.log.t(t), "ev": "fault_read", "addr": address,
                                "count": count})
            return list(self.inputs[address:address + count])

    def read_holding(self, address: int, count: int) -> list[int]:
        with self.lock:
            return list(self.holding[address:address + count])

    def write_holding(self, address: int, values: list[int]) -> None:
        with self.lock:
            t = now()
            self.advance_to(t)
            # The rules at t before the write: a fault that struck since the last tick (revoked)
            # is the governor's own step, not the write's.
            self._update_rules(t)
            self.writes += 1
            before = self.applied_pct
            for i, v in enumerate(values):
                reg = address + i
                if reg == 1 and (v & 0xFFFF) != self.holding[1]:
                    self.hb_last_change = t
                self.holding[reg] = v & 0xFFFF
            self._update_rules(t)
            self._publish(self.ticks * self.dt, new_sample=False)
            # Only writes (asyncio thread) set this; the handler logs it with the write.
            self.last_write_applied = (round(before, 3), round(self.applied_pct, 3))


class GovernorContext(IModbusSlaveContext):
    """The datastore seen by pymodbus: holding 0..2, input 0..9, nothing else (exception 02)."""

    def __init__(self, gov: Governor):
        self.gov = gov

    def reset(self):
        pass

    def validate(self, fx, address, count=1):
        kind = self.decode(fx)
        if kind == "h":
            return 0 <= address and address + count <= HOLDING_COUNT and count >= 1
        if kind == "i":
            return 0 <= address and address + count <= INPUT_COUNT and count >= 1
        return False

    def getValues(self, fx, address, count=1):
        if self.decode(fx) == "i":
            return self.gov.read_inputs(address, count)
        return self.gov.read_holding(address, count)

    def setValues(self, fx, address, values):
        if self.decode(fx) == "h":
            self.gov.write_holding(address, list(values))


def describe_write(request) -> tuple[int, list[int], bool] | None:
    """(first register, values, is a holding-register write) of a write request; None for a
    read. Coil writes (05, 15) and mask writes (22) are logged too, and refused."""
    fc = request.function_code
    if fc == 6:
        return request.address, [request.value], True
    if fc == 16:
        return request.address, list(request.values), True
    if fc == 23:
        return request.write_address, list(request.write_registers), True
    if fc == 5:
        return request.address, [int(bool(request.value))], False
    if fc == 15:
        return request.address, [int(bool(v)) for v in request.values], False
    if fc == 22:
        return request.address, [request.and_mask, request.or_mask], False
    return None


class GovernorHandler(ModbusConnectedRequestHandler):
    """One client connection. execute() is called by pymodbus for every decoded request."""

    gov: Governor = None  # set before the listener starts
    log: JsonLog = None
    seq = 0

    def connection_made(self, transport):
        super().connection_made(transport)
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if peer else "?"
        self.log.write({"t": self.log.t(), "ev": "connect", "peer": self.peer})

    def connection_lost(self, call_exc):
        self.log.write({"t": self.log.t(), "ev": "disconnect", "peer": getattr(self, "peer", "?"),
                        "reason": str(call_exc) if call_exc else "closed"})
        super().connection_lost(call_exc)

    def execute(self, request, *addr):
        gov = self.gov
        t_rx = now()
        w = describe_write(request)
        GovernorHandler.seq += 1
        seq = GovernorHandler.seq
        with gov.lock:
            late = gov.is_("late", t_rx)
            if w is not None:
                first, values, holding = w
                regs = range(first, first + len(values)) if holding else range(0)
                if request.function_code == 22:
                    refuse = 1  # mask write: not supported by this governor (illegal function)
                elif gov.is_("exception06", t_rx):
                    refuse = 6
                elif gov.is_("refuse_writes", t_rx) and 0 in regs:
                    refuse = int(gov.fault_value)
                else:
                    refuse = None
            else:
                refuse = None
        # A slow governor answers its requests in order: a request is answered after the one
        # before it on the same connection, and after the fault's delay when it is late.
        answer_at = max(t_rx + (float(gov.fault_value) if late else 0.0),
                        getattr(self, "busy_until", 0.0))
        self.busy_until = answer_at
        if answer_at > t_rx:
            if w is not None:
                self._log_write(seq, t_rx, None, request, w, "deferred", None)
            asyncio.get_running_loop().call_later(answer_at - t_rx, self._process, seq, t_rx,
                                                  request, w, refuse, addr)
        else:
            self._process(seq, t_rx, request, w, refuse, addr)

    def _process(self, seq, t_rx, request, w, refuse, addr):
        if refuse is not None:
            response = ExceptionResponse(request.function_code, refuse)
            result = "exception"
        else:
            try:
                response = request.execute(self.server.context[request.unit_id])
            except Exception as exc:  # noqa: BLE001 - a datastore bug must still answer
                self.log.write({"t": self.log.t(), "ev": "error", "text": repr(exc)})
                response = ExceptionResponse(request.function_code, 4)
            if isinstance(response, ExceptionResponse):
                result = "exception"
                refuse = response.exception_code
            else:
                result = "ok"
        if w is not None:
            applied = self.gov.last_write_applied if result == "ok" else None
            self._log_write(seq, t_rx, now(), request, w, result, refuse, applied)
        elif request.function_code == 3:
            # Holding reads are rare (a rig reading back what the governor holds): log them.
            rec = {"t": self.log.t(), "ev": "read_holding", "seq": seq, "t_rx": self.log.t(t_rx),
                   "addr": request.address, "count": request.count, "result": result,
                   "peer": getattr(self, "peer", "?")}
            if result == "ok":
                rec["values"] = list(response.registers)
            else:
                rec["exc"] = refuse
            self.log.write(rec)
        if w is None and request.function_code != 3 and result != "ok":
            self.log.write({"t": self.log.t(), "ev": "read_refused", "seq": seq,
                            "fc": request.function_code,
                            "addr": getattr(request, "address", None),
                            "count": getattr(request, "count", None), "exc": refuse,
                            "peer": getattr(self, "peer", "?")})
        response.transaction_id = request.transaction_id
        response.unit_id = request.unit_id
        if self.transport is None or self.transport.is_closing():
            return  # the client has gone; a write that arrived has still taken effect
        self.send(response, *addr)

    def _log_write(self, seq, t_rx, t_done, request, w, result, exc, applied=None):
        first, values, holding = w
        rec = {"t": self.log.t(t_done if t_done is not None else t_rx), "ev": "write",
               "seq": seq, "t_rx": self.log.t(t_rx), "fc": request.function_code,
               "addr": first, "values": values, "result": result,
               "peer": getattr(self, "peer", "?")}
        if exc is not None:
            rec["exc"] = exc
        if holding and first <= 0 < first + len(values):
            rec["bias_pct"] = round(from_i16(values[0 - first]) * 0.001, 3)
        if holding and first <= 2 < first + len(values):
            rec["enable"] = bool(values[2 - first] & 1)
        if applied is not None:  # the governor's applied bias just before and after the write
            rec["applied_before_pct"], rec["applied_after_pct"] = applied
        self.log.write(rec)


class Listener:
    """The listening socket, which drop_listener closes and reopens on the same port."""

    def __init__(self, mbserver: ModbusTcpServer, host: str, port: int, log: JsonLog):
        self.mb = mbserver
        self.host = host
        self.port = port
        self.log = log
        self.server: asyncio.base_events.Server | None = None

    async def open(self) -> None:
        loop = asyncio.get_running_loop()
        self.server = await loop.create_server(lambda: GovernorHandler(self.mb), self.host,
                                               self.port, reuse_address=True)
        self.port = self.server.sockets[0].getsockname()[1]
        self.log.write({"t": self.log.t(), "ev": "listen", "host": self.host, "port": self.port})

    def close_listener(self) -> None:
        if self.server is not None:
            self.server.close()
            self.server = None
            self.log.write({"t": self.log.t(), "ev": "listener_closed", "port": self.port})

    def drop_clients(self) -> int:
        handlers = list(self.mb.active_connections.values())
        for h in handlers:
            if h.transport is not None:
                h.transport.close()
        self.log.write({"t": self.log.t(), "ev": "clients_dropped", "count": len(handlers)})
        return len(handlers)


async def fault_actions(gov: Governor, listener: Listener) -> None:
    """One-shot network faults: drop_connection, drop_listener."""
    done = False
    while not done:
        await asyncio.sleep(0.005)
        if gov.fault not in ("drop_connection", "drop_listener"):
            return
        with gov.lock:
            ft = gov.fault_time()
        if ft is None or now() < ft:
            continue
        done = True
        log = listener.log
        log.write({"t": log.t(), "ev": "fault_on", "fault": gov.fault, "value": gov.fault_value})
        if gov.fault == "drop_connection":
            listener.drop_clients()
        else:
            listener.close_listener()
            listener.drop_clients()
            await asyncio.sleep(float(gov.fault_value))
            await listener.open()
        log.write({"t": log.t(), "ev": "fault_off", "fault": gov.fault})


async def main_async(args) -> int:
    t0 = now()
    log = JsonLog(args.log, t0)
    gov = Governor(args, log)
    GovernorHandler.gov = gov
    GovernorHandler.log = log
    context = ModbusServerContext(slaves=GovernorContext(gov), single=True)
    mbserver = ModbusTcpServer(context, address=(args.host, args.port))
    log.write({"t": 0.0, "ev": "start", "pymodbus": pymodbus.__version__,
               "fault": gov.fault, "fault_value": gov.fault_value, "fault_at_s": args.fault_at,
               "fault_for_s": gov.fault_for, "fault_starts": gov.fault_starts,
               "p0_kw": gov.p0_kw, "rated_kw": gov.rated_kw, "noise_kw": gov.noise_kw,
               "clamp_pct": args.clamp_pct, "tick_hz": args.tick_hz, "fn_hz": args.fn_hz,
               "zeta": args.zeta, "dead_time_ms": args.dead_time_ms,
               "heartbeat_ms": args.heartbeat_ms})
    listener = Listener(mbserver, args.host, args.port, log)
    await listener.open()
    print(f"PORT {listener.port}", flush=True)

    plant = threading.Thread(target=gov.run_plant, name="plant", daemon=True)
    plant.start()
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    actions = asyncio.create_task(fault_actions(gov, listener))
    if args.duration > 0:
        loop.call_later(args.duration, stop.set)
    await stop.wait()
    actions.cancel()
    gov.stop()
    plant.join(timeout=1.0)
    with gov.lock:
        log.write(gov.state_record("final"))
    listener.close_listener()
    listener.drop_clients()
    log.close()
    return 0


def parse_args(argv=None):
    fault_help = "; ".join(f"{k}: {v[3]}" for k, v in FAULTS.items())
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=1502, help="0: ephemeral, printed as 'PORT <n>'")
    p.add_argument("--log", help="JSON-lines log of every write request and the state")
    p.add_argument("--fault", default="none", metavar="NAME[=VALUE]", help=fault_help)
    p.add_argument("--fault-at", type=float, default=20.0,
                   help="seconds after the first enable at which the fault strikes (faults "
                        "marked 'start' act from the start)")
    p.add_argument("--fault-for", type=float, default=None,
                   help="fault duration in s (default per fault: exception06, late, "
                        "refuse_writes 2 s; others for the rest of the run)")
    p.add_argument("--noise-kw", type=float, default=5.0, help="white measurement noise, kW rms")
    p.add_argument("--p0-kw", type=float, default=3500.0)
    p.add_argument("--rated-kw", type=float, default=4600.0)
    p.add_argument("--gain-kw-per-pct", type=float, default=None, help="default rated/100")
    p.add_argument("--fn-hz", type=float, default=2.0)
    p.add_argument("--zeta", type=float, default=0.1)
    p.add_argument("--dead-time-ms", type=float, default=60.0)
    p.add_argument("--clamp-pct", type=float, default=5.0, help="governor's own bias clamp")
    p.add_argument("--heartbeat-ms", type=float, default=500.0)
    p.add_argument("--tick-hz", type=float, default=1000.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--state-interval", type=float, default=0.1,
                   help="s between state lines in the log (0: none)")
    p.add_argument("--duration", type=float, default=0.0, help="stop after this many s (0: never)")
    args = p.parse_args(argv)
    name, _, value = args.fault.partition("=")
    if name not in FAULTS:
        p.error(f"--fault {name}: unknown (one of {', '.join(FAULTS)})")
    args.fault_name = name
    args.fault_value = None
    if value:
        if name == "absurd":
            if value not in ("power", "speed", "freq"):
                p.error("--fault absurd=VALUE: power, speed or freq")
            args.fault_value = value
        else:
            try:
                args.fault_value = float(value)
            except ValueError:
                p.error(f"--fault {name}={value}: expected a number")
    if name == "refuse_writes" and args.fault_value is not None:
        args.fault_value = int(args.fault_value)
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    logging.basicConfig(level=logging.CRITICAL)
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    sys.setswitchinterval(0.0005)
    return asyncio.run(main_async(args))


if __name__ == "__main__":
    sys.exit(main())
