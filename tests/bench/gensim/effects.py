"""The effects gensim can hide, each where a generator set has it, with its physical
parameter, two sizes, and the truth in the units of `rig diagnose`'s parameter.

Sizes of the actuator-side effects scale with the rack motion the excitation causes
(Scales: rms rack deviation and rate per % of bias, from the linearised set and the
excitation's spectrum), so "large" means the same thing whatever the tuning.
"""
import math
from dataclasses import dataclass, field

import numpy as np

import genset as g

# Truths in rig units need the rack per % of bias. The rack's response to the bias is not
# flat (the PI governor's proportional path above ~0.2 Hz, its integral below), so the scale
# is the rms rack deviation over the rms bias for the rig's 4 Hz Gaussian bias.


@dataclass
class Scales:
    rack0: float          # operating rack, pu
    rack_rms: float       # rms rack deviation for the 0.8 % bias, pu
    rate_rms: float       # rms rack rate, pu/s
    rack_per_pct: float   # rack_rms / bias rms
    zeta0: float          # damping ratio of the least damped closed-loop mode (swing)
    f0_hz: float          # its frequency


def modes(p):
    """Closed-loop oscillatory modes (freq Hz, zeta) of the linearised set (loop delay as
    its Pade approximant)."""
    a, b, c_r, c_pf, _ = g.linearise(p)
    pa, pb, pc, pd = g._pade_ss(p["t_d"], g.PADE_ORDER)
    n, m = g.NX, len(pa)
    big = np.zeros((n + m, n + m))
    big[:n, :n] = a + np.outer(b[:, 1], c_pf) + np.outer(b[:, 2], c_r) * pd[0, 0]
    big[:n, n:] = np.outer(b[:, 2], pc[0])
    big[n:, :n] = np.outer(pb[:, 0], c_r)
    big[n:, n:] = pa
    ev = np.linalg.eigvals(big)
    ev = ev[ev.imag > 1e-6]
    return sorted((abs(e) / (2 * math.pi), -e.real / abs(e)) for e in ev)


def scales(p=None):
    p = p or g.NOMINAL
    a, b, c_r, c_pf, _ = g.linearise(p)
    a_loop = a + np.outer(b[:, 1], c_pf)
    f = np.linspace(0.005, 20.0, 4000)
    w = 2 * math.pi * f
    hr = np.array([c_r @ np.linalg.solve(1j * wi * np.eye(g.NX) - a_loop
                                         - np.outer(b[:, 2], c_r) * np.exp(-1j * wi * p["t_d"]),
                                         b[:, 0]) for wi in w])
    su = 1.0 / (1.0 + (f / g.BAND_HZ) ** 8)  # 4th-order Butterworth power response
    norm = np.trapz(su, f)
    rack_rms = g.BIAS_RMS * math.sqrt(np.trapz(np.abs(hr) ** 2 * su, f) / norm)
    rate_rms = g.BIAS_RMS * math.sqrt(np.trapz((w * np.abs(hr)) ** 2 * su, f) / norm)
    _, rack0 = g.steady_state(p)
    f0, z0 = min(modes(p), key=lambda m: m[1])
    return Scales(float(rack0[0]), rack_rms, rate_rms, rack_rms / g.BIAS_RMS, z0, f0)


@dataclass
class Effect:
    name: str            # the DESIGN.md 9 word it should be named by
    place: str           # where it sits in the set
    key: str             # the simulator parameter
    unit: str
    sizes: dict          # size name -> function(Scales) -> physical value
    truth: object = None  # function(value, Scales) -> rig parameter (None: not compared)
    rig_param: str = ""
    accept: tuple = ()   # other verdicts counted right
    extra: dict = field(default_factory=dict)  # other simulator parameters set with it


def _swing_zeta(d_g):
    """The damping ratio, after the change, of the mode least damped before it."""
    s = scales()
    return min(modes(g.with_params(d_g=d_g)), key=lambda m: abs(m[0] - s.f0_hz))[1]


def _shaft_hz(k_s):
    ms = modes(g.with_params(k_s=k_s, c_s=RES_C_S))
    guess = SHAFT_HZ * math.sqrt(k_s / N0["k_s"])  # the mode scales with sqrt(stiffness)
    return min(ms, key=lambda m: abs(m[0] - guess))[0]


N0 = g.NOMINAL
RES_C_S = 2.0          # a worn flexible coupling: damping 25 -> 2 pu (mode damping 0.07-0.05)
SHAFT_HZ = 14.2        # the nominal shaft mode
RIPPLE_KW = {"large": 5.0, "small": 2.0}  # power ripple amplitude at the sensor


def _ripple_pu(kw):
    """Torque ripple amplitude (pu) giving kw of power ripple at the transducer."""
    return kw / calibrate_ripple()


RIPPLE_GAIN_KW_PER_PU = None  # kW of power ripple per pu of torque ripple


def calibrate_ripple():
    """Measured once on a deterministic 4 s run (the shaft and swing filter the ripple)."""
    global RIPPLE_GAIN_KW_PER_PU
    if RIPPLE_GAIN_KW_PER_PU is None:
        # two columns: numpy's arithmetic, which the value was first measured with
        p = g.with_params(ripple_pu=np.array([0.01, 0.01]))
        r = g.simulate(np.zeros(400), p, deterministic=True)
        y = r["y"][100:, 0]
        RIPPLE_GAIN_KW_PER_PU = (y.max() - y.min()) / 2 / 0.01
    return RIPPLE_GAIN_KW_PER_PU


EFFECTS = {e.name: e for e in [
    Effect("dead_time", "fuel transport (injection) delay", "t_d", "s",
           {"large": lambda s: N0["t_d"] + 0.030, "small": lambda s: N0["t_d"] + 0.012},
           lambda v, s: v - N0["t_d"], "extra_delay_s"),
    Effect("extra_lag", "combustion (fuel-to-torque) lag", "t_c", "s",
           {"large": lambda s: N0["t_c"] + 0.060, "small": lambda s: N0["t_c"] + 0.025},
           lambda v, s: v - N0["t_c"], "time_constant_s", ("sensor_lag",)),
    Effect("sensor_lag", "power transducer lag", "t_m", "s",
           {"large": lambda s: N0["t_m"] + 0.060, "small": lambda s: N0["t_m"] + 0.025},
           lambda v, s: v - N0["t_m"], "time_constant_s", ("extra_lag",)),
    Effect("gain_change", "power transducer gain (CT ratio)", "gain", "ratio",
           {"large": lambda s: 0.92, "small": lambda s: 0.97},
           lambda v, s: v, "gain_ratio"),
    Effect("rate_limit", "actuator slew limit", "slew", "pu rack/s",
           {"large": lambda s: 1.0 * s.rate_rms, "small": lambda s: 2.0 * s.rate_rms},
           lambda v, s: v / s.rack_per_pct, "rate_limit_per_s"),
    Effect("saturation", "actuator travel limit (rack stop) above the operating rack",
           "rack_max", "pu rack",
           {"large": lambda s: s.rack0 + 1.0 * s.rack_rms, "small": lambda s: s.rack0 + 1.8 * s.rack_rms},
           lambda v, s: (v - s.rack0) / s.rack_per_pct, "upper_limit"),
    Effect("deadband", "governor power-error deadband", "deadband", "pu power (half width)",
           {"large": lambda s: 0.002, "small": lambda s: 0.0008},
           lambda v, s: 100.0 * v, "half_width"),
    Effect("backlash", "linkage play between actuator and rack", "play", "pu rack (full width)",
           {"large": lambda s: 1.0 * s.rack_rms, "small": lambda s: 0.4 * s.rack_rms},
           lambda v, s: 0.5 * v / s.rack_per_pct, "half_width"),
    Effect("hysteresis", "actuator hysteresis (Bouc-Wen, 30 % linear)", "bw_z0", "pu rack",
           {"large": lambda s: 0.5 * s.rack_rms, "small": lambda s: 1.0 * s.rack_rms},
           None, "", ("backlash",)),
    Effect("static_nonlinearity", "fuel-map kink at the operating rack", "kink",
           "slope change above the operating point",
           {"large": lambda s: 0.6, "small": lambda s: 0.25}, None, ""),
    Effect("resonance", "shaft torsional mode in the band (worn flexible coupling)", "k_s",
           "pu torque/rad",
           {"large": lambda s: N0["k_s"] * (4.5 / 14.2) ** 2,
            "small": lambda s: N0["k_s"] * (7.0 / 14.2) ** 2},
           lambda v, s: _shaft_hz(v), "freq_hz", (), {"c_s": RES_C_S}),
    Effect("load_damping", "alternator damping (damper windings)", "d_g", "pu torque/pu slip",
           {"large": lambda s: 2.0 * N0["d_g"], "small": lambda s: 1.4 * N0["d_g"]},
           lambda v, s: _swing_zeta(v), "zeta"),
    Effect("periodic_disturbance", "torque ripple at the half order (cylinder imbalance)",
           "ripple_pu", "pu torque",
           {"large": lambda s: _ripple_pu(RIPPLE_KW["large"]),
            "small": lambda s: _ripple_pu(RIPPLE_KW["small"])},
           lambda v, s: N0["ripple_order"] * N0["rpm"] / 60.0, "freq_hz"),
    Effect("drift", "power transducer zero drift (60 s)", "drift_kw", "kW rms",
           {"large": lambda s: 20.0, "small": lambda s: 8.0}, None, ""),
    Effect("ac_coupling", "undeclared analogue AC coupling of the transducer", "ac_rc_s", "s",
           {"large": lambda s: 4.0, "small": lambda s: 15.0}, lambda v, s: v, "rc_s"),
]}

DISTURBANCES = ("periodic_disturbance", "drift")


def lag_class(name):
    return "lag" if name in ("extra_lag", "sensor_lag") else name
