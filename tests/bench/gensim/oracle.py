"""The oracle: is the hidden effect detectable in this record at all?

It fits the true structure, the simulator itself with the hidden effect's parameter free,
and the nominal model to the recorded output, the same way `rig diagnose` scores (a 5 s
warm-up, the rest cut into 8 blocks, even blocks estimate, odd blocks validate, a constant
offset fitted on the estimation blocks, NRMSE fit of DESIGN.md 5 on the validation blocks):

  * input-side effects: the set is simulated (deterministic: no noise, drift or grid
    wander) at the nominal value and at 5 values around the truth (x 0.5 0.8 1 1.25 1.6 of
    the change) in one batch; the value with the best estimation fit is kept;
  * disturbances: the nominal prediction plus the disturbance's own regressors fitted by
    least squares on the estimation blocks (the ripple: a cosine and a sine at its known
    frequency; the drift: a cosine series down to the drift's time scale, 2 T / tau terms);
  * pairs: both, on a 2-D grid.

Detectable when the true structure gains >= MIN_GAIN points of validation fit over the
nominal model AND an F test of the validation residuals says so at ALPHA, both residuals
prewhitened by an AR(AR_ORDER) model of the true structure's residual (the noise is
coloured: transducer lag, grid wander, drift). A drift has no out-of-block prediction
(15 s blocks, a 60 s wander): its cosine series is fitted on all blocks (in-sample, as the
rig's own drift smoother is) and its terms count in the F test.
"""
import math

import numpy as np
from scipy import stats

import effects as fx
import genset as g

WARMUP_S = 5.0
BLOCKS = 8
FACTORS = (0.5, 0.8, 1.0, 1.25, 1.6)
PAIR_FACTORS = (0.7, 1.0, 1.4)
MIN_GAIN = 1.0       # points of validation fit: below this no engineer calls it an effect
ALPHA = 1e-3         # F-test level (the rig's own tests are at 1e-2 .. 1e-4)
AR_ORDER = 20        # prewhitening: 0.2 s of the residual's own memory
DRIFT_TERMS_PER_TAU = 4  # cosine terms per drift time constant over the record


def _candidates(name, value, scales):
    """Parameter values to try for one effect: [nominal] + around the truth."""
    e = fx.EFFECTS[name]
    nom = g.NOMINAL[e.key]
    if e.key in ("slew", "k_s", "ac_rc_s"):
        vals = [value * f for f in FACTORS]
    elif e.key == "rack_max":
        vals = [scales.rack0 + (value - scales.rack0) * f for f in FACTORS]
    else:
        vals = [nom + (value - nom) * f for f in FACTORS]
    return [nom] + vals


def _blocks(n):
    w = int(round(WARMUP_S / g.DT))
    edges = np.linspace(w, n, BLOCKS + 1).astype(int)
    est = np.zeros(n, bool)
    for b in range(BLOCKS):
        est[edges[b]:edges[b + 1]] = b % 2 == 0
    val = np.zeros(n, bool)
    val[w:] = ~est[w:]
    return est, val


def _fit(y, yhat, est, val, extra=None, in_sample=False):
    """Offset (+ extra regressors) fitted on est (on est and val: in_sample); returns
    (est fit, val fit, val residual)."""
    cols = [np.ones_like(y)] + ([] if extra is None else list(extra))
    x = np.column_stack(cols)
    on = est | val if in_sample else est
    coef, *_ = np.linalg.lstsq(x[on], (y - yhat)[on], rcond=None)
    r = y - yhat - x @ coef

    def nrmse(mask):
        d = y[mask] - y[mask].mean()
        return 100.0 * (1.0 - np.linalg.norm(r[mask]) / np.linalg.norm(d))
    return nrmse(est), nrmse(val), r[val]


def _disturbance_regressors(name, n, onset_s):
    t = np.arange(n) * g.DT
    on = np.ones(n) if onset_s is None else (t >= onset_s).astype(float)
    if name == "periodic_disturbance":
        f = fx.EFFECTS[name].truth(0, None)
        return [on * np.cos(2 * math.pi * f * t), on * np.sin(2 * math.pi * f * t)]
    k = int(math.ceil(DRIFT_TERMS_PER_TAU * n * g.DT / g.NOMINAL["drift_tau_s"]))
    return [on * np.cos(math.pi * j * (t + 0.5 * g.DT) / (n * g.DT)) for j in range(1, k + 1)]


def _whiten(r1, r0):
    """Both residuals through the AR(AR_ORDER) whitening filter of r1 (least squares)."""
    m = AR_ORDER
    x = np.column_stack([r1[m - i - 1:len(r1) - i - 1] for i in range(m)])
    a, *_ = np.linalg.lstsq(x, r1[m:], rcond=None)

    def filt(r):
        xx = np.column_stack([r[m - i - 1:len(r) - i - 1] for i in range(m)])
        return r[m:] - xx @ a
    return filt(r1), filt(r0)


def plan(case):
    """Batch columns for the simulation: column 0 the recording, then the oracle's
    candidates (deterministic). Returns (p, p_after, labels)."""
    s = fx.scales()
    input_side = [t for t in case["truths"] if t["effect"] not in fx.DISTURBANCES]
    grids = []
    for t in input_side:
        vals = _candidates(t["effect"], t["value"], s)
        if len(input_side) == 2:  # pairs: nominal and 3 values each
            nom = vals[0]
            vals = [nom] + [nom + (t["value"] - nom) * f if t["key"] not in ("slew", "k_s")
                            else t["value"] * f for f in PAIR_FACTORS]
        grids.append((t, vals))
    combos = [[]]
    for t, vals in grids:
        combos = [c + [(t, v, i == 0)] for c in combos for i, v in enumerate(vals)]
    rec_p = case["p_after"] if case["p_after"] is not None else case["p"]
    ncol = 1 + len(combos)
    det = dict(grid_sd_hz=0.0, drift_kw=0.0, noise_kw=0.0, quant_kw=0.0)

    def columns(src, with_effects):
        keys = set(det) | {fx.EFFECTS[t["effect"]].key for t, _ in grids}
        keys |= {xk for t, _ in grids for xk in fx.EFFECTS[t["effect"]].extra}
        p = {k: np.full(ncol, v, float) if k in keys else v for k, v in src.items()}
        for k, v in det.items():
            p[k][1:] = v
        for t in case["truths"]:  # a disturbance is the oracle's regressor, not simulated
            if t["effect"] in fx.DISTURBANCES:
                key = fx.EFFECTS[t["effect"]].key
                p[key] = np.full(ncol, src[key], float)
                p[key][1:] = det.get(key, g.NOMINAL[key])
        if with_effects:
            for j, combo in enumerate(combos, start=1):
                for t, v, is_nom in combo:
                    e = fx.EFFECTS[t["effect"]]
                    p[e.key][j] = v
                    for xk in e.extra:
                        p[xk][j] = g.NOMINAL[xk] if is_nom else e.extra[xk]
        return p
    if case["p_after"] is None:
        return columns(rec_p, True), None, combos
    return columns(case["p"], False), columns(rec_p, True), combos


def judge(case, y_all):
    """y_all: (n, 1 + candidates) from genset.simulate with plan()'s parameters."""
    y = y_all[:, 0]
    n = len(y)
    est, val = _blocks(n)
    combos = plan(case)[2]
    dist = [t["effect"] for t in case["truths"] if t["effect"] in fx.DISTURBANCES]
    extra = []
    for d in dist:
        extra += _disturbance_regressors(d, n, case["onset_s"])
    nom_col = next(j for j, c in enumerate(combos, 1) if all(is_nom for _, _, is_nom in c))
    e0, v0, r0 = _fit(y, y_all[:, nom_col], est, val)
    best = None
    in_sample = "drift" in dist
    for j, combo in enumerate(combos, 1):
        ef, vf, r = _fit(y, y_all[:, j], est, val, extra or None, in_sample)
        if best is None or ef > best[0]:
            best = (ef, vf, r, combo)
    _, v1, r1, combo = best
    k = sum(1 for t in case["truths"] if t["effect"] not in fx.DISTURBANCES) + len(extra)
    w1, w0 = _whiten(r1, r0)
    ss0, ss1 = float(np.sum(w0 ** 2)), float(np.sum(w1 ** 2))
    neff = len(w1)
    if not case["truths"]:
        fstat, pval = 0.0, 1.0
    else:
        fstat = max(ss0 - ss1, 0.0) / max(k, 1) / (ss1 / max(neff - k, 1.0))
        pval = float(stats.f.sf(fstat, max(k, 1), max(neff - k, 1.0)))
    gain = v1 - v0 if case["truths"] else 0.0
    return dict(detectable=bool(case["truths"]) and gain >= MIN_GAIN and pval < ALPHA,
                vfit_nominal=round(v0, 3), vfit_true=round(v1 if case["truths"] else v0, 3),
                gain=round(gain, 3), f=round(fstat, 2), p=pval, n_eff=round(neff),
                fitted={t["effect"]: v for t, v, _ in combo})
