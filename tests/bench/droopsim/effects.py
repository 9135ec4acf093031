"""The effects droopsim can hide, each where a droop-governed set has it: the plant
parameter, a size range from "just detectable" to "clearly visible" (a case draws its size
from it, seeded), and the truth in `rig diagnose`'s parameter.

Actuator-side sizes scale with the rack motion the 1 % bias causes (linear.scales(): rms
rack deviation and rate over the bias spectrum); the rack per % of bias, their ratio to the
bias rms, converts rack-side values to the rig's %-of-bias parameters.
"""
import math
from dataclasses import dataclass, field

import numpy as np

import linear as ln
import plant as pl

N0 = pl.NOMINAL
_SCALES = None


def scales():
    global _SCALES
    if _SCALES is None:
        _SCALES = ln.scales()
    return _SCALES


@dataclass
class Effect:
    name: str            # the vocabulary word it should be named by
    place: str           # where it sits in the set
    key: str             # the plant parameter
    unit: str
    size_unit: str       # what the size x means
    lo: float            # x just detectable ...
    hi: float            # ... clearly visible (log-uniform draws between)
    value: object        # (x, scales, sign) -> plant parameter value
    truth: object = None  # (value, scales) -> rig parameter (None: not compared)
    rig_param: str = ""
    accept: tuple = ()   # other verdicts counted right
    extra: dict = field(default_factory=dict)  # other plant parameters set with it
    signed: bool = False  # a case draws the direction too
    scaled: bool = False  # candidates scale the value itself (nominal means "off")


def _coupling_hz(f_cpl):
    return ln.mode(pl.with_params(f_cpl=f_cpl, z_cpl=RES_Z), "coupling")[0]


def _swing_zeta(d_g):
    return ln.mode(pl.with_params(d_g=d_g), "swing")[1]


RES_Z = 0.08           # a hardened, cracked rubber coupling: softer and less damped
RIPPLE_ORDER_HZ = N0["ripple_order"] * N0["rpm"] / 60.0   # 12.5 Hz, the half order
_RIPPLE_KW_PER_PU = None


def ripple_kw_per_pu():
    """kW of power ripple (amplitude at y) per pu of torque ripple, from the exact response
    of the shaft, generator and transducer at the half order (governor loop included)."""
    global _RIPPLE_KW_PER_PU
    if _RIPPLE_KW_PER_PU is None:
        # torque -> y: y per % of bias divided by torque per % of bias, both exact
        f = np.array([RIPPLE_ORDER_HZ])
        a, b, _, c_pe = ln.mech(N0)
        s = 2j * math.pi * f[0]
        mp = c_pe @ np.linalg.solve(s * np.eye(6) - a, b)
        ma = (1 - np.exp(-s * N0["t_ma"])) / (s * N0["t_ma"])
        _RIPPLE_KW_PER_PU = abs(N0["p_rated_kw"] * ma / (1 + s * N0["t_m"]) * mp)
    return _RIPPLE_KW_PER_PU


def _add(key):
    return lambda x, s, sg: N0[key] + x


EFFECTS = {e.name: e for e in [
    Effect("dead_time", "injection delay (fixed part; + half a firing interval)", "t_dfix", "s",
           "added delay, s", 0.0085, 0.029, _add("t_dfix"),
           lambda v, s: v - N0["t_dfix"], "extra_delay_s"),
    Effect("extra_lag", "combustion (fuel-to-torque) lag", "t_c", "s", "added lag, s",
           0.009, 0.046, _add("t_c"), lambda v, s: v - N0["t_c"], "time_constant_s",
           ("sensor_lag",)),
    Effect("sensor_lag", "power transducer lag after the moving average", "t_m", "s",
           "added lag, s", 0.010, 0.048, _add("t_m"), lambda v, s: v - N0["t_m"],
           "time_constant_s", ("extra_lag",)),
    Effect("gain_change", "power transducer gain (CT ratio)", "gain", "ratio", "|1 - gain|",
           0.06, 0.16, lambda x, s, sg: 1.0 + sg * x, lambda v, s: v, "gain_ratio",
           signed=True),
    Effect("rate_limit", "servo velocity limit", "vmax", "pu rack/s",
           "rack rate rms / limit", 0.6, 1.2, lambda x, s, sg: s["rate_rms"] / x,
           lambda v, s: v / s["rack_per_pct"], "rate_limit_per_s", scaled=True),
    Effect("saturation", "smoke (boost) limiter just above the operating demand", "smoke",
           "pu rack above d0 at the operating air", "demand rms / margin", 0.45, 1.2,
           lambda x, s, sg: s["do_rms"] / x, lambda v, s: v / s["rack_per_pct"],
           "upper_limit", scaled=True),
    Effect("deadband", "governor speed-error deadband", "deadband", "pu speed (half width)",
           "half width, % of bias", 0.105, 0.38, lambda x, s, sg: x / 100.0 * N0["droop"],
           lambda v, s: 100.0 * v / N0["droop"], "half_width"),
    Effect("backlash", "linkage play between actuator and fuel rack", "play",
           "pu rack (full width)", "play / rack rms", 0.24, 0.9,
           lambda x, s, sg: x * s["rack_rms"], lambda v, s: 0.5 * v / s["rack_per_pct"],
           "half_width"),
    Effect("hysteresis", "actuator hysteresis (Prandtl-Ishlinskii, 5 plays, 25 % linear)",
           "pi_r", "pu rack (largest threshold)", "threshold / rack rms", 0.25, 1.2,
           lambda x, s, sg: x * s["rack_rms"], None, "", ("backlash",)),
    Effect("static_nonlinearity", "fuel-map curvature about the operating rack", "curv",
           "slope change at 1 rack rms", "slope change", 0.15, 0.65,
           lambda x, s, sg: x, None, ""),
    Effect("resonance", "flywheel-generator coupling softened (mode into the band)", "f_cpl",
           "Hz (design)", "coupling design frequency, Hz (lower: clearer)", 7.5, 4.3,
           lambda x, s, sg: x, lambda v, s: _coupling_hz(v), "freq_hz", (),
           {"z_cpl": RES_Z}, scaled=True),
    Effect("load_damping", "damper windings (alternator damping)", "d_g", "pu torque/pu slip",
           "damping ratio factor", 1.4, 2.8,
           lambda x, s, sg: N0["d_g"] * (x if sg > 0 else 1 / x),
           lambda v, s: _swing_zeta(v), "zeta", signed=True),
    Effect("periodic_disturbance", "torque ripple at the half order (cylinder imbalance)",
           "ripple_pu", "pu torque", "kW at y (amplitude)", 2.0, 6.0,
           lambda x, s, sg: x / ripple_kw_per_pu(), lambda v, s: RIPPLE_ORDER_HZ, "freq_hz"),
    Effect("drift", "power transducer zero drift (OU, 40 s)", "drift_kw", "kW rms", "kW rms",
           2.5, 9.0, lambda x, s, sg: x, None, ""),
    Effect("ac_coupling", "undeclared analogue AC coupling of the transducer", "ac_rc_s", "s",
           "RC, s (lower: clearer)", 10.0, 2.5, lambda x, s, sg: x, lambda v, s: v, "rc_s",
           scaled=True),
]}

DISTURBANCES = ("periodic_disturbance", "drift")


def draw(name, rng, where="all"):
    """A size x: log-uniform over the range (where="mid": its middle third) and a sign."""
    e = EFFECTS[name]
    a, b = sorted((math.log(e.lo), math.log(e.hi)))
    lo, hi = (a + (b - a) / 3, a + 2 * (b - a) / 3) if where == "mid" else (a, b)
    x = math.exp(rng.uniform(lo, hi))
    sg = (1 if rng.uniform() < 0.5 else -1) if e.signed else 1
    return x, sg


def lag_class(name):
    return "lag" if name in ("extra_lag", "sensor_lag") else name
