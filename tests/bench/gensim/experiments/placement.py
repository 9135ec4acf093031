#!/usr/bin/python3
"""Where should an in-loop nonlinearity sit in an approximate model built from the closed
loop G (bias -> power) alone?  gensim cases, nonlinearities N fitted under placements:

  A input      y = G N(u)
  B WH         w = F u, F = 1/(1+s Tf);  y = [G (1+s Tf)] N(w)
  C LFR        w = F u, d = N(w) - w;    y = G u + [G (1+s Tf)] S d,  S = 1 - G/G(0)
  D loop       T = R/G(0) (R: G without its delay), L = T/(1-T); e = u - z, v = F e,
               z = [L (1+s Tf)] N(v) closed sample by sample; y = G(0) z(t - delay)
  I loop/int   as D with F = 1/s, P = L s (N right after the loop's integrator; Tf is
               redundant there: one parameter)
  E output     y = G(0) N(G u / G(0))

scored as `rig diagnose` scores (5 s warm-up, 8 blocks, even estimate, odd validate, offset
on the estimation blocks), with the oracle's true-structure gain for reference.

    /usr/bin/python3 tests/bench/gensim/experiments/placement.py --seed 1 [--jobs 2]
"""
import argparse
import json
import math
import os
import sys
import time
from multiprocessing import Pool

import numpy as np
from scipy import optimize, signal

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import cases as cs  # noqa: E402
import genset as g  # noqa: E402
import oracle  # noqa: E402

DT = g.DT
CASES = [("none", "large", "plain"), ("rate_limit", "large", "plain"),
         ("backlash", "large", "plain"), ("saturation", "large", "plain"),
         ("static_nonlinearity", "large", "plain"), ("hysteresis", "large", "plain"),
         ("deadband", "large", "plain"), ("backlash", "small", "small"),
         ("rate_limit", "small", "small")]
# the N tried under the explicit loop D (slow: a Python loop per sample) for each effect
MATCH = {"rate_limit": ["rate"], "backlash": ["backlash"], "hysteresis": ["backlash"],
         "saturation": ["sat_up", "sat_sym"], "static_nonlinearity": ["kink"],
         "deadband": ["deadband"], "none": ["backlash", "rate"]}

# ---------------------------------------------------------------- linear simulation (FOH)


def foh_ss(num, den):
    """Continuous TF -> discrete state space, first-order hold (input piecewise linear)."""
    num = np.trim_zeros(np.atleast_1d(np.asarray(num, float)), "f")
    den = np.asarray(den, float)
    num, den = num / den[0], den / den[0]
    a, b, c, d = signal.tf2ss(num, den)
    return signal.cont2discrete((a, b, c, d), DT, method="foh")[:4]


class Lin:
    """G(s) e^{-s delay}: FOH-discretised, diagonalised (parallel first-order sections,
    well conditioned for an order-10 model at 100 Hz), delay as a whole-sample shift plus
    a linear interpolation of the input for the fraction (the rig's convention)."""

    def __init__(self, num, den, delay_s=0.0):
        ad, bd, cd, dd = foh_ss(num, den)
        lam, v = np.linalg.eig(ad)
        self.lam = lam
        self.b = np.linalg.solve(v, bd[:, 0])
        self.c = cd[0] @ v
        self.d = float(dd[0, 0])
        k = delay_s / DT
        self.m = int(math.floor(k + 1e-9))
        self.f = max(k - self.m, 0.0) if k - self.m > 1e-9 else 0.0

    def __call__(self, u):
        u = np.asarray(u, float)
        if self.f:
            u = (1 - self.f) * u + self.f * np.concatenate([[0.0], u[:-1]])
        if self.m:
            u = np.concatenate([np.zeros(self.m), u[:-self.m]])
        y = self.d * u
        for lam, b, c in zip(self.lam, self.b, self.c):
            y = y + (c * b * signal.lfilter([0.0, 1.0], [1.0, -lam], u.astype(complex))).real
        return y

# ---------------------------------------------------------------- nonlinearities (bias %)


def _backlash(w, h):
    out = np.empty(len(w))
    y = float(w[0])
    for i, x in enumerate(w.tolist()):
        if x - h > y:
            y = x - h
        elif x + h < y:
            y = x + h
        out[i] = y
    return out


def _rate(w, r):
    out = np.empty(len(w))
    y, s = float(w[0]), r * DT
    for i, x in enumerate(w.tolist()):
        dx = x - y
        y += s if dx > s else (-s if dx < -s else dx)
        out[i] = y
    return out


# name: (function(w, p), starting values, bounds, unit); sizes ~ the bias (0.8 % rms)
NL = {
    "deadband": (lambda w, p: np.sign(w) * np.maximum(np.abs(w) - p, 0.0),
                 [0.05, 0.2, 0.5], (0.0, 3.0), "half-width %"),
    "backlash": (_backlash, [0.05, 0.2, 0.5], (0.0, 3.0), "half-width %"),
    "sat_sym": (lambda w, p: np.clip(w, -p, p), [0.5, 1.0, 2.0], (0.05, 5.0), "+-limit %"),
    "sat_up": (lambda w, p: np.minimum(w, p), [0.3, 0.8, 1.6], (-1.0, 5.0), "upper %"),
    "rate": (_rate, [4.0, 10.0, 25.0], (0.3, 200.0), "%/s"),
    "kink": (lambda w, p: w + p * np.maximum(w, 0.0), [-0.4, 0.4], (-0.95, 3.0), "k"),
    "cubic": (lambda w, p: w + p * w ** 3, [-0.3, 0.3], (-3.0, 3.0), "c %^-2"),
}
SCALAR = {  # the same, per sample, for the closed loop
    "deadband": lambda v, p: (v - p if v > p else (v + p if v < -p else 0.0)),
    "sat_sym": lambda v, p: min(max(v, -p), p),
    "sat_up": lambda v, p: min(v, p),
    "kink": lambda v, p: v + p * max(v, 0.0),
    "cubic": lambda v, p: v + p * v ** 3,
}
TF_B = (math.log(0.005), math.log(2.0))  # front lag Tf, fitted as log(Tf)

# ---------------------------------------------------------------- scoring (as the rig)


def blocks(n):
    w = int(round(5.0 / DT))
    e = np.linspace(w, n, 9).astype(int)
    est = np.zeros(n, bool)
    for b in range(8):
        est[e[b]:e[b + 1]] = b % 2 == 0
    val = np.zeros(n, bool)
    val[w:] = ~est[w:]
    return est, val


def vfit(y, yhat, est, val):
    r = y - yhat
    r = r - r[est].mean()
    d = y[val] - y[val].mean()
    return 100.0 * (1.0 - np.linalg.norm(r[val]) / np.linalg.norm(d))

# ---------------------------------------------------------------- placements


class Model:
    def __init__(self, doc, u):
        self.u = u
        self.num, self.den = np.array(doc["num"]), np.array(doc["den"])
        self.delay = float(doc["delay_s"])
        self.g0 = self.num[-1] / self.den[-1]
        self.G = Lin(self.num, self.den, self.delay)
        self.Gu = self.G(u)
        self._cache = {}

    def lead(self, tf):  # G (1 + s Tf), with the delay
        key = ("lead", round(tf, 9))
        if key not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[key] = Lin(np.polymul(self.num, [tf, 1.0]), self.den, self.delay)
        return self._cache[key]

    def front(self, tf):  # F u, F = 1/(1 + s Tf)
        key = ("front", round(tf, 9))
        if key not in self._cache:
            self._cache[key] = Lin([1.0], [tf, 1.0])(self.u)
        return self._cache[key]

    def predict(self, place, nl, p, tf=None):
        f = NL[nl][0]
        if place == "A":
            return self.G(f(self.u, p))
        if place == "E":
            return self.g0 * f(self.Gu / self.g0, p)
        if place == "I":
            return self.loop(nl, p, None)
        w = self.front(tf)
        if place == "B":
            return self.lead(tf)(f(w, p))
        if place == "C":
            d = f(w, p) - w
            s = d - self.G(d) / self.g0
            return self.Gu + self.lead(tf)(s)
        if place == "D":
            return self.loop(nl, p, tf)
        raise ValueError(place)

    # D: the explicit unity loop, N between F = 1/(1+s Tf) and P = L (1+s Tf)
    def loop_parts(self, tf):
        nt = np.concatenate([np.zeros(len(self.den) - len(self.num)), self.num]) / self.g0
        dl = self.den - nt
        dl[-1] = 0.0  # T(0) = 1: L has an integrator
        nl = np.trim_zeros(dl, "f")  # L = nt / dl
        if tf is None:  # F = 1/s, P = L s = nt / (dl / s)
            return foh_ss([1.0], [1.0, 0.0]), foh_ss(nt, nl[:-1]), np.roots(nl)
        pn = np.polymul(nt, [tf, 1.0])
        if len(np.trim_zeros(pn, "f")) > len(nl):
            raise ValueError("L (1+s Tf) improper")
        return foh_ss([1.0], [tf, 1.0]), foh_ss(pn, nl), np.roots(nl)

    def i_scale(self, nl):
        """I: the integrator's output v = S u / s has not the bias's scale: factor for N's
        parameter (amplitude: rms v / rms u; rate: rms dv / rms du; cubic: 1 / that^2)."""
        if "v" not in self._cache:
            self._cache["v"] = self.loop("rate", 0.0, None, nonlinear=False, want_v=True)
        v, u = self._cache["v"][500:], self.u[500:]
        k = np.std(v) / np.std(u)
        return {"rate": np.std(np.diff(v)) / np.std(np.diff(u)), "kink": 1.0,
                "cubic": 1.0 / k ** 2}.get(nl, k)

    def loop(self, nl, p, tf, nonlinear=True, want_v=False):
        (fa, fb, fc, fd), (pa, pb, pc, pd), _ = self.loop_parts(tf)
        fa, fb, fc, fd = float(fa[0, 0]), float(fb[0, 0]), float(fc[0, 0]), float(fd[0, 0])
        pb, pc, pd = pb[:, 0], pc[0], float(pd[0, 0])
        f = SCALAR.get(nl)
        memory = nl in ("backlash", "rate")
        xf, xp, state = 0.0, np.zeros(len(pa)), None
        n = len(self.u)
        z = np.empty(n)
        vv = np.empty(n)
        uu = self.u.tolist()
        for k in range(n):
            base_v = fc * xf + fd * uu[k]
            yp0 = float(pc @ xp)
            v = base_v - fd * yp0  # fixed point: v = F(u - z), z = yp0 + pd n(v)
            for _ in range(3):
                if not nonlinear:
                    q = v
                elif memory:
                    s = state if state is not None else v
                    if nl == "backlash":
                        q = min(max(s, v - p), v + p)
                    else:
                        q = s + max(-p * DT, min(p * DT, v - s))
                else:
                    q = f(v, p)
                v = base_v - fd * (yp0 + pd * q)
            state = q
            vv[k] = v
            zk = yp0 + pd * q
            z[k] = zk
            xf = fa * xf + fb * (uu[k] - zk)
            xp = pa @ xp + pb * q
        if want_v:
            return vv
        m = int(round(self.delay / DT))
        return self.g0 * np.concatenate([np.zeros(m), z[:n - m]])

# ---------------------------------------------------------------- fitting


def fit_one(mod, y, est, val, place, nl, max_nfev=40):
    func, starts, bnd, _ = NL[nl]
    if place == "I":
        k = mod.i_scale(nl)
        starts = [k * s for s in starts]
        bnd = (bnd[0] * k, bnd[1] * k) if nl not in ("kink",) else bnd
    needs_tf = place in ("B", "C", "D")
    yo = y[est]

    def res(x):
        yh = mod.predict(place, nl, x[0], math.exp(x[1]) if needs_tf else None)
        r = (yo - yh[est])
        if not np.all(np.isfinite(r)):  # a cubic can make the closed loop escape
            return np.full(len(r), 1e4)
        return r - r.mean()

    lo = [bnd[0]] + ([TF_B[0]] if needs_tf else [])
    hi = [bnd[1]] + ([TF_B[1]] if needs_tf else [])
    tf_grid = [math.log(t) for t in ((0.02, 0.1, 0.4, 1.2) if place != "D" else (0.03, 0.15, 0.6))]
    grid = [[p] + ([t] if needs_tf else []) for p in starts
            for t in (tf_grid if needs_tf else [0])]
    scored = sorted((float(np.sum(res(np.array(x)) ** 2)), x) for x in grid)
    best = None
    for _, x0 in scored[:2]:
        try:
            sol = optimize.least_squares(res, x0, bounds=(lo, hi), diff_step=0.02,
                                         max_nfev=max_nfev if place not in "DI" else 20,
                                         x_scale="jac")
        except Exception as e:  # noqa: BLE001
            print(f"  {place} {nl}: {e}", file=sys.stderr)
            continue
        if best is None or sol.cost < best.cost:
            best = sol
    if best is None or 2 * best.cost > scored[0][0]:  # keep the grid point if LS got worse
        x = np.array(scored[0][1], float)
    else:
        x = best.x
    tf = math.exp(x[1]) if needs_tf else None
    yh = mod.predict(place, nl, x[0], tf)
    if not np.all(np.isfinite(yh)):
        return -1e3, float(x[0]), tf
    p = float(x[0]) / (mod.i_scale(nl) if place == "I" else 1.0)  # bias-% equivalent
    return vfit(y, yh, est, val), p, tf

def fit_resonance(mod, y, est, val):
    """The rig's competing linear hypothesis: G (a s^2 + 2 z r w s + w^2)/(s^2 + 2 z w s + w^2)
    in series (rig/diagnose/effects/resonance.cpp: zeta <= 0.4, peak_ratio 0.05..20, hf_gain
    0..1); x = log f, zeta, log r, a."""
    yo = y[est]

    def pred(x):
        w, z, r, a = 2 * math.pi * math.exp(x[0]), x[1], math.exp(x[2]), x[3]
        num = np.polymul(mod.num, [a / w ** 2, 2 * z * r / w, 1.0])
        den = np.polymul(mod.den, [1 / w ** 2, 2 * z / w, 1.0])
        return Lin(num, den, mod.delay)(mod.u)

    def res(x):
        r = yo - pred(x)[est]
        return r - r.mean()
    lo, hi = [math.log(0.05), 0.005, math.log(0.05), 0.0], [math.log(45.0), 0.4, math.log(20.0), 1.0]
    best = None
    for f0 in (0.5, 1.76, 4.0, 8.0):
        for z0, r0, a0 in ((0.1, 1.5, 1.0), (0.1, 0.6, 1.0), (0.2, 0.05, 0.0)):
            sol = optimize.least_squares(res, [math.log(f0), z0, math.log(r0), a0],
                                         bounds=(lo, hi), max_nfev=60, x_scale="jac")
            if best is None or sol.cost < best.cost:
                best = sol
    x = best.x
    return vfit(y, pred(x), est, val), (math.exp(x[0]), x[1], math.exp(x[2]), x[3])

# ---------------------------------------------------------------- cases


def make(spec, seed, work):
    effect, size, con = spec
    name = f"{effect}-{con}"
    d = os.path.join(work, name)
    if os.path.exists(os.path.join(d, "oracle.json")):
        return d
    case = cs.make_case(name, effect, size, con, seed)
    p, p_after, _ = oracle.plan(case)  # column 0: the recording, as cases.py writes it
    sim = g.simulate(case["u"], p, seed=case["seed"], onset_s=case["onset_s"], p_after=p_after)
    orc = oracle.judge(case, sim["y"])
    cs.write_case(case, sim["y"][:, 0], d)
    with open(os.path.join(d, "oracle.json"), "w") as f:
        json.dump({k: v for k, v in orc.items()}, f, indent=1, default=float)
    return d


def run(args):
    spec, seed, work, all_d, places = args
    t0 = time.time()
    d = make(spec, seed, work)
    rec = np.loadtxt(os.path.join(d, "recording.csv"), delimiter=",", skiprows=1)
    u, y = rec[:, 1], rec[:, 2]
    doc = json.load(open(os.path.join(d, "model.json")))
    orc = json.load(open(os.path.join(d, "oracle.json")))
    truth = json.load(open(os.path.join(d, "truth.json")))["truths"]
    mod = Model(doc, u)
    est, val = blocks(len(y))
    base = vfit(y, mod.Gu, est, val)
    out = dict(case=os.path.basename(d), base=base, oracle=orc["gain"],
               oracle_det=orc["detectable"], truth=[t["truth"] for t in truth], rows={})
    # D sanity: the linear loop must reproduce G
    try:
        lin = mod.loop("rate", 0.0, 0.3, nonlinear=False)
        out["loop_check"] = float(np.max(np.abs(lin - mod.Gu)[500:]) / np.std(mod.Gu))
        out["L_poles_rhp"] = int(np.sum(mod.loop_parts(0.3)[2].real > 1e-9))
        lin = mod.loop("rate", 0.0, None, nonlinear=False)
        out["loop_check_I"] = float(np.max(np.abs(lin - mod.Gu)[500:]) / np.std(mod.Gu))
    except Exception as e:  # noqa: BLE001
        out["loop_check"] = repr(e)
    vr, pr = fit_resonance(mod, y, est, val) if "R" in places else (np.nan, (np.nan,) * 4)
    out["res"] = (vr - base, pr)
    eff = spec[0]
    for nl in NL:
        for place in places.replace("R", ""):
            if place in "DI" and not (all_d or nl in MATCH.get(eff, [])):
                continue
            vf, p, tf = fit_one(mod, y, est, val, place, nl)
            out["rows"][(place, nl)] = (vf - base, p, tf)
    out["secs"] = time.time() - t0
    return out


def report(results):
    print("\nvalidation fit gain over the baseline G (points); N parameter in bias-% units"
          " [Tf ms]; best N per placement (then the matched N's own line)")
    hdr = f"{'case':28s} {'base':>6s} {'oracle':>7s} | " + " | ".join(
        f"{p:^21s}" for p in "ABCDIE")
    print(hdr)
    print("-" * len(hdr))
    for r in results:
        def cell(place, nls):
            c = [(v[0], nl, v) for (pl, nl), v in r["rows"].items() if pl == place and nl in nls]
            if not c:
                return f"{'-':^21s}"
            gain, nl, (_, p, tf) = max(c, key=lambda t: t[0])
            s = f"{gain:+5.1f} {nl[:5]} {p:.2g}" + (f" [{tf*1e3:.0f}]" if tf else "")
            return f"{s:21s}"
        orc = f"{r['oracle']:+6.1f}{'' if r['oracle_det'] else '*'}"
        print(f"{r['case']:28s} {r['base']:6.1f} {orc:>7s} | "
              + " | ".join(cell(p, list(NL)) for p in "ABCDIE"))
        eff = r["case"].rsplit("-", 1)[0]
        for nl in MATCH.get(eff, []):
            print(f"{'   ' + nl:28s} {'':6s} {'':>7s} | " + " | ".join(cell(p, [nl]) for p in "ABCDIE"))
    print("\nR = the rig's resonance factor in series (gain; f Hz, zeta, peak_ratio, hf_gain):")
    for r in results:
        g_, (f_, z_, pr_, a_) = r["res"]
        print(f"  {r['case']:26s} {g_:+6.2f}  f {f_:.2f} zeta {z_:.3f} r {pr_:.2f} a {a_:.2f}")
    print("\ntruths (rig units):", {r["case"]: r["truth"] for r in results})
    r = results[0]
    print("linear-loop check, max |loop - G u| / std(G u): D (Tf 0.3 s)", r.get("loop_check"),
          " I", r.get("loop_check_I"), "; RHP poles of L:", r.get("L_poles_rhp"))
    print("\nfull table: case place N gain param Tf_ms")
    for r in results:
        for (pl, nl), (gain, p, tf) in sorted(r["rows"].items()):
            print(f"  {r['case']:26s} {pl} {nl:9s} {gain:+6.2f} {p:9.4g} "
                  + (f"{tf*1e3:7.1f}" if tf else "      -"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--work", default="/tmp/gensim_placement")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cases", default="", help="comma list of indices into CASES")
    ap.add_argument("--all-d", action="store_true", help="every N under D and I (slow)")
    ap.add_argument("--places", default="ABCDIER", help="R: the rig's resonance factor")
    a = ap.parse_args()
    specs = CASES if not a.cases else [CASES[int(i)] for i in a.cases.split(",")]
    work = os.path.join(a.work, f"seed{a.seed}")
    os.makedirs(work, exist_ok=True)
    with Pool(a.jobs) as pool:
        results = pool.map(run, [(s, a.seed, work, a.all_d, a.places) for s in specs], chunksize=1)
    report(results)
    print("\nseconds per case:", [round(r["secs"]) for r in results])


if __name__ == "__main__":
    main()
