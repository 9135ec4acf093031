"""thesis.html: the tables and inline SVG plots, self-contained (no scripts, works offline)."""
import html, math

W, H, PAD_L, PAD_R, PAD_T, PAD_B = 600, 300, 64, 180, 16, 40
COLOURS = ('#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#17becf')
STYLE = """body{font-family:sans-serif;max-width:1100px;margin:1em auto;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:13px}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eee}
h2{margin-top:2em;border-bottom:1px solid #ccc}svg{background:#fff;border:1px solid #ddd}
.note{color:#555;font-size:13px;max-width:900px}"""


def ticks(lo, hi, log):
    if log:
        return [10 ** k for k in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)]
    step = 10 ** math.floor(math.log10((hi - lo) / 4 or 1))
    for m in (1, 2, 5, 10):
        if (hi - lo) / (step * m) <= 6:
            step *= m
            break
    start = math.ceil(lo / step) * step
    return [start + i * step for i in range(int((hi - start) / step) + 1)]


def plot(title, series, xlabel, ylabel, logx=False, logy=False):
    """series: (label, xs, ys, 'line' | 'points')."""
    pts = [(x, y) for _, xs, ys, _ in series for x, y in zip(xs, ys)
           if x == x and y == y and (not logx or x > 0) and (not logy or y > 0)]
    if not pts:
        return ''
    tx = (lambda v: math.log10(v)) if logx else (lambda v: v)
    ty = (lambda v: math.log10(v)) if logy else (lambda v: v)
    x0, x1 = min(tx(p[0]) for p in pts), max(tx(p[0]) for p in pts)
    y0, y1 = min(ty(p[1]) for p in pts), max(ty(p[1]) for p in pts)
    x0, x1 = (x0 - 0.5, x1 + 0.5) if x0 == x1 else (x0 - 0.03 * (x1 - x0), x1 + 0.03 * (x1 - x0))
    y0, y1 = (y0 - 0.5, y1 + 0.5) if y0 == y1 else (y0 - 0.06 * (y1 - y0), y1 + 0.06 * (y1 - y0))
    pw, ph = W - PAD_L - PAD_R, H - PAD_T - PAD_B

    def sx(v):
        return PAD_L + (tx(v) - x0) / (x1 - x0) * pw

    def sy(v):
        return PAD_T + ph - (ty(v) - y0) / (y1 - y0) * ph
    out = [f'<svg width="{W}" height="{H}" xmlns="http://www.w3.org/2000/svg" '
           f'font-size="11"><title>{html.escape(title)}</title>',
           f'<rect x="{PAD_L}" y="{PAD_T}" width="{pw}" height="{ph}" fill="none" '
           'stroke="#888"/>']
    out += axis_ticks(x0, x1, y0, y1, logx, logy, sx, sy)
    out.append(f'<text x="{PAD_L + pw / 2}" y="{H - 6}" text-anchor="middle">'
               f'{html.escape(xlabel)}</text>')
    out.append(f'<text transform="translate(12,{PAD_T + ph / 2}) rotate(-90)" '
               f'text-anchor="middle">{html.escape(ylabel)}</text>')
    for i, (label, xs, ys, kind) in enumerate(series):
        c = COLOURS[i % len(COLOURS)]
        xy = [(sx(x), sy(y)) for x, y in zip(xs, ys)
              if x == x and y == y and (not logx or x > 0) and (not logy or y > 0)]
        if kind == 'line':
            out.append(f'<polyline fill="none" stroke="{c}" stroke-width="1.5" points="' +
                       ' '.join(f'{a:.1f},{b:.1f}' for a, b in xy) + '"/>')
        else:
            r = 5 if kind == 'marker' else 2.5
            out += [f'<circle cx="{a:.1f}" cy="{b:.1f}" r="{r}" fill="{c}" fill-opacity=".7"/>'
                    for a, b in xy]
        ly = PAD_T + 12 + 14 * i
        out.append(f'<rect x="{W - PAD_R + 8}" y="{ly - 8}" width="10" height="8" fill="{c}"/>'
                   f'<text x="{W - PAD_R + 22}" y="{ly}">{html.escape(label)}</text>')
    out.append('</svg>')
    return ''.join(out)


def axis_ticks(x0, x1, y0, y1, logx, logy, sx, sy):
    out = []
    lo, hi = (10 ** x0, 10 ** x1) if logx else (x0, x1)
    for v in ticks(lo, hi, logx):
        if lo <= v <= hi:
            out.append(f'<text x="{sx(v):.1f}" y="{H - PAD_B + 14}" text-anchor="middle">'
                       f'{v:g}</text>')
    lo, hi = (10 ** y0, 10 ** y1) if logy else (y0, y1)
    for v in ticks(lo, hi, logy):
        if lo <= v <= hi:
            out.append(f'<text x="{PAD_L - 4}" y="{sy(v) + 4:.1f}" text-anchor="end">'
                       f'{v:.4g}</text><line x1="{PAD_L}" x2="{W - PAD_R}" y1="{sy(v):.1f}" '
                       f'y2="{sy(v):.1f}" stroke="#eee"/>')
    return out


def table_html(table):
    title, header, rows = table
    h = ''.join(f'<th>{html.escape(str(c))}</th>' for c in header)
    body = ''.join('<tr>' + ''.join(f'<td>{html.escape(str(c))}</td>' for c in r) + '</tr>'
                   for r in rows)
    return f'<p><b>{html.escape(title)}</b></p><table><tr>{h}</tr>{body}</table>'


def section(title, note, tables, plots):
    return (f'<h2>{html.escape(title)}</h2><p class="note">{html.escape(note)}</p>' +
            ''.join(table_html(t) for t in tables) + ''.join(plots))


def render(doc, sections, command):
    parts = [f'<!doctype html><html><head><meta charset="utf-8"><title>Thesis reproduction'
             f'</title><style>{STYLE}</style></head><body><h1>Thesis reproduction on '
             f'plantsim</h1><p class="note">Command: <code>{html.escape(command)}</code>; '
             f'wall time {doc["wall_s"]:.0f} s. Every figure is in thesis.json; '
             'docs/thesis.md explains each experiment.</p>']
    parts += [section(*s) for s in sections]
    parts.append('</body></html>')
    return '\n'.join(parts)


def stornoway_plots(e):
    pts = []
    for src in ('online', 'mmfm'):
        key = 'online_at' if src == 'online' else 'mmfm'
        ms = [r[key].get(e['blocks']) for r in e['runs']]
        ms = [m for m in ms if m]
        pts.append((src, [m['q1_q2'] for m in ms], [m['q0_q2'] for m in ms], 'points'))
    pts.append(('thesis average', [e['thesis']['q1_q2']], [e['thesis']['q0_q2']], 'marker'))
    lengths = sorted(e['vs_length']['mmfm'])
    vs = [(f'{src} {k}', lengths, [e['vs_length'][src][n][k]['rel_sd'] for n in lengths],
           'line') for src in ('online', 'mmfm') for k in ('q1_q2', 'q0_q2')]
    return [plot('runs', pts, 'q1/q2 (1/s)', 'q0/q2 (1/s^2)'),
            plot('spread against length', vs, 'blocks', 'sd / mean', logx=True, logy=True)]


def loads_plots(e):
    s = [(f'{c["load_kw"]} kW {c["amplitude"]}',
          [m['zeta'] for m in c['online_models']], [m['fn_hz'] for m in c['online_models']],
          'points') for c in e['cells']]
    s += [(f'linearisation {kw} kW', [v['zeta']], [v['fn_hz']], 'marker')
          for kw, v in sorted(e['linearisation'].items())]
    return [plot('cells', s, 'zeta (online)', 'fn Hz (online)')]


def static_plots(e):
    s = []
    for kw, v in sorted(e.items()):
        s.append((f'{kw} kW', v['levels_pct'], v['power_kw'], 'points'))
        xs = [min(v['levels_pct']), max(v['levels_pct'])]
        s.append((f'{kw} kW linearisation', xs, [kw + v['dc_gain'] * x for x in xs], 'line'))
    return [plot('static', s, 'bias (% of rated)', 'power (kW)')]


def table52_plots(e):
    b = e['blocks']
    ks = list(range(1, len(b) + 1))
    return [plot('blocks', [('fn (Hz)', ks, [m['fn_hz'] for m in b], 'points'),
                            ('zeta x 10', ks, [10 * m['zeta'] for m in b], 'points')],
                 'block', 'estimate')]


def fig59_plots(e):
    rows = [r for r in e['rows'] if r.get('rel')]
    xs = [r['offset_pct'] for r in rows]
    return [plot('fig59', [(k, xs, [100 * r['rel'][k] for r in rows], 'line')
                           for k in ('gain', 'zeta', 'fn_hz')],
                 'delay left in (+) / advance (-), % of settling time', 'change (%)')]


def prbs_plots(e):
    s = [(kind, list(range(len(e[kind]['corr_mean']))), e[kind]['corr_mean'], 'line')
         for kind in ('gaussian', 'prbs') if e[kind]['corr_mean']]
    return [plot('corr', s, 'lag (samples of 32 ms)', 'r_yu / var(u), first run')]
