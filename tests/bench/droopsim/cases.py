#!/usr/bin/python3
"""Concealed cases made by droopsim: an effect x a drawn size x a concealment, seeded.

Always present (the set's ordinary noise): 1.5 kW A/D noise, 0.5 kW quantisation, a 1.5 kW
rms / 40 s transducer zero drift, a 4 mHz rms / 8 s grid frequency wander (through the droop
about 5 kW of slow power). Sizes are drawn log-uniformly between the effect's "just
detectable" and "clearly visible" ends (effects.py); `plain` and pairs draw from the middle
third. Concealments:
  plain      a mid size, nothing more
  noisy      3x the A/D noise (4.5 kW)
  load_step  a grid frequency event part-way (20-50 mHz either way, falling in 2 s and
             recovering to 40 % in about 45 s: 12-31 kW through the droop)
  late       the effect present only in the last third (from 100 s of 150 s)
  coupled8   y recorded through a declared 8 s AC coupling (sidecar coupling_rc_s 8,
             coupled_columns ["y"])
  wander     3x the grid frequency wander (12 mHz rms)
  pair       two effects at once (PAIRS)
Each effect gets plain, noisy, late and two of load_step/coupled8/wander (rotated with the
effect and the seed); an AC coupling is neither late nor behind a declared coupling, a drift
not behind a declared coupling. Nulls: plain (2), noisy, wander, load_step, coupled8,
nuisances (2x noise, 2x wander, 3 kW drift, 1 kW quantisation).

    /usr/bin/python3 cases.py --effect backlash --concealment noisy --seed 3 --out DIR
"""
import argparse
import json
import os

import numpy as np

import effects as fx
import linear as ln
import plant as pl

DURATION_S = 150.0
COUPLING_RC_S = 8.0
LATE_ONSET_S = 100.0
NOISY_KW = 4.5
WANDER_HZ = 0.012
NUISANCES = dict(noise_kw=3.0, grid_sd_hz=0.008, drift_kw=3.0, quant_kw=1.0)
CONCEALMENTS = ("plain", "noisy", "load_step", "late", "coupled8", "wander")  # + "pair"
ROTATED = ("load_step", "coupled8", "wander")
NULLS = ("plain", "plain", "noisy", "wander", "load_step", "coupled8", "nuisances")
PAIRS = (("sensor_lag", "backlash"), ("saturation", "periodic_disturbance"),
         ("dead_time", "gain_change"), ("rate_limit", "drift"), ("deadband", "extra_lag"),
         ("hysteresis", "load_damping"))


def concealments_for(name, i, seed):
    if name == "ac_coupling":
        return ("plain", "noisy", "load_step", "wander")
    if name == "drift":
        return ("plain", "noisy", "late", "load_step", "wander")
    k = (i + seed) % 3
    return ("plain", "noisy", "late") + tuple(ROTATED[j] for j in range(3) if j != k)


def case_params(names, concealment, rng):
    """(p before, p after the onset or None, onset_s or None, truths)."""
    s = fx.scales()
    base = dict(pl.NOMINAL)
    if concealment == "noisy":
        base["noise_kw"] = NOISY_KW
    if concealment == "wander":
        base["grid_sd_hz"] = WANDER_HZ
    if concealment == "coupled8":
        base["ac_rc_s"] = COUPLING_RC_S
    if concealment == "nuisances":
        base.update(NUISANCES)
    if concealment == "load_step":
        base["step_hz"] = float(rng.choice([-1, 1]) * rng.uniform(0.02, 0.05))
        base["step_s"] = float(rng.uniform(35.0, 115.0))
    eff = dict(base)
    truths = []
    for name in names:
        e = fx.EFFECTS[name]
        x, sg = fx.draw(name, rng, "mid" if concealment in ("plain", "pair") else "all")
        v = float(e.value(x, s, sg))
        eff[e.key] = v
        eff.update(e.extra)
        t = e.truth(v, s) if e.truth else None
        truths.append(dict(effect=name, key=e.key, value=v, unit=e.unit, place=e.place,
                           size=x, size_unit=e.size_unit, rig_param=e.rig_param,
                           truth=None if t is None else float(t)))
    if concealment == "late":
        return base, eff, LATE_ONSET_S, truths
    return eff, None, None, truths


def make_case(case_id, effect, concealment, seed):
    rng = np.random.default_rng(seed)
    names = [] if effect == "none" else effect.split("+")
    p, p_after, onset, truths = case_params(names, concealment, rng)
    u = pl.excitation(int(round(DURATION_S / pl.DT)), seed * 7907 + 3)
    return dict(id=case_id, effect=effect, concealment=concealment, seed=seed, u=u, p=p,
                p_after=p_after, onset_s=onset, truths=truths,
                grid_event=dict(step_hz=p["step_hz"], step_s=p["step_s"])
                if concealment == "load_step" else None)


_MODEL = None


def model_doc():
    global _MODEL
    if _MODEL is None:
        _MODEL = ln.nominal_model(pl.NOMINAL)[0]
    return _MODEL


def write_recording(case, y, freq_hz, out):
    """recording.csv: t, u, y and the bus frequency as the rig records it (freq_hz)."""
    n = len(case["u"])
    t = np.arange(n) * pl.DT
    np.savetxt(os.path.join(out, "recording.csv"), np.column_stack([t, case["u"], y, freq_hz]),
               delimiter=",", header="t,u,y,freq_hz", comments="",
               fmt=["%.2f", "%.6f", "%.4f", "%.3f"])


def write_case(case, y, freq_hz, out):
    os.makedirs(out, exist_ok=True)
    write_recording(case, y, freq_hz, out)
    side = dict(sample_rate_hz=1.0 / pl.DT, y_sampled_after_s=0.0,
                units=dict(t="s", u="% of rated power", y="kW", freq_hz="Hz"),
                source=dict(simulator="droopsim", case=case["id"], seed=case["seed"]))
    if case["concealment"] == "coupled8":
        side.update(coupling_rc_s=COUPLING_RC_S, coupled_columns=["y"])
    with open(os.path.join(out, "recording.json"), "w") as f:
        json.dump(side, f, indent=1)
    with open(os.path.join(out, "model.json"), "w") as f:
        json.dump(model_doc(), f, indent=1)
    truth = {k: case[k] for k in ("id", "effect", "concealment", "seed", "onset_s", "truths",
                                  "grid_event")}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)


def case_list(seed, quick=False):
    """Every effect under its concealments, the pairs, the nulls (quick: one concealment
    for every other effect, two pairs, two nulls)."""
    rng = np.random.default_rng(seed + 1000)
    out = []
    for i, name in enumerate(fx.EFFECTS):
        cons = concealments_for(name, i, seed)
        if quick:
            if (i + seed) % 2:
                continue
            cons = (cons[(i + seed) % len(cons)],)
        out += [(name, c) for c in cons]
    pairs = PAIRS[seed % 3::3] if quick else PAIRS
    out += [(f"{a}+{b}", "pair") for a, b in pairs]
    out += [("none", c) for c in (NULLS[1:3] if quick else NULLS)]
    seeds = rng.integers(1, 10 ** 6, len(out))
    return [dict(id=f"d{k:03d}", effect=e, concealment=c, seed=int(sd))
            for k, ((e, c), sd) in enumerate(zip(out, seeds))]


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--effect", default="none", help="an effect, a+b, or none")
    ap.add_argument("--concealment", default="plain", choices=CONCEALMENTS + ("pair", "nuisances"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    case = make_case("manual", a.effect, a.concealment, a.seed)
    r = pl.simulate(case["u"], case["p"], seed=case["seed"], onset_s=case["onset_s"],
                    p_after=case["p_after"])
    write_case(case, r["y"][:, 0], a.out)
    print(f"{a.out}: {a.effect} ({a.concealment}, seed {a.seed}); truth "
          + json.dumps(case["truths"]))


if __name__ == "__main__":
    main()
