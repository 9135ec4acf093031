"""droopsim's linear side: the set's small-signal response from its block diagram (exact:
the injection delay inside the speed loop and the moving average kept as exponentials),
the closed-loop modes by root continuation of the loop's characteristic quasi-polynomial,
and the model handed over: a vector fit of the advanced response, balanced-truncated.

Not a Jacobian and not a Pade approximant (gensim's way): every block's transfer function is
written down from plant.deriv's equations, linearised by hand at the operating point.
"""
import math
import os
import sys

import numpy as np
from scipy import linalg, signal

import plant as pl

sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "gensim"))
from genset import _balanced_truncation  # noqa: E402  (generic linear algebra)

CHECK_DB, CHECK_DEG = 0.02, 0.2
CHECK_F = (0.02, 8.0)      # the excited band: the bias is 20 dB down at 8 Hz


def _s(v):
    return float(np.asarray(v).flat[0])


def mech(p):
    """Shaft + generator against a stiff grid: A (6x6: w_e w_f w_g twist_ef twist_fg delta),
    input engine torque; outputs flywheel speed and electrical power."""
    q = {k: _s(v) for k, v in p.items()}
    k_ef, c_ef, k_c, c_c = (float(v) for v in pl.shaft_consts(q))
    ks = q["p_max"] * math.cos(pl.OP["delta"])
    he, hf, hg = 2 * q["h_e"], 2 * q["h_f"], 2 * q["h_g"]
    a = np.array([
        [-c_ef / he, c_ef / he, 0, -k_ef / he, 0, 0],
        [c_ef / hf, -(c_ef + c_c) / hf, c_c / hf, k_ef / hf, -k_c / hf, 0],
        [0, c_c / hg, -(c_c + q["d_g"] - q["p0"]) / hg, 0, k_c / hg, -ks / hg],
        [pl.WB, -pl.WB, 0, 0, 0, 0],
        [0, pl.WB, -pl.WB, 0, 0, 0],
        [0, 0, pl.WB, 0, 0, 0]])
    b = np.array([1 / he, 0, 0, 0, 0, 0])
    c_wf = np.eye(6)[1]
    c_pe = np.array([0, 0, q["d_g"], 0, 0, ks])
    return a, b, c_wf, c_pe


def engine_consts(p):
    q = {k: _s(v) for k, v in p.items()}
    lam = pl.OP["lam"]
    e = 1 - q["eta_k"] * math.exp(-(lam - 1) / q["eta_l"])
    de = q["eta_k"] / q["eta_l"] * math.exp(-(lam - 1) / q["eta_l"])
    return pl.OP["k_f"], e - lam * de, de * q["a_fuel"]   # map slope, d tq/d fuel, via air


def frf(p, f):
    """Exact small-signal responses at f (Hz): y (kW per %), rack (pu per %), d_o."""
    q = {k: _s(v) for k, v in p.items()}
    s = 2j * math.pi * np.asarray(f, float)
    a, b, c_wf, c_pe = mech(q)
    mw = np.empty(len(s), complex)
    mp = np.empty(len(s), complex)
    for i, si in enumerate(s):
        v = np.linalg.solve(si * np.eye(6) - a, b)
        mw[i], mp[i] = c_wf @ v, c_pe @ v
    kf, ef, ea = engine_consts(q)
    eng = kf * (ef + ea / (1 + s * q["t_t"])) / (1 + s * q["t_c"])
    wa = 2 * math.pi * q["f_a"]
    act = wa * wa / (s * s + 2 * q["z_a"] * wa * s + wa * wa)
    k = q["kp"] + q["ki"] / s
    dd = q["kd"] * s / (1 + s * q["t_df"])
    r = q["droop"]
    delay = np.exp(-s * _s(pl.t_delay(q)))
    loop = eng * act * delay
    delta = 1 + s * q["t_o"] + k * r / pl.OP["span"] + (k + dd) / (1 + s * q["t_sp"]) * mw * loop
    do = k * r / 100.0 / delta
    tma = q["t_ma"]
    ma = (1 - np.exp(-s * tma)) / (s * tma)
    y = q["p_rated_kw"] * q["gain"] * ma / (1 + s * q["t_m"]) * mp * loop * do
    if q["ac_rc_s"] > 0:
        y = y * s * q["ac_rc_s"] / (1 + s * q["ac_rc_s"])
    return dict(y=y, rack=act * do, do=do)


def _poly(*fs):
    out = np.array([1.0])
    for f in fs:
        out = np.polymul(out, f)
    return out


def modes(p, steps=60):
    """Closed-loop oscillatory modes [(f Hz, zeta, origin)] by continuation in the loop gain
    lam from 0 (open loop: the shaft, the servo) to 1 of P1(s) + lam exp(-s td) P2(s)."""
    q = {k: _s(v) for k, v in p.items()}
    a, b, c_wf, _ = mech(q)
    nw, dm = signal.ss2tf(a, b[:, None], c_wf[None, :], np.zeros((1, 1)))
    nw = np.trim_zeros(nw[0], "f")
    kf, ef, ea = engine_consts(q)
    wa = 2 * math.pi * q["f_a"]
    r = q["droop"] / pl.OP["span"]
    p1 = _poly(np.polyadd(np.polymul([q["t_o"], 1], [1, 0]), [q["kp"] * r, q["ki"] * r]),
               [q["t_df"], 1], [q["t_sp"], 1], dm, [q["t_c"], 1], [q["t_t"], 1],
               [1, 2 * q["z_a"] * wa, wa * wa])
    p2 = _poly(np.polyadd(np.polymul([q["kp"], q["ki"]], [q["t_df"], 1]), [q["kd"], 0, 0]),
               nw, kf * np.array([ef * q["t_t"], ef + ea]), [wa * wa])
    td = _s(pl.t_delay(q))
    d1, d2 = np.polyder(p1), np.polyder(p2)
    shaft = sorted(np.roots(dm), key=abs)
    shaft = [z for z in shaft if z.imag > 1e-6]
    names = {id(z): n for z, n in zip(shaft, ("swing", "coupling", "crankshaft"))}
    out = []
    for z0 in [z for z in np.roots(p1) if z.imag > 1e-6]:
        z = z0
        for lam in np.linspace(0, 1, steps + 1)[1:]:
            for _ in range(30):
                e = np.exp(-z * td)
                f = np.polyval(p1, z) + lam * e * np.polyval(p2, z)
                df = np.polyval(d1, z) + lam * e * (np.polyval(d2, z) - td * np.polyval(p2, z))
                dz = f / df
                z = z - dz
                if abs(dz) < 1e-11 * max(1.0, abs(z)):
                    break
        near = min(shaft, key=lambda w: abs(w - z0))
        name = names[id(near)] if abs(near - z0) < 1e-6 * abs(z0) else "governor/servo"
        out.append((abs(z) / (2 * math.pi), -z.real / abs(z), name))
    return sorted(out)


def mode(p, name):
    return next(m for m in modes(p) if m[2] == name)


def scales(p=None):
    """Rack motion the bias causes: rms deviation and rate for the 1 % bias, rack per %."""
    p = p or pl.NOMINAL
    f = np.linspace(0.002, 25.0, 6000)
    b, a = signal.butter(2, pl.BAND_HZ, fs=1 / pl.DT)
    su = np.abs(signal.freqz(b, a, worN=f, fs=1 / pl.DT)[1]) ** 2
    h = frf(p, f)
    norm = np.trapz(su, f)
    rms = lambda g: pl.BIAS_RMS * math.sqrt(np.trapz(np.abs(g) ** 2 * su, f) / norm)  # noqa
    rack_rms = rms(h["rack"])
    return dict(rack0=pl.OP["rack"], rack_rms=rack_rms, rate_rms=rms(2j * math.pi * f * h["rack"]),
                rack_per_pct=rack_rms / pl.BIAS_RMS, y_rms=rms(h["y"]), do_rms=rms(h["do"]),
                swing=mode(p, "swing"), coupling=mode(p, "coupling"))


# ------------------------------------------------------------------ vector fitting
def _basis(s, poles):
    cols = []
    for p in poles:
        if abs(p.imag) > 0:
            cols += [1 / (s - p) + 1 / (s - p.conjugate()), 1j / (s - p) - 1j / (s - p.conjugate())]
        else:
            cols.append(1 / (s - p))
    return np.column_stack(cols)


def _realisation(poles):
    n = sum(2 if abs(p.imag) > 0 else 1 for p in poles)
    a, b, i = np.zeros((n, n)), np.zeros(n), 0
    for p in poles:
        if abs(p.imag) > 0:
            a[i:i + 2, i:i + 2] = [[p.real, p.imag], [-p.imag, p.real]]
            b[i] = 2.0
            i += 2
        else:
            a[i, i], b[i] = p.real, 1.0
            i += 1
    return a, b


def _stack(m, w):
    m = m * w[:, None] if m.ndim == 2 else m * w
    return np.concatenate([m.real, m.imag])


def vector_fit(f, h, n_pairs, iters=30):
    """Strictly proper real rational fit (Gustavsen-Semlyen), relative weighting.
    Returns (A, B, C) real."""
    s = 2j * math.pi * f
    wmax = 2 * math.pi * f.max()
    beta = np.geomspace(2 * math.pi * f.min(), wmax, n_pairs)
    poles = list(-beta / 100 + 1j * beta)
    wt = 1 / np.abs(h)
    for _ in range(iters):
        phi = _basis(s, poles)
        n = phi.shape[1]
        m = np.hstack([phi, -h[:, None] * phi])
        x = np.linalg.lstsq(_stack(m, wt), _stack(h, wt), rcond=None)[0]
        a, b = _realisation(poles)
        z = np.linalg.eigvals(a - np.outer(b, x[n:]))
        z = np.where(z.real > 0, -z.real + 1j * z.imag, z)
        z = np.where(np.abs(z.real) < 1e-9 * np.abs(z), z - 1e-6 * np.abs(z), z)
        poles = [p for p in z if p.imag >= 0]
        poles = [p if p.imag > 1e-9 * abs(p) else complex(p.real, 0) for p in poles]
    phi = _basis(s, poles)
    c = np.linalg.lstsq(_stack(phi, wt), _stack(h, wt), rcond=None)[0]
    a, b = _realisation(poles)
    return a, b, c


def row_delay(p):
    return _s(pl.t_delay(p)) + _s(p["t_ma"]) / 2 + pl.DT / 2


def _check(num, den, p, f, exact):
    w = 2 * math.pi * f
    sn = np.sinc(f * pl.DT)
    model = signal.freqs(num, den, w)[1] * np.exp(-1j * w * row_delay(p)) * sn ** 2
    ratio = model / (exact * sn * np.exp(-1j * w * pl.DT / 2))
    return (float(np.max(np.abs(20 * np.log10(np.abs(ratio))))),
            float(np.max(np.abs(np.degrees(np.angle(ratio))))))


def nominal_model(p=None):
    """The model of the rows: R(s) exp(-s delay), delay = injection delay + half the moving
    average + half a row (the held bias); R fits the response advanced by the delay and
    divided by the held bias's sinc (the rig simulates with a first-order hold: sinc^2).
    Checked against exact(jw) sinc e^{-jw dt/2} over CHECK_F. Returns (model.json, check)."""
    p = p or pl.NOMINAL
    ff = np.geomspace(0.001, 24.0, 700)
    w = 2 * math.pi * ff
    target = frf(p, ff)["y"] * np.exp(1j * w * (row_delay(p) - pl.DT / 2)) / np.sinc(ff * pl.DT)
    fc = np.geomspace(*CHECK_F, 400)
    exact = frf(p, fc)["y"]
    best = None
    for n_pairs in (6, 7, 8, 9, 10, 12):
        a, b, c = vector_fit(ff, target, n_pairs)
        if np.any(np.linalg.eigvals(a).real >= 0):
            continue
        for r in range(4, len(a) + 1):
            ar, br, cr = _balanced_truncation(a, b, c, r)
            num, den = signal.ss2tf(ar, br[:, None], cr[None, :], np.zeros((1, 1)))
            num = np.trim_zeros(num[0], "f")
            num, den = num / den[0], den / den[0]
            if np.any(np.roots(den).real >= 0):
                continue
            edb, edeg = _check(num, den, p, fc, exact)
            if best is None or (edb < CHECK_DB / 2 and edeg < CHECK_DEG / 2 and r < best[0]) \
                    or (best[1] >= CHECK_DB / 2 and edb + edeg / 10 < best[1] + best[2] / 10):
                best = (r, edb, edeg, num, den)
            if edb < CHECK_DB / 2 and edeg < CHECK_DEG / 2:
                break
        if best and best[1] < CHECK_DB / 2 and best[2] < CHECK_DEG / 2:
            break
    r, edb, edeg, num, den = best
    check = dict(order=r, max_err_db=edb, max_err_deg=edeg, band_hz=list(CHECK_F),
                 passed=bool(edb < CHECK_DB and edeg < CHECK_DEG))
    doc = dict(type="tf", num=num.tolist(), den=den.tolist(), delay_s=row_delay(p),
               units=dict(input="% of rated power", output="kW"), input="u", output="y",
               source=dict(simulator="droopsim", check=check))
    return doc, check


def warmup_s(doc, n_rows):
    """The rig's warm-up: 4 slowest time constants + the dead time, at most 10 % of the record."""
    slow = 1 / np.min(np.abs(np.roots(doc["den"]).real))
    return min(4 * slow + doc["delay_s"], 0.1 * n_rows * pl.DT)
