#!/usr/bin/python3
"""Concealed cases made by gensim: an effect x size x concealment, seeded.

Concealments (what hides the effect; nominal nuisances are always there: 2 kW transducer
noise, 2 kW / 60 s transducer drift, 5 mHz / 5 s grid frequency wander, 0.5 kW steps):
  plain      the large size, nothing more
  small      the small size against doubled transducer noise (4 kW)
  drift      the large size behind a 12 kW rms, 60 s transducer drift
  coupled    the large size, the power recorded through an AC coupling (RC 5 s) that the
             sidecar declares (coupling_rc_s, coupled_columns ["y"])
  partial    the large size, present from half-way through the record only
  pair       two large effects at once (PAIRS)
and the null cases (no effect): plain, small (4 kW noise), nuisances (grid wander 15 mHz,
4 kW drift, 2 kW quantisation, 2.5 kW noise: the set's normal operating noise), coupled.

A case directory holds recording.csv (t, u in % of rated power, y in kW), recording.json,
model.json (the nominal set's linear model of the rows, genset.nominal_model) and
truth.json. model.json is the same for every case.

    /usr/bin/python3 cases.py --effect backlash --concealment drift --seed 3 --out DIR
"""
import argparse
import json
import os

import numpy as np

import effects as fx
import genset as g

DURATION_S = 120.0     # record length: 12 000 rows (rig diagnose's 8 blocks of 15 s)
COUPLING_RC_S = 5.0    # the declared coupling of the `coupled` concealment
NOISE_SMALL_KW = 4.0   # `small`: doubled transducer noise
DRIFT_HIDE_KW = 12.0   # `drift`: 0.4 % of the 3.2 MW level, 60 s
NUISANCES = dict(grid_sd_hz=0.015, drift_kw=4.0, quant_kw=2.0, noise_kw=2.5)

CONCEALMENTS = ("plain", "small", "drift", "coupled", "partial")
NULL_CONCEALMENTS = ("plain", "small", "nuisances", "coupled")
# Two effects at once, as they come together on a worn or badly set-up set.
PAIRS = (("backlash", "periodic_disturbance"), ("dead_time", "rate_limit"),
         ("gain_change", "extra_lag"), ("saturation", "drift"),
         ("load_damping", "sensor_lag"), ("deadband", "periodic_disturbance"))


def concealments_for(effect):
    """A coupling neither hides behind a declared coupling nor switches on mid-record; a
    declared coupling removes most of a slow drift, and a drift does not hide behind one."""
    if effect == "ac_coupling":
        return ("plain", "small", "drift")
    if effect == "drift":
        return ("plain", "small", "partial")
    return CONCEALMENTS


def case_params(effect_names, size, concealment):
    """(p before, p after the onset or None, onset_s or None, truths)."""
    s = fx.scales()
    fx.calibrate_ripple()
    base = dict(g.NOMINAL)
    if concealment == "small":
        base["noise_kw"] = NOISE_SMALL_KW
    if concealment == "drift":
        base["drift_kw"] = DRIFT_HIDE_KW
    if concealment == "coupled":
        base["ac_rc_s"] = COUPLING_RC_S
    if concealment == "nuisances":
        base.update(NUISANCES)
    eff = dict(base)
    truths = []
    for name in effect_names:
        e = fx.EFFECTS[name]
        v = float(e.sizes[size](s))
        eff[e.key] = v
        eff.update(e.extra)
        t = e.truth(v, s) if e.truth else None
        truths.append(dict(effect=name, key=e.key, value=v, unit=e.unit, place=e.place,
                           rig_param=e.rig_param, truth=None if t is None else float(t)))
    if concealment == "partial":
        return base, eff, 0.5 * DURATION_S, truths
    return eff, None, None, truths


def make_case(case_id, effect, size, concealment, seed, exc="gaussian"):
    """A case as a dict (not yet written): u, y, params, truth."""
    names = [] if effect == "none" else effect.split("+")
    p, p_after, onset, truths = case_params(names, size, concealment)
    u = g.excitation(int(round(DURATION_S / g.DT)), seed * 7919 + 17, kind=exc)
    return dict(id=case_id, effect=effect, size=size, concealment=concealment, seed=seed,
                excitation=exc, u=u, p=p, p_after=p_after, onset_s=onset, truths=truths)


_MODEL = None


def model_doc():
    global _MODEL
    if _MODEL is None:
        _MODEL = g.nominal_model(g.NOMINAL)[0]
    return _MODEL


def write_case(case, y, out):
    os.makedirs(out, exist_ok=True)
    n = len(case["u"])
    t = np.arange(n) * g.DT
    np.savetxt(os.path.join(out, "recording.csv"), np.column_stack([t, case["u"], y]),
               delimiter=",", header="t,u,y", comments="", fmt=["%.2f", "%.6f", "%.4f"])
    side = dict(sample_rate_hz=1.0 / g.DT, y_sampled_after_s=0.0,
                units=dict(t="s", u="% of rated power", y="kW"),
                source=dict(simulator="gensim", case=case["id"], seed=case["seed"]))
    if case["concealment"] == "coupled":
        side.update(coupling_rc_s=COUPLING_RC_S, coupled_columns=["y"])
    with open(os.path.join(out, "recording.json"), "w") as f:
        json.dump(side, f, indent=1)
    with open(os.path.join(out, "model.json"), "w") as f:
        json.dump(model_doc(), f, indent=1)
    truth = {k: case[k] for k in ("id", "effect", "size", "concealment", "seed", "excitation",
                                  "onset_s", "truths")}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)


def case_list(seed, per_effect=None, quick=False):
    """The benchmark's cases: every effect under each of its concealments, the pairs and
    the null cases. quick: every other effect (by the seed's parity), one concealment each
    (rotated by the seed), one pair, two nulls."""
    rng = np.random.default_rng(seed)
    out = []
    names = list(fx.EFFECTS)
    for i, name in enumerate(names):
        cons = concealments_for(name)
        if quick:
            if (i + seed) % 2:
                continue
            cons = (cons[(i + seed) % len(cons)],)
        for c in cons:
            out.append((name, "small" if c == "small" else "large", c))
    pairs = PAIRS[seed % len(PAIRS):][:1] if quick else PAIRS
    for a, b in pairs:
        out.append((f"{a}+{b}", "large", "pair"))
    nulls = NULL_CONCEALMENTS[1:3] if quick else NULL_CONCEALMENTS + ("plain", "nuisances")
    for c in nulls:
        out.append(("none", "large", c))
    seeds = rng.integers(1, 10**6, len(out))
    return [dict(id=f"g{k:03d}", effect=e, size=s, concealment=c, seed=int(sd))
            for k, ((e, s, c), sd) in enumerate(zip(out, seeds))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--effect", default="none", help="an effect, a+b, or none")
    ap.add_argument("--size", default="large", choices=("large", "small"))
    ap.add_argument("--concealment", default="plain",
                    choices=CONCEALMENTS + ("pair", "nuisances"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--excitation", default="gaussian", choices=("gaussian", "prbs"))
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    case = make_case("manual", a.effect, a.size, a.concealment, a.seed, a.excitation)
    r = g.simulate(case["u"], case["p"], seed=case["seed"], onset_s=case["onset_s"],
                   p_after=case["p_after"])
    write_case(case, r["y"][:, 0], a.out)
    print(f"{a.out}: {a.effect} ({a.size}, {a.concealment}, seed {a.seed}); truth "
          + json.dumps(case["truths"]))


if __name__ == "__main__":
    main()
