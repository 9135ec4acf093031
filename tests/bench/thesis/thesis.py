#!/usr/bin/env python3
"""The Stornoway results of the thesis (MMFM.md; its chapter 5 and 3-2) reproduced on plantsim.

  thesis.py [--rig build/bin/rig] [--plantsim PATH] [--runs 20] [--quick] [--out out/thesis]
            [--seed 1]

Six experiments (docs/thesis.md), one rig or plantsim process at a time under nice:
  1. the Stornoway parameters in unit-free form (q1/q2 = 2 zeta wn, q0/q2 = wn^2, the delay)
     and their relative spread over --runs runs, beside the thesis's;
  2. two loads (2 and 3.5 MW) x two excitation amplitudes, differences against 2 standard
     errors;
  3. the static input/output curve (slow bias steps, plantsim --replay) against the
     linearisation's gain;
  4. Table 5-2: estimates from single, non-averaged blocks;
  5. Fig. 5-9: a dead time left in, or over-corrected into an advance;
  6. Gaussian against PRBS excitation (thesis 3-2).
Thesis settings: 64 lags over about 2 s (31.25 Hz), blocks of 2048 samples, skip 8, Gaussian
noise of 5 Hz bandwidth, 0.1 Hz matched AC coupling, the +-3 % band; the record of
experiment 1 is 2 W - 1 = 99 blocks, the memory of the thesis's exponential average with
weight W = 50. Prints every seed, progress to stderr, the tables as markdown on stdout;
writes OUT/thesis.html and OUT/thesis.json.
"""
import argparse, dataclasses, json, math, os, sys, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiments as E  # noqa: E402
import page as P  # noqa: E402
import runner as R  # noqa: E402
import tables as T  # noqa: E402

FULL = {'runs': 20, 'blocks': 99, 'cell_blocks': 40, 'cell_runs': 5, 'prbs_runs': 10}
QUICK = {'runs': 4, 'blocks': 10, 'cell_blocks': 10, 'cell_runs': 2, 'prbs_runs': 2}


@dataclasses.dataclass(frozen=True)
class Context:
    rig: str
    plantsim: str
    out: str
    seed: int
    runs: int
    blocks: int          # experiment 1's record, blocks of 2048 samples
    cell_blocks: int     # experiments 2 and 6
    cell_runs: int
    prbs_runs: int

    def with_blocks(self, n):
        return dataclasses.replace(self, blocks=n)


def parse():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--rig', default='build/bin/rig')
    p.add_argument('--plantsim', help='default: beside --rig')
    p.add_argument('--runs', type=int, help='experiment 1 runs (default 20, quick 4)')
    p.add_argument('--quick', action='store_true',
                   help='smoke test: 4 runs of 10 blocks, 2 per cell (under a minute)')
    p.add_argument('--out', default='out/thesis')
    p.add_argument('--seed', type=int, default=1, help='first seed (plant noise and excitation)')
    a = p.parse_args()
    size = dict(QUICK if a.quick else FULL)
    if a.runs:
        size['runs'] = a.runs
    if size['runs'] < 2:
        p.error('--runs: at least 2 (a spread needs two)')
    rig = R.which(a.rig)
    plantsim = R.which(a.plantsim or os.path.join(os.path.dirname(rig), 'plantsim'))
    os.makedirs(a.out, exist_ok=True)
    return Context(rig, plantsim, os.path.abspath(a.out), a.seed, **size)


def clean(x):
    """JSON without NaN: NaN and infinities become null."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {str(k): clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    return x


def main():
    ctx = parse()
    t0 = time.monotonic()
    command = ' '.join(sys.argv)
    R.log(f'thesis: rig {ctx.rig}, plantsim {ctx.plantsim}, out {ctx.out}')
    lin = E.linearisations(ctx)
    e1 = E.stornoway(ctx, lin)
    e2 = E.loads_amplitudes(ctx, e1, lin)
    e6 = E.gauss_prbs(ctx, e1)
    e3 = E.static_curve(ctx, lin)
    e4 = E.table52(e1)
    e5 = E.fig59(ctx, lin)
    doc = {'command': command, 'settings': dataclasses.asdict(ctx), 'linearisation': lin,
           'stornoway': e1, 'loads_amplitudes': e2, 'static': e3, 'table52': e4, 'fig59': e5,
           'gauss_prbs': e6, 'wall_s': time.monotonic() - t0}
    sections = [
        ('1. Stornoway parameters', seeds_line(e1['seeds']) + f'; {e1["blocks"]} blocks '
         f'({e1["record_s"]:.0f} s) per run at 3.5 MW; excitation std '
         f'{e1["std_pct"]["mean"]:.3f} % of rated, SNR {e1["snr_db"]["mean"]:.1f} dB '
         f'(response std over noise std), largest deviation {e1["max_dev_pct"]:.2f} % of P0.',
         T.stornoway(e1), P.stornoway_plots(e1)),
        ('2. Loads x amplitudes', 'seeds ' + '; '.join(
            f'{c["load_kw"]} kW {c["amplitude"]}: {c["seeds"]}' for c in e2['cells'])
         + f'; {e2["blocks"]} blocks per run.', T.loads(e2), P.loads_plots(e2)),
        ('3. Static input/output curve', 'noise-free replay; no seed.', T.static(e3),
         P.static_plots(e3)),
        ('4. Table 5-2', f'seed {e4["seed"]}.', T.table52(e4), P.table52_plots(e4)),
        ('5. Fig. 5-9', f'seed {e5["seed"]} (excitation); noise-free replay of {e5["blocks"]} '
         f'blocks; reference dead time {e5["reference_delay_s"] * 1e3:.1f} ms (MMFM\'s own estimate on '
         'this record).', T.fig59(e5), P.fig59_plots(e5)),
        ('6. Gaussian against PRBS', f'PRBS {seeds_line(e6["seeds_prbs"])}; Gaussian: '
         'experiment 1 at the same record length.', T.gauss_prbs(e6), P.prbs_plots(e6)),
    ]
    for title, note, tabs, _ in sections:
        print(f'### {title}\n\n{note}\n')
        for t in tabs:
            print(T.markdown(t))
    with open(os.path.join(ctx.out, 'thesis.json'), 'w') as fh:
        json.dump(clean(doc), fh, indent=1)
    with open(os.path.join(ctx.out, 'thesis.html'), 'w') as fh:
        fh.write(P.render(doc, sections, command))
    R.log(f'thesis: {doc["wall_s"]:.0f} s; {ctx.out}/thesis.html, thesis.json')


def seeds_line(seeds):
    return 'seeds ' + ', '.join(map(str, seeds))


if __name__ == '__main__':
    main()
