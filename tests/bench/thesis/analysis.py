"""Figures from the models and recordings: the thesis's q-form, spreads, the matched AC
coupling, cross-correlation variance, differences against their standard error."""
import math
import numpy as np
from scipy.signal import lfilter

# Thesis 5-3 and the appended IEE paper (3.5 MW, 0.6 V rms, volts on the governor input):
# the average q's and their range over runs. H(s) = 1 / (q2 s^2 + q1 s + q0).
THESIS_Q = {'q2': (0.07, 0.04, 0.10), 'q1': (0.19, 0.14, 0.23), 'q0': (11.05, 9.6, 12.5)}
# A difference is "resolved" when it exceeds this many of its standard errors (about 95 %).
RESOLVE_SIGMAS = 2.0
SETTLING_E_FOLDS = 4.0        # 2 % settling time of a second order: 4 / (zeta wn)


def thesis_ratios():
    """The unit-free form of the thesis's average q's (q1/q2 = 2 zeta wn, q0/q2 = wn^2)."""
    q2, q1, q0 = (THESIS_Q[k][0] for k in ('q2', 'q1', 'q0'))
    wn = math.sqrt(q0 / q2)
    return {'q1_q2': q1 / q2, 'q0_q2': q0 / q2, 'fn_hz': wn / (2 * math.pi),
            'zeta': q1 / q2 / (2 * wn)}


def thesis_rel_spread():
    """Half the thesis's range over its mid-point, per q (unit-free, so comparable)."""
    return {k: (hi - lo) / (hi + lo) for k, (_, lo, hi) in THESIS_Q.items()}


def q_form(num, den, delay_s):
    """A 2/0 model b0 / (s^2 + a1 s + a0) as the thesis's q's and their unit-free ratios."""
    b0 = num[-1] / den[0]
    a1, a0 = den[1] / den[0], den[2] / den[0]
    wn = math.sqrt(max(a0, 0.0))
    return {'q2': 1 / b0, 'q1': a1 / b0, 'q0': a0 / b0, 'q1_q2': a1, 'q0_q2': a0,
            'delay_s': delay_s, 'gain': b0 / a0, 'fn_hz': wn / (2 * math.pi),
            'zeta': a1 / (2 * wn) if wn > 0 else float('nan')}


def from_identify(report):
    m = report['model']
    return q_form(m['num'], m['den'], m['delay_s'])


def from_commission(report):
    m = report['mmfm']
    return q_form(m['num'], m['den'], m['delay_s'])


def spread(values):
    """Mean, relative standard deviation, min, max and relative half-range of a list."""
    a = np.asarray(values, dtype=float)
    mean = float(a.mean())
    sd = float(a.std(ddof=1)) if a.size > 1 else float('nan')
    return {'n': int(a.size), 'mean': mean, 'sd': sd, 'rel_sd': sd / abs(mean),
            'min': float(a.min()), 'max': float(a.max()),
            'rel_half_range': float(a.max() - a.min()) / (2 * abs(mean))}


def spreads(models, keys):
    return {k: spread([m[k] for m in models]) for k in keys}


def difference(a, b):
    """b - a with its standard error (Welch) and whether it is resolved."""
    sa, sb = spread(a), spread(b)
    d = sb['mean'] - sa['mean']
    se = math.sqrt(sa['sd'] ** 2 / sa['n'] + sb['sd'] ** 2 / sb['n'])
    return {'diff': d, 'se': se, 'rel': d / abs(sa['mean']),
            'resolved': abs(d) > RESOLVE_SIGMAS * se}


def ac_couple(x, dt, rc):
    """The RC high-pass s RC / (1 + s RC) as the rig applies it (backward Euler), the same
    on both channels, so the identification sees matched coupling as in the thesis."""
    a = rc / (rc + dt)
    x = np.asarray(x, dtype=float)
    return lfilter([a, -a], [1.0, -a], x - x[0])


def cross_correlations(u, y, lags, block, skip):
    """r_yu(k), k = 0..lags-1, of each whole block: products at every skip-th anchor."""
    out = []
    for start in range(0, len(u) - block + 1, block):
        ub = u[start:start + block] - np.mean(u[start:start + block])
        yb = y[start:start + block] - np.mean(y[start:start + block])
        anchors = np.arange(0, block - lags + 1, skip)
        out.append([float(np.mean(ub[anchors] * yb[anchors + k])) for k in range(lags)])
    return np.asarray(out)


def correlation_noise(r, input_var):
    """Block-to-block spread of r_yu relative to its peak: the rms over lags of the blocks'
    standard deviation, over the peak of the mean, both per unit input variance."""
    r = r / input_var
    mean = r.mean(axis=0)
    return float(np.sqrt(np.mean(r.var(axis=0, ddof=1))) / np.max(np.abs(mean)))


def settling_time(fn_hz, zeta):
    return SETTLING_E_FOLDS / (zeta * 2 * math.pi * fn_hz)
