#!/usr/bin/env python3
"""Condition monitoring on the emulated plant: does `rig monitor` find and name the faults?

  monitor_bench.py --rig build/bin/rig [--seeds 5] [--seed 31] [--faults all|a,b]
                   [--shapes abrupt,ramped] [--free-hours 48] [--free-seeds 4]
                   [--memory-hours 24] [--jobs 2] [--out DIR]

Every run is `rig monitor --emulate` (plantsim, lockstep over Modbus TCP) with a baseline
model from one `rig commission --emulate` (seed 1), so the monitor watches the set the way a
station would: with its own commissioning model.

Faults (the table FAULTS below; two sizes each) are injected at --fault-time (after the
baseline's spread has been learnt), abruptly or ramped in over 1800 s. Per run: the first
alarm at or after the injection, its delay (abrupt: from the injection; ramped: from the
ramp's end, negative when found before it), its cause against the truth and its additive /
multiplicative class; alarms before the injection count as false alarms. Printed: a line
per run, a confusion matrix (truth x named cause), the share named right per fault and shape,
and the headline figures of the issue.

Fault-free runs: --free-seeds runs of --free-hours / --free-seeds hours each, with load changes
(setpoint steps and ramps at random times, seeded) and measurement drift; every alarm is a
false alarm; printed as alarms per day of plant time, with the designed rate.

--memory-hours H: one fault-free run of H hours, the rig's resident memory sampled while it
runs; printed at 1 h and at the end (and the peak).
Exit 1 when a run fails to run (a crash or an unexpected exit code).
"""
import argparse, concurrent.futures, json, os, random, shutil, statistics, subprocess, sys
import tempfile, time

RAMP_S = 1800.0
AFTER_S = 600.0  # monitored after the fault (abrupt) or after the ramp's end

# name: (truth cause, class, [size 1 change, size 2 change])
FAULTS = {
    'injector': ('injector/cylinder loss', 'multiplicative',
                 ['engine.injectors_out=1', 'engine.injectors_out=2']),
    'transducer_gain': ('power transducer gain error', 'multiplicative',
                        ['meas.gain=1.05', 'meas.gain=1.1']),
    'transducer_offset': ('power transducer offset', 'additive',
                          ['meas.offset_kw=50', 'meas.offset_kw=120']),
    'damping': ('alternator damping change', 'multiplicative', ['alt.d_pu=8', 'alt.d_pu=6']),
    'backlash': ('actuator wear (backlash)', 'multiplicative',
                 ['gov.backlash_pu=0.002', 'gov.backlash_pu=0.004']),
    'dead_time': ('fuel dead time or combustion lag change', 'multiplicative',
                  ['engine.dead_time_s=0.08', 'engine.dead_time_s=0.1']),
}


def run_monitor(rig, baseline, seed, faults, duration, out, extra=()):
    if os.path.exists(out):
        shutil.rmtree(out)
    cmd = [rig, 'monitor', '--emulate', '--seed', str(seed), '--baseline', baseline,
           '--out', out, '--duration', str(duration), '--quiet'] + list(extra)
    for f in faults:
        cmd += ['--fault', f]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    alarms = []
    for line in p.stdout.splitlines():
        try:
            j = json.loads(line)
        except ValueError:
            continue
        if j.get('type') == 'alarm':
            alarms.append(j)
    return {'code': p.returncode, 'alarms': alarms, 'wall_s': time.time() - t0,
            'stderr': p.stderr.strip().splitlines()[-1:] if p.stderr else []}


def make_baseline(rig, work):
    out = os.path.join(work, 'commission')
    subprocess.run([rig, 'commission', '--emulate', '--seed', '1', '--out', out, '--quiet',
                    '--force'], check=True, capture_output=True)
    return os.path.join(out, 'model.json')


def fault_runs(args, baseline, work):
    names = list(FAULTS) if args.faults == 'all' else args.faults.split(',')
    jobs = []
    for name in names:
        truth, klass, sizes = FAULTS[name]
        for size_i, change in enumerate(sizes):
            for shape in args.shapes.split(','):
                for s in range(args.seeds):
                    seed = args.seed + s
                    spec = f'{change}@t={args.fault_time:g}'
                    end = args.fault_time
                    if shape == 'ramped':
                        spec += f',ramp={RAMP_S:g}'
                        end += RAMP_S
                    jobs.append(dict(name=name, truth=truth, klass=klass, size=size_i + 1,
                                     change=change, shape=shape, seed=seed, spec=spec, end=end,
                                     duration=end + AFTER_S))
    def one(j):
        out = os.path.join(work, f"{j['name']}-{j['size']}-{j['shape']}-{j['seed']}")
        r = run_monitor(args.rig, baseline, j['seed'], [j['spec']], j['duration'], out)
        j.update(r)
        return j
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as ex:
        return list(ex.map(one, jobs))


def judge(j, fault_time):
    before = [a for a in j['alarms'] if a['t_s'] < fault_time]
    after = [a for a in j['alarms'] if a['t_s'] >= fault_time]
    first = after[0] if after else None
    j['false'] = len(before)
    j['detected'] = first is not None
    j['named'] = first['cause'] if first else '(none)'
    j['right'] = bool(first) and first['cause'] == j['truth']
    j['class_right'] = bool(first) and first['class'] == j['klass']
    j['delay'] = (first['t_s'] - (fault_time if j['shape'] == 'abrupt' else j['end'])) \
        if first else None
    return j


def print_fault_table(runs, args):
    print(f"{'fault':18} {'size':>4} {'shape':7} {'seed':>4} {'exit':>4} {'delay s':>8} "
          f"{'named':40} {'ok':>3} {'cls':>3} {'fa':>3} {'wall s':>6}")
    for j in runs:
        d = '-' if j['delay'] is None else f"{j['delay']:.0f}"
        print(f"{j['name']:18} {j['size']:>4} {j['shape']:7} {j['seed']:>4} {j['code']:>4} "
              f"{d:>8} {j['named'][:40]:40} {'y' if j['right'] else 'n':>3} "
              f"{'y' if j['class_right'] else 'n':>3} {j['false']:>3} {j['wall_s']:>6.0f}")
    causes = sorted({j['named'] for j in runs} | {j['truth'] for j in runs})
    print('\nconfusion matrix (rows: truth, columns: first alarm after the fault)')
    short = {c: c.split(' ')[0][:10] + ('/' + c.split(' ')[1][:4] if ' ' in c else '')
             for c in causes}
    print(f"{'':40}" + ''.join(f'{short[c]:>16}' for c in causes))
    for t in sorted({j['truth'] for j in runs}):
        row = [sum(1 for j in runs if j['truth'] == t and j['named'] == c) for c in causes]
        print(f'{t[:40]:40}' + ''.join(f'{n:>16}' for n in row))
    print('\nper fault and shape: named right / runs, class right, median delay (s), detected')
    for name in dict.fromkeys(j['name'] for j in runs):
        for shape in args.shapes.split(','):
            sel = [j for j in runs if j['name'] == name and j['shape'] == shape]
            if not sel:
                continue
            delays = [j['delay'] for j in sel if j['delay'] is not None]
            med = f'{statistics.median(delays):.0f}' if delays else '-'
            print(f"  {name:18} {shape:7} {sum(j['right'] for j in sel):>3}/{len(sel):<3} "
                  f"class {sum(j['class_right'] for j in sel):>3}/{len(sel):<3} delay {med:>6} "
                  f"detected {sum(j['detected'] for j in sel)}/{len(sel)}")
    total = len(runs)
    print(f"\noverall named right: {sum(j['right'] for j in runs)}/{total} "
          f"({100.0 * sum(j['right'] for j in runs) / max(total, 1):.0f} %), class right "
          f"{sum(j['class_right'] for j in runs)}/{total}, false alarms before the faults "
          f"{sum(j['false'] for j in runs)}")
    inj = [j for j in runs if j['name'] == 'injector' and j['size'] == 2]
    for shape, limit in (('abrupt', 300.0), ('ramped', 600.0)):
        sel = [j for j in inj if j['shape'] == shape]
        if sel:
            ok = sum(1 for j in sel if j['right'] and j['delay'] is not None and j['delay'] <= limit)
            print(f"two injectors out, {shape}: named injector/cylinder loss within {limit:.0f} s"
                  f" in {ok}/{len(sel)} seeds")
    sel = [j for j in runs if j['name'] == 'transducer_gain' and j['size'] == 2
           and j['shape'] == 'abrupt']
    if sel:
        ok = sum(1 for j in sel if j['named'].startswith('power transducer'))
        print(f"10 % transducer gain, abrupt: named a sensor fault in {ok}/{len(sel)} seeds")


def free_run_changes(rng, hours):
    """Load changes (setpoint steps and ramps) and drift for one fault-free run."""
    changes = ['meas.drift_kw=8@t=0']
    t = 1200.0
    p = 3500.0
    while t < hours * 3600.0 - 1200.0:
        t += rng.uniform(1800.0, 7200.0)
        p = min(4000.0, max(3000.0, p + rng.choice([-1, 1]) * rng.uniform(50.0, 300.0)))
        ramp = rng.choice([0.0, 0.0, 60.0, 300.0])
        changes.append(f'op.power_kw={p:.0f}@t={t:.0f}' + (f',ramp={ramp:g}' if ramp else ''))
    return changes


def free_runs(args, baseline, work):
    hours = args.free_hours / args.free_seeds
    def one(s):
        seed = args.seed + 100 + s
        changes = free_run_changes(random.Random(seed), hours)
        out = os.path.join(work, f'free-{seed}')
        r = run_monitor(args.rig, baseline, seed, changes, hours * 3600.0, out,
                        ['--max-trips', '1000'])
        r.update(seed=seed, hours=hours, changes=len(changes) - 1)
        return r
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as ex:
        runs = list(ex.map(one, range(args.free_seeds)))
    total_h = sum(r['hours'] for r in runs)
    alarms = sum(len(r['alarms']) for r in runs)
    for r in runs:
        print(f"fault-free seed {r['seed']}: {r['hours']:.1f} h, {r['changes']} load changes, "
              f"exit {r['code']}, {len(r['alarms'])} alarms "
              f"{[a['cause'] for a in r['alarms']]}, wall {r['wall_s']:.0f} s")
    print(f'fault-free: {alarms} false alarms in {total_h:.1f} h of plant time '
          f'({alarms / total_h * 24.0:.3f} per day); designed: 0.5 per month')
    return runs


def memory_run(args, baseline, work):
    """A fault-free run (load changes and drift as the others) with its memory sampled."""
    out = os.path.join(work, 'memory')
    seed = args.seed + 99
    changes = free_run_changes(random.Random(seed), args.memory_hours)
    cmd = [args.rig, 'monitor', '--emulate', '--seed', str(seed), '--baseline', baseline,
           '--out', out, '--duration', str(args.memory_hours * 3600.0), '--quiet',
           '--max-trips', '1000']
    for c in changes:
        cmd += ['--fault', c]
    t0 = time.time()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    samples = []
    while p.poll() is None:
        try:
            with open(f'/proc/{p.pid}/status') as f:
                st = dict(l.split(':', 1) for l in f if ':' in l)
            samples.append((time.time() - t0, int(st['VmRSS'].split()[0]),
                            int(st['VmHWM'].split()[0])))
        except (OSError, KeyError):
            pass
        time.sleep(0.5)
    wall = time.time() - t0
    alarms = [json.loads(l) for l in p.stdout.read().splitlines() if l.startswith('{')]
    rate = args.memory_hours * 3600.0 / wall  # plant seconds per wall second
    def rss_at(plant_s):
        w = plant_s / rate
        best = min(samples, key=lambda s: abs(s[0] - w))
        return best[1] / 1024.0
    print(f'memory: {args.memory_hours:g} h of plant time in {wall:.0f} s wall; resident '
          f'{rss_at(3600.0):.1f} MiB at 1 h, {samples[-1][1] / 1024.0:.1f} MiB at the end, '
          f'peak {max(s[2] for s in samples) / 1024.0:.1f} MiB (exit {p.returncode}); '
          f'{len(changes) - 1} load changes, {len(alarms)} alarms (false) '
          f'{[a["cause"] for a in alarms]}')
    return p.returncode


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rig', default='build/bin/rig')
    ap.add_argument('--baseline', help='baseline model (default: one commissioning run)')
    ap.add_argument('--seeds', type=int, default=5)
    ap.add_argument('--seed', type=int, default=31)
    ap.add_argument('--faults', default='all')
    ap.add_argument('--shapes', default='abrupt,ramped')
    ap.add_argument('--fault-time', type=float, default=900.0)
    ap.add_argument('--free-hours', type=float, default=0.0)
    ap.add_argument('--free-seeds', type=int, default=4)
    ap.add_argument('--memory-hours', type=float, default=0.0)
    ap.add_argument('--jobs', type=int, default=2)
    ap.add_argument('--out')
    args = ap.parse_args()
    work = args.out or tempfile.mkdtemp(prefix='monitor-bench-')
    os.makedirs(work, exist_ok=True)
    baseline = args.baseline or make_baseline(args.rig, work)
    print(f'monitor bench: rig {args.rig}, baseline {baseline}, seeds {args.seed}..'
          f'{args.seed + args.seeds - 1}, fault time {args.fault_time:g} s, work {work}')
    failed = False
    if args.seeds > 0 and args.faults != 'none':
        runs = [judge(j, args.fault_time) for j in fault_runs(args, baseline, work)]
        print_fault_table(runs, args)
        failed |= any(j['code'] not in (0,) for j in runs)
    if args.free_hours > 0:
        failed |= any(r['code'] != 0 for r in free_runs(args, baseline, work))
    if args.memory_hours > 0:
        failed |= memory_run(args, baseline, work) != 0
    if not args.out:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
