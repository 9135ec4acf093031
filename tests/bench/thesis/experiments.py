"""The six experiments of the thesis reproduction (docs/thesis.md). Each returns a dict of
figures; the runs go one at a time, progress on stderr."""
import math, os
import numpy as np
from scipy.signal import butter, lfilter

import analysis as A
import runner as R
import runs as S

LOADS_KW = (2000, 3500)           # thesis 5-3: the set at 2 MW and 3.5 MW
STORNOWAY_KW = 3500               # the thesis's Stornoway parameters: 3.5 MW, 0.6 V rms
PREFIX_BLOCKS = (1, 2, 5, 10, 20, 40, 99)  # record lengths for the spread against length
Q_KEYS = ('q2', 'q1', 'q0', 'q1_q2', 'q0_q2', 'delay_s', 'gain', 'fn_hz', 'zeta')
PAIR_KEYS = ('q1_q2', 'q0_q2', 'delay_s', 'gain', 'fn_hz', 'zeta')
# Fig. 5-9: dead time left in (+) or over-corrected into a time advance (-), in % of the
# 2 % settling time, on a noise-free record as in the thesis's software simulation (5-1-2).
# The thesis's 10 and 20 % delays and 5 and 10 % advances of its -1 +- 3j system are 0.19 and
# 0.38, 0.1 and 0.19 of its ringing period; for the lightly damped 2 Hz mode the same share
# of the period is 3 and 6 %, 1.5 and 3 % of the settling time, where the fit has broken down
# (no stable 2/0 from about +3 %): the grid stays within.
FIG59_OFFSETS_PCT = (-3, -2, -1.5, -1, -0.5, 0, 0.5, 1, 1.5, 2, 3)
FIG59_BLOCKS = 20                 # a long noise-free record: the curve is the method's own
FIG59_SUBSTEPS = 8                # plant ticks per sample in the replay (4 ms)
FIG59_STD_PCT = 0.15              # about the plan at 3.5 MW (the plant is linear here)
# Static curve: the bias held at each level until settled (the power loop settles within
# 1e-3 kW in 30 s after a 10 % step), the last seconds averaged; levels over a wide bias.
STATIC_LEVELS_PCT = tuple(range(-30, 31, 5))
STATIC_LOADS_KW = LOADS_KW + (4600,)  # and at rated load, to reach the fuel limit (1.1 pu)
STATIC_HOLD_S = 30.0
STATIC_AVERAGE_S = 5.0
STATIC_DT_S = 0.01
STATIC_BIAS_LIMIT_PCT = 32        # plantsim's largest external bias clamp (default 5 %)
TEST_RANGE_PCT = 5                # the rig's clamp: the bias a commissioning test may use
NONLINEAR_REL = 0.02              # a local slope 2 % off the linear gain counts as non-linear


def seeds(base, offset, n):
    return [base + offset + i for i in range(n)]


def models(rs, source, n):
    """The runs' q-forms from one estimator (online | mmfm) at record length n blocks."""
    key = 'online_at' if source == 'online' else 'mmfm'
    return [r[key][n] for r in rs if r[key].get(n)]


def linearisations(ctx):
    out = {}
    for kw in LOADS_KW:
        doc = R.linearise(ctx.plantsim, R.plant_toml(ctx.plantsim, ctx.out, kw),
                          os.path.join(ctx.out, f'linearised_{kw}kw.json'))
        d = doc['derived']['sopdt_0p5_5hz']
        wn = 2 * math.pi * d['fn_hz']
        out[kw] = {'gain': d['gain_kw_per_pct'], 'fn_hz': d['fn_hz'], 'zeta': d['zeta'],
                   'delay_s': d['delay_s'], 'q1_q2': 2 * d['zeta'] * wn, 'q0_q2': wn * wn,
                   'dc_gain': doc['derived']['dc_gain_kw_per_pct']}
    return out


def stornoway(ctx, lin):
    """20+ runs at 3.5 MW with the thesis's settings and record length: the spread."""
    R.log(f'stornoway: {ctx.runs} runs of {ctx.blocks} blocks at {STORNOWAY_KW} kW')
    sd = seeds(ctx.seed, 0, ctx.runs)
    prefixes = sorted(set(PREFIX_BLOCKS) | {ctx.cell_blocks, ctx.blocks})
    rs = S.series(ctx, 'stornoway', STORNOWAY_KW, 'gaussian', S.PLAN_FULL, sd,
                  detail_first=True, prefixes=prefixes)
    lengths = [n for n in prefixes if n <= ctx.blocks]
    vs_length = {src: {n: A.spreads(models(rs, src, n), Q_KEYS) for n in lengths}
                 for src in ('online', 'mmfm')}
    return {'seeds': [r['seed'] for r in rs], 'runs': rs, 'blocks': ctx.blocks,
            'record_s': ctx.blocks * S.BLOCK / S.SAMPLE_RATE_HZ,
            'online': vs_length['online'][ctx.blocks], 'mmfm': vs_length['mmfm'][ctx.blocks],
            'vs_length': vs_length, 'snr_db': A.spread([r['snr_db'] for r in rs]),
            'std_pct': A.spread([r['applied_std_pct'] for r in rs]),
            'max_dev_pct': max(r['max_dev_pct'] for r in rs),
            'thesis': A.thesis_ratios(), 'thesis_rel': A.thesis_rel_spread(),
            'truth': lin[STORNOWAY_KW]}


def loads_amplitudes(ctx, e1, lin):
    """Two loads x two excitation amplitudes: the rig's plan (80 % of the +-3 % band) and
    half its std; the 3.5 MW full-amplitude cell is e1's runs at the same record length."""
    n = ctx.cell_blocks
    sub = ctx.with_blocks(n)
    cells = []
    for i, kw in enumerate(LOADS_KW):
        full = e1['runs'] if kw == STORNOWAY_KW else cell_runs(
            sub, kw, None, seeds(ctx.seed, 100 + 200 * i, ctx.cell_runs))
        half_std = float(np.mean([r['planned_std_pct'] for r in full])) / 2
        half = cell_runs(sub, kw, half_std, seeds(ctx.seed, 200 + 200 * i, ctx.cell_runs))
        cells += [cell(kw, 'plan', full, n), cell(kw, 'half', half, n)]
    return {'blocks': n, 'cells': cells, 'linearisation': lin,
            'differences': differences(cells, lin)}


def cell_runs(ctx, kw, std_pct, sd):
    what = 'the plan' if std_pct is None else f'std {std_pct:.4f} %'
    R.log(f'loads: {kw} kW, {what}: {len(sd)} runs of {ctx.blocks} blocks')
    return S.series(ctx, f'load{kw}_' + ('plan' if std_pct is None else 'half'), kw,
                    'gaussian', S.PLAN_FULL, sd, prefixes=(ctx.blocks,), std_pct=std_pct)


def cell(kw, amp, rs, n):
    c = {'load_kw': kw, 'amplitude': amp, 'seeds': [r['seed'] for r in rs],
         'std_pct': A.spread([r['applied_std_pct'] for r in rs]),
         'snr_db': A.spread([r['snr_db'] for r in rs]),
         'online_models': models(rs, 'online', n), 'mmfm_models': models(rs, 'mmfm', n)}
    for src in ('online', 'mmfm'):
        c[src] = A.spreads(c[src + '_models'], Q_KEYS)
    return c


def differences(cells, lin):
    """Load effect at each amplitude and amplitude effect at each load, per estimator."""
    by = {(c['load_kw'], c['amplitude']): c for c in cells}
    pairs = [('load', (2000, p), (3500, p)) for p in ('plan', 'half')]
    pairs += [('amplitude', (kw, 'half'), (kw, 'plan')) for kw in LOADS_KW]
    out = []
    for what, a, b in pairs:
        row = {'what': what, 'a': a, 'b': b}
        for src in ('online', 'mmfm'):
            ma, mb = by[a][src + '_models'], by[b][src + '_models']
            row[src] = {k: A.difference([m[k] for m in ma], [m[k] for m in mb])
                        for k in PAIR_KEYS}
        if what == 'load':
            row['linearisation'] = {k: lin[b[0]][k] / lin[a[0]][k] - 1 for k in PAIR_KEYS}
        out.append(row)
    return out


def table52(e1):
    """Non-averaged estimates: the thesis's method on single blocks of the first run."""
    first = e1['runs'][0]
    blocks = [m for m in first.get('blocks', []) if m]
    return {'seed': first['seed'], 'blocks': blocks, 'failed': len(first['blocks']) - len(blocks),
            'spread': A.spreads(blocks, Q_KEYS), 'averaged': e1['mmfm'],
            'record_blocks': e1['blocks']}


def fig59(ctx, lin):
    """A dead time left in or over-corrected: MMFM 2/0 with the dead time fixed at the
    reference (its own estimate on the same record) minus an offset, on Gaussian noise
    (seed ctx.seed) replayed through the noise-free plant at 3.5 MW."""
    truth = lin[STORNOWAY_KW]
    ts = A.settling_time(truth['fn_hz'], truth['zeta'])
    u, y = noise_free_record(ctx)
    out = os.path.join(ctx.out, 'fig59')
    ref = S.identify(ctx, u, y, out, 'reference', 0.0)
    rows = []
    for p in FIG59_OFFSETS_PCT:
        q = ref if p == 0 else S.identify(ctx, u, y, out, f'offset{p}', 0.0,
                                          delay=ref['delay_s'] - p / 100 * ts)
        r = {'offset_pct': p, 'offset_s': p / 100 * ts, 'model': q}
        if q:
            r['rel'] = {k: q[k] / ref[k] - 1 for k in ('gain', 'zeta', 'fn_hz', 'q1_q2',
                                                       'q0_q2')}
        rows.append(r)
    return {'seed': ctx.seed, 'settling_s': ts, 'reference_delay_s': ref['delay_s'],
            'blocks': FIG59_BLOCKS, 'rows': rows}


def noise_free_record(ctx):
    """Band-limited Gaussian noise held per sample, through plantsim --replay (no noise,
    drift, pick-up or ripple), sampled and AC coupled as the rig's rows are."""
    n = FIG59_BLOCKS * S.BLOCK
    fast = S.SAMPLE_RATE_HZ * FIG59_SUBSTEPS
    b, a = butter(4, S.BANDWIDTH_HZ / (fast / 2))
    w = lfilter(b, a, np.random.default_rng(ctx.seed).standard_normal(n * FIG59_SUBSTEPS))
    u = w[::FIG59_SUBSTEPS] / np.std(w) * FIG59_STD_PCT
    held = np.repeat(u, FIG59_SUBSTEPS)
    t = np.arange(len(held)) / fast
    os.makedirs(os.path.join(ctx.out, 'fig59'), exist_ok=True)
    power = R.replay(ctx.plantsim, R.plant_toml(ctx.plantsim, ctx.out, STORNOWAY_KW), t, held)
    y = np.asarray(power)[::FIG59_SUBSTEPS]
    dt = 1 / S.SAMPLE_RATE_HZ
    return A.ac_couple(u, dt, S.AC_RC_S), A.ac_couple(y, dt, S.AC_RC_S)


def gauss_prbs(ctx, e1):
    """Gaussian against PRBS at the same planned amplitude and record length (thesis 3-2)."""
    n = ctx.cell_blocks
    R.log(f'gauss_prbs: {ctx.prbs_runs} PRBS runs of {n} blocks at {STORNOWAY_KW} kW')
    rs = S.series(ctx.with_blocks(n), 'prbs', STORNOWAY_KW, 'prbs', S.PLAN_FULL,
                  seeds(ctx.seed, 600, ctx.prbs_runs), prefixes=(n,))
    out = {'blocks': n, 'seeds_prbs': [r['seed'] for r in rs], 'seeds_gaussian': e1['seeds']}
    for kind, runs in (('gaussian', e1['runs']), ('prbs', rs)):
        out[kind] = {'online': A.spreads(models(runs, 'online', n), Q_KEYS),
                     'mmfm': A.spreads(models(runs, 'mmfm', n), Q_KEYS),
                     'corr_noise': A.spread([r['corr_noise'] for r in runs]),
                     'std_pct': A.spread([r['applied_std_pct'] for r in runs]),
                     'corr_mean': runs[0]['corr_mean'] if runs else []}
    out['variance_ratio'] = {
        src: {k: (out['prbs'][src][k]['sd'] / out['gaussian'][src][k]['sd']) ** 2
              for k in PAIR_KEYS} for src in ('online', 'mmfm')}
    out['corr_variance_ratio'] = (out['prbs']['corr_noise']['mean'] /
                                  out['gaussian']['corr_noise']['mean']) ** 2
    return out


def static_curve(ctx, lin):
    """The bias in slow steps through the noise-free plant (plantsim --replay) at both loads;
    the gain in the test range against the linearisation."""
    out = {}
    for kw in STATIC_LOADS_KW:
        dc_gain = lin[kw]['dc_gain'] if kw in lin else R.linearise(
            ctx.plantsim, R.plant_toml(ctx.plantsim, ctx.out, kw),
            os.path.join(ctx.out, f'linearised_{kw}kw.json'))['derived']['dc_gain_kw_per_pct']
        cfg = R.plant_toml_with(ctx.plantsim, ctx.out, kw, f'plant_{kw}kw_wide.toml',
                                {'ext_bias_limit_pct': STATIC_BIAS_LIMIT_PCT})
        levels = [0.0] + list(STATIC_LEVELS_PCT) + list(reversed(STATIC_LEVELS_PCT))
        per = int(round(STATIC_HOLD_S / STATIC_DT_S))
        bias = [lv for lv in levels for _ in range(per)]
        t = [k * STATIC_DT_S for k in range(len(bias))]
        power = np.asarray(R.replay(ctx.plantsim, cfg, t, bias))
        tail = int(round(STATIC_AVERAGE_S / STATIC_DT_S))
        settled = [float(power[(i + 1) * per - tail:(i + 1) * per].mean())
                   for i in range(len(levels))]
        out[kw] = static_figures(levels, settled, dc_gain, kw)
        R.log(f'static: {kw} kW: gain in +-{TEST_RANGE_PCT} % {out[kw]["gain"]:.2f} kW/%')
    return out


def static_figures(levels, settled, dc_gain, p0_kw):
    lv, p = np.asarray(levels), np.asarray(settled)
    inside = np.abs(lv) <= TEST_RANGE_PCT
    gain = float(np.polyfit(lv[inside], p[inside], 1)[0])
    up = len(STATIC_LEVELS_PCT) + 1
    x, yv = lv[1:up], p[1:up]
    slopes = np.diff(yv) / np.diff(x)
    off = [float((x[i] + x[i + 1]) / 2) for i in range(len(slopes))
           if abs(slopes[i] / dc_gain - 1) > NONLINEAR_REL]
    return {'levels_pct': levels, 'power_kw': settled, 'gain': gain, 'dc_gain': dc_gain,
            'gain_rel': gain / dc_gain - 1, 'local_slopes': slopes.tolist(),
            'nonlinear_at_pct': off, 'p0_kw': p0_kw,
            'hysteresis_kw': float(np.max(np.abs(yv - p[up:][::-1])))}
