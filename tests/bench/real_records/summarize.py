"""Summarises tests/bench/real_records/run.sh's folders: model, verdict, place, fits, top 3."""
import glob
import json
import os
import re
import sys
OUT = sys.argv[1] if len(sys.argv) > 1 else '/tmp/real-records'
def f(x, d=1):
    return '-' if x is None else (f'{x:.{d}f}' if isinstance(x, (int, float)) else str(x))
def effstr(h):
    parts = []
    for e in h.get('effects', []):
        p = ', '.join(f'{k} {v:.4g}' if isinstance(v, (int, float)) else f'{k} {v}' for k, v in e.get('params', {}).items())
        parts.append(f"{e['effect']}@{e.get('place','?')} ({p})")
    return ' + '.join(parts)
for name in sorted(n for n in os.listdir(OUT) if os.path.isdir(os.path.join(OUT, n))):
    w = os.path.join(OUT, name)
    print(f'\n### {name}')
    used = open(f'{w}/id_used.txt').read().strip() if os.path.exists(f'{w}/id_used.txt') else 'hand-written model.json'
    mj = f'{w}/id/model.json' if os.path.exists(f'{w}/id/model.json') else f'{w}/model.json'
    if os.path.exists(mj):
        m = json.load(open(mj))
        print(f"model: {m.get('structure')} fit {f(m.get('fit_percent'))} % (identify options: {used}); num {m['num']} den {m['den']} delay {m.get('delay_s')}")
    else:
        log = open(f'{w}/log.txt').read()
        fat = sorted(set(re.findall(r'fatal: (.*)', log)))
        print('model: none; identify refuses with every option tried:', ' | '.join(x[:140] for x in fat) or log[-300:])
        continue
    rp = f'{w}/dg/report.json'
    if not os.path.exists(rp):
        print('diagnose: no report;', open(f'{w}/log.txt').read()[-400:]); continue
    r = json.load(open(rp))
    hs = r.get('hypotheses', [])
    ch = r.get('chosen')
    print(f"verdict: {r['verdict']}  elapsed_s {f(r.get('elapsed_s'),3)}  samples {r.get('samples')}  chosen={ch}")
    if ch is not None:
        h = hs[ch] if isinstance(ch, int) else ch
        print(f"chosen: {effstr(h)}  val fit {f(h.get('validation_fit_before'))} -> {f(h.get('validation_fit_after'))}  score {f(h.get('score'),2)}")
    else:
        print(f"validation_fit_before {f(r.get('validation_fit_before'))}")
    hs_sorted = hs  # order as in report (ranked)
    for i, h in enumerate(hs_sorted[:3]):
        print(f"  top{i+1}: {h['effect']} places {[e.get('place') for e in h.get('effects',[])]} score {f(h.get('score'),2)} val {f(h.get('validation_fit_before'))}->{f(h.get('validation_fit_after'))} :: {effstr(h)}")
    for key in ('hysteresis', 'saturation', 'coulomb_friction', 'output_saturation', 'backlash', 'nonlinear_stiffness'):
        for i, h in enumerate(hs):
            if any(e['effect'] == key or key in e['effect'] for e in h.get('effects', [])) and i >= 3:
                print(f"  also rank {i+1}: {effstr(h)} score {f(h.get('score'),2)} val {f(h.get('validation_fit_before'))}->{f(h.get('validation_fit_after'))}")
    print(f"  n_hypotheses {len(hs)}; effects tried: {sorted(set(h['effect'] for h in hs))}")
    if r['verdict'] in ('none', 'unexplained'):
        loc = r.get('location', {})
        print('  location.residual_tests:', json.dumps(loc.get('residual_tests'))[:1200])
        a = dict(loc.get('amplitude', {}))
        print('  location.amplitude:', json.dumps(a)[:1500])
