"""The figures as tables (title, header, rows), rendered as markdown for the console and as
HTML for the page. Ours beside the thesis's wherever the thesis gives a figure."""
import analysis as A
import experiments as E

NAMES = {'q2': 'q2', 'q1': 'q1', 'q0': 'q0', 'q1_q2': 'q1/q2 = 2 zeta wn (1/s)',
         'q0_q2': 'q0/q2 = wn^2 (1/s^2)', 'delay_s': 'delay (ms)', 'gain': 'K (kW/%)',
         'fn_hz': 'fn (Hz)', 'zeta': 'zeta'}
SCALE = {'delay_s': 1e3}
RATIO_KEYS = ('q1_q2', 'q0_q2', 'fn_hz', 'zeta', 'delay_s', 'gain')


def f(x, digits=3):
    if x is None or x != x:
        return '-'
    return f'{x:.{digits}g}' if abs(x) < 1e4 else f'{x:.0f}'


def pct(x, digits=1):
    return '-' if x is None or x != x else f'{100 * x:+.{digits}f} %'


def rel(x):
    return '-' if x is None or x != x else f'{100 * x:.1f} %'


def mean_sd(s, key):
    k = SCALE.get(key, 1)
    return f'{f(s["mean"] * k, 4)} +- {f(s["sd"] * k, 2)}'


def stornoway(e):
    th, tr = e['thesis'], A.THESIS_Q
    t1 = ('Stornoway parameters, relative spread over runs (unit-free)',
          ['q', 'thesis range', 'thesis half-range / mid', 'online: half-range / mean',
           'online: sd / mean', 'MMFM: half-range / mean', 'MMFM: sd / mean'],
          [[k, f'{tr[k][1]}-{tr[k][2]}', rel(e['thesis_rel'][k]),
            rel(e['online'][k]['rel_half_range']), rel(e['online'][k]['rel_sd']),
            rel(e['mmfm'][k]['rel_half_range']), rel(e['mmfm'][k]['rel_sd'])]
           for k in ('q2', 'q1', 'q0')])
    t2 = ('Stornoway parameters, unit-free form (mean +- sd over runs)',
          ['quantity', 'thesis (averages)', 'online (rig commission)', 'MMFM (thesis method)',
           'plantsim linearisation (SOPDT 0.5-5 Hz)'],
          [[NAMES[k], f(th[k] * SCALE.get(k, 1), 4) if k in th else 'not given',
            mean_sd(e['online'][k], k), mean_sd(e['mmfm'][k], k),
            f(e['truth'][k] * SCALE.get(k, 1), 4)] for k in RATIO_KEYS])
    lengths = sorted(e['vs_length']['mmfm'])
    t3 = ('Relative sd against record length (blocks of 2048 samples)',
          ['blocks', 'seconds'] + [f'{src} {k}' for src in ('online', 'MMFM')
                                    for k in ('q1/q2', 'q0/q2', 'delay')],
          [[n, f(n * 2048 / 31.25, 4)] + [rel(e['vs_length'][src][n][k]['rel_sd'])
                                         for src in ('online', 'mmfm')
                                         for k in ('q1_q2', 'q0_q2', 'delay_s')]
           for n in lengths])
    t4 = ('q2, q1, q0 of the thesis\'s method against record length: half-range / mean over '
          'runs, beside the thesis\'s range over its runs',
          ['blocks', 'seconds', 'q2', 'q1', 'q0'],
          [[n, f(n * 2048 / 31.25, 4)] + [rel(e['vs_length']['mmfm'][n][k]['rel_half_range'])
                                         for k in ('q2', 'q1', 'q0')] for n in lengths] +
          [['thesis', '-'] + [rel(e['thesis_rel'][k]) for k in ('q2', 'q1', 'q0')]])
    return [t1, t2, t3, t4]


def loads(e):
    lin = e['linearisation']
    cells = ('Loads x amplitudes (mean +- sd over runs)',
             ['load kW', 'amplitude', 'std %', 'SNR dB', 'est.', 'fn Hz', 'zeta', 'K kW/%',
              'delay ms', 'runs'],
             [])
    for c in e['cells']:
        for src in ('online', 'mmfm'):
            s = c[src]
            cells[2].append([c['load_kw'], c['amplitude'], f(c['std_pct']['mean']),
                             f(c['snr_db']['mean']), src] +
                            [mean_sd(s[k], k) for k in ('fn_hz', 'zeta', 'gain', 'delay_s')] +
                            [s['fn_hz']['n']])
    for kw in sorted(lin):
        cells[2].append([kw, '-', '-', '-', 'linearisation'] +
                        [f(lin[kw][k] * SCALE.get(k, 1), 4)
                         for k in ('fn_hz', 'zeta', 'gain', 'delay_s')] + ['-'])
    diffs = ('Differences (b - a, relative to a; resolved when beyond 2 standard errors)',
             ['effect', 'a -> b', 'quantity', 'online', 'MMFM', 'linearisation'], [])
    for d in e['differences']:
        for k in ('fn_hz', 'zeta', 'gain', 'delay_s'):
            cols = [verdict(d[src][k]) for src in ('online', 'mmfm')]
            ln = pct(d['linearisation'][k], 2) if 'linearisation' in d else '-'
            pair = f'{d["a"][0]} kW {d["a"][1]} -> {d["b"][0]} kW {d["b"][1]}'
            diffs[2].append([d['what'], pair, NAMES[k]] + cols + [ln])
    return [cells, diffs]


def verdict(d):
    """The relative difference, twice its standard error, and whether it is resolved."""
    word = 'resolved' if d['resolved'] else 'within spread'
    base = abs(d['diff'] / d['rel']) if d['rel'] else float('nan')
    return f'{pct(d["rel"], 2)} +- {100 * A.RESOLVE_SIGMAS * d["se"] / base:.2f} % ({word})'


def static(e):
    return [('Static input/output curve (plantsim --replay, bias held 30 s per level)',
             ['load kW', f'gain in +-{E.TEST_RANGE_PCT} % (kW/%)', 'linearisation dc gain',
              'difference', 'local slope off by > 2 % at bias (%)', 'up/down hysteresis kW'],
             [[kw, f(s['gain'], 5), f(s['dc_gain'], 5), pct(s['gain_rel'], 3),
               ', '.join(f'{x:+g}' for x in s['nonlinear_at_pct']) or 'none',
               f(s['hysteresis_kw'], 2)] for kw, s in sorted(e.items())])]


def table52(e):
    rows = [[i + 1] + [f(b[k] * SCALE.get(k, 1), 4) for k in RATIO_KEYS]
            for i, b in enumerate(e['blocks'][:10])]
    s, a = e['spread'], e['averaged']
    rows.append(['sd / mean, all blocks'] + [rel(s[k]['rel_sd']) for k in RATIO_KEYS])
    rows.append(['min-max, all blocks'] + [f'{f(s[k]["min"] * SCALE.get(k, 1))}-'
                                           f'{f(s[k]["max"] * SCALE.get(k, 1))}'
                                           for k in RATIO_KEYS])
    rows.append([f'sd / mean over runs of {e["record_blocks"]} blocks'] +
                [rel(a[k]['rel_sd']) for k in RATIO_KEYS])
    q = ('The q\'s relative spread: single blocks against averaged records and the thesis',
         ['q', 'blocks: sd / mean', 'blocks: half-range / mean',
          f'{e["record_blocks"]}-block runs: sd / mean', 'thesis: half-range / mid'],
         [[k, rel(s[k]['rel_sd']), rel(s[k]['rel_half_range']), rel(a[k]['rel_sd']),
           rel(A.thesis_rel_spread()[k])] for k in ('q2', 'q1', 'q0')])
    return [(f'Table 5-2 analogue: non-averaged block estimates (seed {e["seed"]}, '
             f'{len(e["blocks"])} blocks, first 10 shown; {e["failed"]} gave no stable model; '
             'the thesis\'s own table is not legible in the scanned text)',
             ['block'] + [NAMES[k] for k in RATIO_KEYS], rows), q]


def fig59(e):
    rows = []
    for r in e['rows']:
        side = 'delay left in' if r['offset_pct'] > 0 else 'advance' if r['offset_pct'] < 0 \
            else 'reference'
        rel_ = r.get('rel', {})
        rows.append([f'{r["offset_pct"]:+g}', f'{r["offset_s"] * 1e3:+.0f}', side] +
                    [pct(rel_.get(k)) for k in ('gain', 'zeta', 'fn_hz', 'q1_q2', 'q0_q2')])
    return [(f'Fig. 5-9 analogue (seed {e["seed"]}; settling time {e["settling_s"]:.2f} s; '
             'thesis: with delay gain, damping and fn all fall, with advance they rise)',
             ['offset % of settling', 'offset ms', 'kind', 'K', 'zeta', 'fn', 'q1/q2',
              'q0/q2'], rows)]


def gauss_prbs(e):
    rows = []
    for src in ('online', 'mmfm'):
        for k in ('q1_q2', 'q0_q2', 'delay_s', 'gain'):
            rows.append([src, NAMES[k], rel(e['gaussian'][src][k]['rel_sd']),
                         rel(e['prbs'][src][k]['rel_sd']), f(e['variance_ratio'][src][k])])
    rows.append(['-', 'excitation std (% of rated), mean', f(e['gaussian']['std_pct']['mean']),
                 f(e['prbs']['std_pct']['mean']), '-'])
    rows.append(['-', 'cross-correlation, block sd / peak', rel(e['gaussian']['corr_noise']['mean']),
                 rel(e['prbs']['corr_noise']['mean']), f(e['corr_variance_ratio'])])
    return [(f'Gaussian against PRBS ({e["blocks"]} blocks; thesis 3-2: PRBS gave a larger '
             'variance in the cross-correlation)',
             ['estimator', 'quantity', 'Gaussian sd / mean', 'PRBS sd / mean',
              'variance ratio PRBS / Gaussian'], rows)]


def markdown(table):
    title, header, rows = table
    out = [f'**{title}**', '', '| ' + ' | '.join(map(str, header)) + ' |',
           '|' + '---|' * len(header)]
    out += ['| ' + ' | '.join(map(str, r)) + ' |' for r in rows]
    return '\n'.join(out) + '\n'
