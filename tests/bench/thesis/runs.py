"""The commissioning runs (rig commission against plantsim at the thesis's settings) and what
is drawn from each: the rig's own online estimate, the thesis's method (MMFM on the matched
AC-coupled record, `rig identify`) on record prefixes and single blocks, the signal-to-noise
ratio and the block-to-block variance of the cross-correlation."""
import json, math, os
import numpy as np

import analysis as A
import runner as R

# Thesis settings (5-3-1, 3-1-2, 4; the IEE paper):
LAGS = 64                 # "a sixty four point correlation function"
SAMPLE_RATE_HZ = 31.25    # 64 lags then span 2.05 s: "the sample window of the correlation
                          # functions being approximately two seconds" (3-1-2); 32 plant ticks
LOCKSTEP_TICKS = 32       # 32 ms per sample at plantsim's 1 ms tick
BLOCK = 2048              # samples per block: "two blocks of 2048 bytes" per transfer
SKIP = 8                  # "a skip of eight was used"
WEIGHT = 50               # "an exponential averaging weighting factor of fifty"
BANDWIDTH_HZ = 5.0        # "a noise signal of 5 Hz bandwidth" (5-3-2)
AC_RC_S = 1.6             # 0.1 Hz coupling on both channels (the IEE paper, the rig's default)
PLAN_FULL = 0.8           # planned peak 80 % of the +-3 % band: "never exceed +-3 %"
CLAMP_SIGMAS = 3.0        # the rig caps the planned std at clamp_pct / 3 (Gaussian clipped
                          # at 3 sigma): a clamp of 3 std fixes the std whatever the plan
PILOT_PCT = 0.3           # the default pilot amplitude, lowered to the clamp when above it
PRBS_DIVIDER = 3          # PRBS clock 10.4 Hz: its -3 dB point 4.6 Hz, near the Gaussian's 5 Hz
PRBS_REGISTER = 10
EXCITE_CODE = 2           # recording.csv phase code of the excitation
MODEL_KEYS = ('q2', 'q1', 'q0', 'q1_q2', 'q0_q2', 'delay_s', 'gain', 'fn_hz', 'zeta')


def sections(kind, plan_fraction, blocks, weight, seed, std_pct=None):
    """The test TOML; std_pct fixes the excitation's std (% of rated) below the plan."""
    seconds = blocks * BLOCK / SAMPLE_RATE_HZ
    exc = {'type': kind, 'bandwidth_hz': BANDWIDTH_HZ, 'seed': seed,
           'ac_coupling_rc_s': AC_RC_S}
    if kind == 'prbs':
        exc.update(prbs_register_length=PRBS_REGISTER, prbs_clock_divider=PRBS_DIVIDER)
    safety = {'plan_fraction': plan_fraction}
    if std_pct:
        safety['clamp_pct'] = round(CLAMP_SIGMAS * std_pct, 6)
    return {'link': {'sample_rate_hz': SAMPLE_RATE_HZ, 'lockstep_ticks': LOCKSTEP_TICKS},
            'safety': safety,
            'pilot': {'amplitude_pct': min(PILOT_PCT, safety.get('clamp_pct', PILOT_PCT))},
            'excitation': exc,
            'mmfm': {'auto_order': False, 'order_n': 2, 'order_m': 0, 'lags': LAGS,
                     'block_size': BLOCK, 'skip': SKIP, 'averaging': 'exponential',
                     'averaging_w': weight, 'min_duration_s': seconds,
                     'max_duration_s': seconds},
            'sweep': {'enabled': False}}


def run(ctx, load_kw, kind, plan_fraction, seed, tag, prefixes=(), per_block=False,
        keep=False, std_pct=None):
    """One commissioning run and its figures (None when the rig produced no estimate)."""
    out = os.path.join(ctx.out, 'runs', f'{tag}_seed{seed}')
    cfg = R.plant_toml(ctx.plantsim, ctx.out, load_kw)
    rep, code = R.commission(ctx.rig, ctx.plantsim, cfg, seed,
                             sections(kind, plan_fraction, ctx.blocks, WEIGHT, seed, std_pct),
                             out)
    if rep is None or not rep.get('mmfm'):
        R.log(f'  seed {seed}: no estimate (exit {code})')
        return None
    res = {'seed': seed, 'load_kw': load_kw, 'kind': kind, 'plan_fraction': plan_fraction,
           'exit_code': code, 'online': A.from_commission(rep),
           'online_at': {n: A.q_form(h['num'], h['den'], h['delay_s'])
                         for n, h in enumerate(rep['history'], 1) if h.get('ok') and
                         (n in prefixes or n == ctx.blocks)},
           'planned_std_pct': rep['excitation']['planned_std_pct'],
           'applied_std_pct': rep['excitation']['applied_std_pct'],
           'p0_kw': rep['steady_state']['p0_kw'],
           'max_dev_pct': rep['safety']['max_abs_deviation_pct']}
    u, y = coupled_excitation(os.path.join(out, 'rig', 'recording.csv'), ctx.blocks)
    shift = timing_shift(os.path.join(out, 'rig', 'recording.json'))
    noise_kw = rep['steady_state']['noise_pct'] / 100 * res['p0_kw']
    signal_kw = math.sqrt(max(float(np.var(y)) - noise_kw ** 2, 0.0))
    res.update(noise_kw=noise_kw, response_kw=signal_kw,
               snr_db=20 * math.log10(signal_kw / noise_kw) if signal_kw > 0 else float('nan'))
    res['mmfm'] = {}
    for n in prefixes:
        if n <= ctx.blocks:
            res['mmfm'][n] = identify(ctx, u[:n * BLOCK], y[:n * BLOCK], out, f'prefix{n}',
                                      shift)
    if per_block:
        res['blocks'] = [identify(ctx, u[k * BLOCK:(k + 1) * BLOCK],
                                  y[k * BLOCK:(k + 1) * BLOCK], out, f'block{k}', shift)
                         for k in range(ctx.blocks)]
    r = A.cross_correlations(u, y, LAGS, BLOCK, SKIP)
    res['corr_noise'] = A.correlation_noise(r, float(np.var(u)))
    res['corr_mean'] = (r.mean(axis=0) / float(np.var(u))).tolist()
    if not keep:  # the report.json stays; the recording and the page are 4-5 MB a run
        for name in ('recording.csv', 'report.html'):
            os.remove(os.path.join(out, 'rig', name))
    return res


def coupled_excitation(path, blocks):
    """The excitation's first `blocks` blocks of u and y, AC coupled (0.1 Hz) over the whole
    recording as the thesis's logger saw them."""
    _, u, y, phase = R.read_recording(path)
    dt = 1 / SAMPLE_RATE_HZ
    uc, yc = A.ac_couple(u, dt, AC_RC_S), A.ac_couple(y, dt, AC_RC_S)
    first = phase.index(EXCITE_CODE)
    n = blocks * BLOCK
    if phase[first:first + n].count(EXCITE_CODE) < n:
        raise RuntimeError(f'{path}: fewer than {blocks} blocks of excitation')
    return uc[first:first + n], yc[first:first + n]


def write(out, name, u, y):
    path = os.path.join(out, name + '.csv')
    R.write_recording(path, [k / SAMPLE_RATE_HZ for k in range(len(u))], u, y)
    return path


def timing_shift(sidecar):
    """What to add to a dead time identified from raw rows to refer it to the plant, as the
    rig does for its own estimates: the power is sampled y_sampled_after_s after the write,
    the bias held for one sample (docs/decisions.md, sample timing correction)."""
    with open(sidecar) as fh:
        doc = json.load(fh)
    return doc['y_sampled_after_s'] - 0.5 / doc['sample_rate_hz']


def identify(ctx, u, y, out, name, shift, delay='auto'):
    """The thesis's method on a stretch of record: MMFM, 2/0, 64 lags, skip 8; the dead
    time referred to the plant (shift)."""
    fixed = delay if delay == 'auto' else delay - shift
    if fixed != 'auto' and fixed < 0:
        # rig identify takes no negative dead time: the output is moved earlier by whole
        # samples instead and their time added back to the fixed dead time.
        k = math.ceil(-fixed * SAMPLE_RATE_HZ)
        u, y, fixed = u[:-k], y[k:], fixed + k / SAMPLE_RATE_HZ
    path = write(out, name, u, y)
    rep = R.identify(ctx.rig, path, delay=fixed, lags=LAGS, skip=SKIP)
    os.remove(path)
    if not rep:
        return None
    q = A.from_identify(rep)
    q['delay_s'] += shift
    return q


def series(ctx, tag, load_kw, kind, plan_fraction, seeds, detail_first=False, prefixes=(),
           std_pct=None):
    """Runs over seeds, progress on stderr; the runs that gave an estimate (with
    detail_first, the first run's coupled record is kept and its blocks identified)."""
    done = []
    for i, seed in enumerate(seeds):
        first = detail_first and i == 0
        r = run(ctx, load_kw, kind, plan_fraction, seed, tag, prefixes, per_block=first,
                keep=first, std_pct=std_pct)
        if r:
            o = r['online']
            R.log(f'  {tag} seed {seed} ({i + 1}/{len(seeds)}): K {o["gain"]:.2f} kW/% '
                  f'fn {o["fn_hz"]:.3f} Hz zeta {o["zeta"]:.4f} Td {o["delay_s"] * 1e3:.1f} ms'
                  f' SNR {r["snr_db"]:.1f} dB')
            done.append(r)
    return done
