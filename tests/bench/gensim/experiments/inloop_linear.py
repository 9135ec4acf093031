# Linear effects inside the loop against the same effect in series, on gensim case folders
# (run_bench.py --out DIR leaves them): a lag or a delay put into the unity loop L = T/(1 - T)
# that the closed-loop model T = G/G0 implies (the delay as a [3/3] Pade), grid-searched.
#   /usr/bin/python3 inloop_linear.py /tmp/gensim-s1/g005 /tmp/gensim-s1/g000 ...
import sys, json, math, numpy as np
sys.path.insert(0, __import__('os').path.dirname(__import__('os').path.abspath(__file__)))
import placement as P
from scipy import optimize

def pade(theta, n=3):
    # e^{-s theta} [n/n] Pade
    from math import factorial
    c = [factorial(2*n-k)*factorial(n)/(factorial(2*n)*factorial(k)*factorial(n-k)) for k in range(n+1)]
    num = np.array([c[k]*(-theta)**k for k in range(n+1)])[::-1]
    den = np.array([c[k]*(theta)**k for k in range(n+1)])[::-1]
    return num, den

def load(case):
    d = case
    import csv
    data = np.loadtxt(f'{d}/recording.csv', delimiter=',', skiprows=1)
    doc = json.load(open(f'{d}/model.json'))
    tf = doc.get('tf', doc)
    return data[:,1], data[:,2], tf

def run(case):
    u, y, tf = load(case)
    u = u - u.mean(); y = y - y.mean()
    num, den = np.array(tf['num'], float), np.array(tf['den'], float)
    delay = float(tf['delay_s'])
    g0 = num[-1]/den[-1]
    est, val = P.blocks(len(u))
    base = P.Lin(num, den, delay)(u)
    vb = P.vfit(y, base, est, val)
    pn, pd = pade(delay, 3)
    N = np.polymul(num, pn)/g0; D = np.polymul(den, pd)
    L = len(D); N = np.concatenate([np.zeros(L-len(N)), N])
    def lag(tau):
        Dn = np.polyadd(D, np.polymul([tau, 0.0], np.polysub(D, N)))
        return g0*P.Lin(N, Dn, 0.0)(u)
    def ser_lag(tau):
        return P.Lin(num, np.polymul(den, [tau, 1.0]), delay)(u)
    def ser_delay(th):
        return P.Lin(num, den, delay+th)(u)
    out = {}
    for name, f, grid in [('loop_lag', lag, np.geomspace(0.005, 0.5, 25)), ('series_lag', ser_lag, np.geomspace(0.005, 0.5, 25)), ('series_delay', ser_delay, np.linspace(0, 0.08, 17))]:
        best = None
        for g in grid:
            yh = f(g); r = y - yh; r -= r[est].mean()
            c = np.sum(r[est]**2)
            if best is None or c < best[0]: best = (c, g, P.vfit(y, yh, est, val))
        out[name] = (round(best[1], 4), round(best[2]-vb, 2))
    print(case.rstrip('/').split('/')[-1], 'base', round(vb, 1), out)

for c in sys.argv[1:]:
    run(c)
