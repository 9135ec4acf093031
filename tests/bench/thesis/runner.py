"""Runs plantsim and rig for the thesis reproduction: a plantsim per run on an ephemeral port
(lockstep clock, a plant TOML for the operating point), `rig commission --link` against it,
`rig identify` on a recording, `plantsim --replay` and `--linearise`. One process pair at a
time, under `nice`, so the reproduction leaves the machine usable."""
import csv, json, os, re, shutil, subprocess, sys, tempfile, time

NICE = ['nice', '-n', '10']
PLANT_TICK_S = 0.001         # plantsim's default tick; lockstep_ticks = sample period / tick
READY_TIMEOUT_S = 10.0       # plantsim prints its endpoint within milliseconds
READY = re.compile(r'plantsim: modbus (tcp://[0-9.]+:[0-9]+) ready')


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def plant_toml(plantsim, out_dir, power_kw, preset='stornoway'):
    """The preset written out with the operating point replaced (plantsim --list-params)."""
    path = os.path.join(out_dir, f'plant_{int(power_kw)}kw.toml')
    if os.path.exists(path):
        return path
    text = subprocess.run([plantsim, '--preset', preset, '--list-params'], check=True,
                          capture_output=True, text=True).stdout
    text, n = re.subn(r'(?m)^power_kw = [0-9.e+]+', f'power_kw = {power_kw:g}', text)
    if n != 1:
        raise RuntimeError('plantsim --list-params: no single power_kw line to replace')
    with open(path, 'w') as fh:
        fh.write(text)
    return path


def plant_toml_with(plantsim, out_dir, power_kw, name, replace):
    """A plant TOML with further keys replaced: replace = {key: value} (keys unique in it)."""
    base = plant_toml(plantsim, out_dir, power_kw)
    with open(base) as fh:
        text = fh.read()
    for key, value in replace.items():
        text, n = re.subn(rf'(?m)^{re.escape(key)} = [0-9.e+-]+', f'{key} = {value:g}', text)
        if n != 1:
            raise RuntimeError(f'plant TOML: no single {key} line to replace')
    path = os.path.join(out_dir, name)
    with open(path, 'w') as fh:
        fh.write(text)
    return path


def linearise(plantsim, toml, out_json):
    subprocess.run([plantsim, '--config', toml, '--linearise', out_json], check=True,
                   capture_output=True)
    with open(out_json) as fh:
        return json.load(fh)


def toml_text(sections):
    """A test TOML from {section: {key: value}}."""
    lines = []
    for name, keys in sections.items():
        lines.append(f'[{name}]')
        for k, v in keys.items():
            if isinstance(v, bool):
                v = 'true' if v else 'false'
            elif isinstance(v, str):
                v = f'"{v}"'
            lines.append(f'{k} = {v}')
    return '\n'.join(lines) + '\n'


def commission(rig, plantsim, plant_cfg, seed, sections, out_dir):
    """One commissioning test against a fresh plantsim (noise seed = seed). Returns the parsed
    report.json (None when the rig wrote none) and the exit code."""
    os.makedirs(out_dir, exist_ok=True)
    test = os.path.join(out_dir, 'test.toml')
    with open(test, 'w') as fh:
        fh.write(toml_text(sections))
    with open(os.path.join(out_dir, 'plantsim.log'), 'w') as plog:
        plant = subprocess.Popen(NICE + [plantsim, '--config', plant_cfg, '--clock', 'lockstep',
                                         '--modbus', 'tcp://127.0.0.1:0', '--seed', str(seed)],
                                 stdout=subprocess.PIPE, stderr=plog, text=True)
        try:
            endpoint = wait_ready(plant)
            res = subprocess.run(NICE + [rig, 'commission', '--link',
                                         f'modbus+{endpoint}?unit=1', '--test', test,
                                         '--out', os.path.join(out_dir, 'rig'), '--force',
                                         '--quiet'],
                                 capture_output=True, text=True)
        finally:
            plant.terminate()
            try:
                plant.wait(timeout=5)
            except subprocess.TimeoutExpired:
                plant.kill()
                plant.wait()
    report = os.path.join(out_dir, 'rig', 'report.json')
    if not os.path.exists(report):
        log(f'  rig exit {res.returncode}: {res.stdout.strip()} {res.stderr.strip()}')
        return None, res.returncode
    with open(report) as fh:
        return json.load(fh), res.returncode


def wait_ready(plant):
    deadline = time.monotonic() + READY_TIMEOUT_S
    while time.monotonic() < deadline:
        line = plant.stdout.readline()
        if not line:
            break
        m = READY.search(line)
        if m:
            return m.group(1)
    raise RuntimeError('plantsim did not report its Modbus endpoint')


def identify(rig, recording, order='2/0', delay='auto', lags=None, skip=None, rows='all'):
    """rig identify (MMFM) on a CSV; the parsed report.json (its files are not kept), or
    None when it gave no model (a failed check, or no stable model)."""
    with tempfile.TemporaryDirectory(prefix='thesis-id-') as out_dir:
        # The thesis's method always has a dead time: estimated, never left out.
        cmd = NICE + [rig, 'identify', '--recording', recording, '--order', order, '--delay',
                      'estimated' if delay == 'auto' else str(delay), '--method', 'mmfm', '--rows', rows, '--out', out_dir,
                      '--force', '--json']
        if lags:
            cmd += ['--lags', str(lags)]
        if skip:
            cmd += ['--skip', str(skip)]
        res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0 or not res.stdout.strip():
        return None
    return json.loads(res.stdout)


def read_recording(path):
    """Columns t, u, y and phase of a rig recording."""
    t, u, y, phase = [], [], [], []
    with open(path) as fh:
        for row in csv.DictReader(fh):
            t.append(float(row['t']))
            u.append(float(row['u']))
            y.append(float(row['y']))
            phase.append(int(row['phase']))
    return t, u, y, phase


def write_recording(path, t, u, y, sidecar=None):
    """A t,u,y CSV; with the rig's sidecar (sample rate, AC coupling) beside it when given."""
    with open(path, 'w') as fh:
        fh.write('t,u,y\n')
        for a, b, c in zip(t, u, y):
            fh.write(f'{a:.6f},{b:.9g},{c:.9g}\n')
    if sidecar:
        doc = dict(sidecar)
        for key in ('rows', 'complete', 'phase_codes'):
            doc.pop(key, None)
        with open(os.path.splitext(path)[0] + '.json', 'w') as fh:
            json.dump(doc, fh)


def replay(plantsim, plant_cfg, t, bias):
    """plantsim --replay: the bias through the plant without noise; returns the power."""
    with tempfile.TemporaryDirectory(prefix='thesis-replay-') as tmp:
        src, dst = os.path.join(tmp, 'in.csv'), os.path.join(tmp, 'out.csv')
        with open(src, 'w') as fh:
            fh.write('t,u\n')
            for a, b in zip(t, bias):
                fh.write(f'{a:.6f},{b:.9g}\n')
        subprocess.run(NICE + [plantsim, '--config', plant_cfg, '--replay', src,
                               '--replay-out', dst], check=True, capture_output=True)
        with open(dst) as fh:
            return [float(r['power_kw']) for r in csv.DictReader(fh)]


def which(path):
    found = shutil.which(path) if os.sep not in path else path
    if not found or not os.path.exists(found):
        raise SystemExit(f'thesis: {path}: not found (build it, or pass --rig/--plantsim)')
    return os.path.abspath(found)

