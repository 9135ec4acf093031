"""The oracle: is the hidden effect detectable in this record at all?

As gensim's: the true structure (droopsim itself with the hidden effect's parameter at the
nominal value and x 0.6 0.85 1 1.2 1.5 of the change; pairs: nominal and x 0.7 1 1.4 each,
a 4 x 4 grid) is simulated deterministically (no noise, drift, grid wander or
quantisation; a grid-frequency event or a declared coupling of the case is kept) in the same
batch as the recording, and scored the rig's way: warm-up (4 slowest model time constants
+ delay, at most 10 %), 8 blocks, even estimate / odd validate, an offset fitted on the
estimation blocks. Disturbances are their own least-squares regressors (the ripple: cosine
and sine at the half order; a drift: a cosine series of 4 terms per 40 s, fitted in-sample);
since the droop turns the grid's wander into ~5 kW of slow power in every record, the gain
the regressors make on a twin column (the same record, same noise, without the disturbance)
is subtracted from a disturbance's gain.

Detectable when the true structure gains >= MIN_GAIN points of validation fit over the
nominal structure AND an F test on the validation residuals, both prewhitened by an AR(20)
model of the true structure's residual, gives p < ALPHA. The fit, whitening and F-test
arithmetic are gensim's (`_fit`, `_whiten`, imported); the blocks use droopsim's rows.

A pair's members are also judged one by one (`members`): the best true structure without
the member (its parameter at nominal, or a disturbance's regressors left out) against the
best with it, by the same gain and nested F test.
"""
import importlib.util
import math
import os

import numpy as np
from scipy import stats

import effects as fx
import linear as ln
import plant as pl

MIN_GAIN = 1.0
ALPHA = 1e-3
FACTORS = (0.6, 0.85, 1.0, 1.2, 1.5)
PAIR_FACTORS = (0.7, 1.0, 1.4)
DRIFT_TERMS_PER_TAU = 4
BLOCKS = 8

_here = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location(
    "gensim_oracle", os.path.join(_here, "..", "gensim", "oracle.py"))
_go = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_go)
_fit, _whiten = _go._fit, _go._whiten      # generic: offset + regressors; AR(20) whitening


def blocks(n, model_doc):
    w = int(round(ln.warmup_s(model_doc, n) / pl.DT))
    edges = np.linspace(w, n, BLOCKS + 1).astype(int)
    est = np.zeros(n, bool)
    for b in range(BLOCKS):
        est[edges[b]:edges[b + 1]] = b % 2 == 0
    val = np.zeros(n, bool)
    val[w:] = ~est[w:]
    return est, val


def candidates(t, factors=FACTORS):
    """[nominal] + values around the truth of one effect."""
    e = fx.EFFECTS[t["effect"]]
    v, v0 = t["value"], pl.NOMINAL[e.key]
    vals = [v * f for f in factors] if e.scaled else [v0 + (v - v0) * f for f in factors]
    return [v0] + vals


DET = dict(grid_sd_hz=0.0, drift_kw=0.0, noise_kw=0.0, quant_kw=0.0)


def plan(case):
    """Batch parameters: column 0 the recording, then the candidates (deterministic).
    Returns (p, p_after, combos)."""
    inside = [t for t in case["truths"] if t["effect"] not in fx.DISTURBANCES]
    grids = []
    for t in inside:
        vals = candidates(t, PAIR_FACTORS if len(inside) == 2 else FACTORS)
        grids.append((t, vals))
    combos = [[]]
    for t, vals in grids:
        combos = [c + [(t, v, i == 0)] for c in combos for i, v in enumerate(vals)]
    dist = [t for t in case["truths"] if t["effect"] in fx.DISTURBANCES]
    ncol = 1 + len(combos) + (1 if dist else 0)   # + the twin: the record without them

    def columns(src, with_effects):
        p = {k: (np.full(ncol, v, float) if not isinstance(v, str) else v) for k, v in src.items()}
        for k, v in DET.items():
            p[k][1:] = v
        for t in case["truths"]:     # a disturbance is the oracle's regressor, not simulated
            if t["effect"] in fx.DISTURBANCES:
                key = fx.EFFECTS[t["effect"]].key
                p[key][1:] = DET.get(key, pl.NOMINAL[key])
        if dist:                     # the twin: column 0 (noise included) with them nominal
            for k in p:
                if isinstance(p[k], np.ndarray):
                    p[k][-1] = p[k][0]
            for t in dist:
                key = fx.EFFECTS[t["effect"]].key
                p[key][-1] = pl.NOMINAL[key]
        if with_effects:
            for j, combo in enumerate(combos, start=1):
                for t, v, is_nom in combo:
                    e = fx.EFFECTS[t["effect"]]
                    p[e.key][j] = v
                    for xk, xv in e.extra.items():
                        p[xk][j] = pl.NOMINAL[xk] if is_nom else xv
        return _compact(p)
    if case["p_after"] is None:
        return columns(case["p"], True), None, combos
    return columns(case["p"], False), columns(case["p_after"], True), combos


def _compact(p):
    """Arrays whose columns are all equal back to scalars (the simulator's fast paths)."""
    out = {}
    for k, v in p.items():
        if isinstance(v, np.ndarray) and np.all(v == v[0]) and k not in DET:
            out[k] = float(v[0])
        else:
            out[k] = v
    return out


def regressors(name, n, onset_s):
    t = np.arange(n) * pl.DT
    on = np.ones(n) if onset_s is None else (t >= onset_s).astype(float)
    if name == "periodic_disturbance":
        f = fx.RIPPLE_ORDER_HZ
        return [on * np.cos(2 * math.pi * f * t), on * np.sin(2 * math.pi * f * t)]
    k = int(math.ceil(DRIFT_TERMS_PER_TAU * n * pl.DT / pl.NOMINAL["drift_tau_s"]))
    return [on * np.cos(math.pi * j * (t + 0.5 * pl.DT) / (n * pl.DT)) for j in range(1, k + 1)]


def judge(case, y_all, model_doc):
    """y_all: (n, 1 + candidates) from plant.simulate with plan()'s parameters."""
    y = y_all[:, 0]
    n = len(y)
    est, val = blocks(n, model_doc)
    combos = plan(case)[2]
    dist = [t["effect"] for t in case["truths"] if t["effect"] in fx.DISTURBANCES]
    extra = []
    for d in dist:
        extra += regressors(d, n, case["onset_s"])
    nom_col = next(j for j, c in enumerate(combos, 1) if all(nm for _, _, nm in c))
    _, v0, r0 = _fit(y, y_all[:, nom_col], est, val)
    best = None
    in_sample = "drift" in dist
    for j, combo in enumerate(combos, 1):
        ef, vf, r = _fit(y, y_all[:, j], est, val, extra or None, in_sample)
        if best is None or ef > best[0]:
            best = (ef, vf, r, combo)
    _, v1, r1, combo = best
    twin_gain = 0.0
    if dist:     # what the regressors gain on the same record without the disturbance
        jb = next(j for j, c in enumerate(combos, 1) if c is combo)
        yt = y_all[:, -1]
        twin_gain = (_fit(yt, y_all[:, jb], est, val, extra, in_sample)[1]
                     - _fit(yt, y_all[:, jb], est, val)[1])
    k = sum(1 for t in case["truths"] if t["effect"] not in fx.DISTURBANCES) + len(extra)
    w1, w0 = _whiten(r1, r0)
    ss0, ss1 = float(np.sum(w0 ** 2)), float(np.sum(w1 ** 2))
    neff = len(w1)
    if not case["truths"]:
        fstat, pval = 0.0, 1.0
    else:
        fstat = max(ss0 - ss1, 0.0) / max(k, 1) / (ss1 / max(neff - k, 1.0))
        pval = float(stats.f.sf(fstat, max(k, 1), max(neff - k, 1.0)))
    gain = v1 - v0 - twin_gain if case["truths"] else 0.0
    out = dict(detectable=bool(case["truths"]) and gain >= MIN_GAIN and pval < ALPHA,
               vfit_nominal=round(v0, 3), vfit_true=round(v1 if case["truths"] else v0, 3),
               gain=round(gain, 3), twin_gain=round(twin_gain, 3), f=round(fstat, 2), p=pval,
               n_eff=round(neff),
               fitted={t["effect"]: v for t, v, _ in combo})
    if len(case["truths"]) > 1:
        out["members"] = members(case, y_all, est, val, combos, (v1, r1), twin_gain)
    return out


def members(case, y_all, est, val, combos, full, twin_gain):
    """Each member of a pair judged as the single effect the other leaves to be found: the
    best true structure without it (its parameter at nominal, or a disturbance's regressors
    left out) against the best with it, by the same gain and nested F test (its own
    parameters counted). A member its pair's best fit does not need is not detectable."""
    y = y_all[:, 0]
    n = len(y)
    v1, r1 = full
    out = {}
    for i, t in enumerate(case["truths"]):
        others = [d for d in case["truths"] if d is not t and d["effect"] in fx.DISTURBANCES]
        extra = []
        for d in others:
            extra += regressors(d["effect"], n, case["onset_s"])
        in_sample = any(d["effect"] == "drift" for d in others)
        if t["effect"] in fx.DISTURBANCES:
            pool, k, twin = combos, len(regressors(t["effect"], n, case["onset_s"])), twin_gain
        else:
            j = [c for c in case["truths"] if c["effect"] not in fx.DISTURBANCES].index(t)
            pool, k, twin = [c for c in combos if c[j][2]], 1, 0.0
        best = None
        for c in pool:
            col = combos.index(c) + 1
            ef, vf, r = _fit(y, y_all[:, col], est, val, extra or None, in_sample)
            if best is None or ef > best[0]:
                best = (ef, vf, r)
        _, v0, r0 = best
        w1, w0 = _whiten(r1, r0)
        ss0, ss1 = float(np.sum(w0 ** 2)), float(np.sum(w1 ** 2))
        fstat = max(ss0 - ss1, 0.0) / k / (ss1 / max(len(w1) - k, 1.0))
        pval = float(stats.f.sf(fstat, k, max(len(w1) - k, 1.0)))
        gain = v1 - v0 - twin
        out[t["effect"]] = dict(detectable=bool(gain >= MIN_GAIN and pval < ALPHA),
                                gain=round(gain, 3), p=pval)
    return out
