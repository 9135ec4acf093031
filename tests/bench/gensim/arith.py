"""The arithmetic the simulators step with (genset.simulate, droopsim's plant.simulate):
numpy arrays of one column per parameter set (the oracles' grids), or plain floats for a
single set, where numpy's per-call overhead on one-element arrays made a 150 s droopsim
record take 22 s (1 s in floats). The same expressions run on either, so each plant's
physics is written once; both give the same record (arith_test.py beside each)."""
import math

import numpy as np


class Arrays:
    """State (NX, B), parameters per column."""
    minimum, maximum, where, sign = np.minimum, np.maximum, np.where, np.sign
    exp, sin, rint = np.exp, np.sin, np.round

    @staticmethod
    def num(v):
        return np.asarray(v, float)

    @staticmethod
    def consts(c):
        return c

    @staticmethod
    def state(x):
        return x

    @staticmethod
    def vector(values):
        return np.array(values)

    @staticmethod
    def rows(v, n):
        """n copies of v (one per row of a history)."""
        return np.repeat(np.asarray(v, float)[None, :], n, 0)

    @staticmethod
    def mean(rows):
        return rows.mean(axis=0)

    @staticmethod
    def axpy(x, h, k):
        return x + h * k

    @staticmethod
    def rk4(x, h6, k1, k2, k3, k4):
        return x + h6 * (k1 + 2 * k2 + 2 * k3 + k4)

    @staticmethod
    def taps(j, f):
        return j, f


class Floats:
    """State a list of NX floats, parameters floats."""
    minimum, maximum, exp, sin, rint = min, max, math.exp, math.sin, round

    @staticmethod
    def where(c, a, b):
        return a if c else b

    @staticmethod
    def sign(v):
        return float(v > 0) - float(v < 0)

    @staticmethod
    def num(v):
        return float(np.asarray(v, float).flat[0])

    @staticmethod
    def consts(c):
        return {k: float(np.asarray(v).flat[0]) if isinstance(v, (np.ndarray, np.floating)) else v
                for k, v in c.items()}

    @staticmethod
    def state(x):
        return [float(v) for v in x[:, 0]]

    @staticmethod
    def vector(values):
        return list(values)

    @staticmethod
    def rows(v, n):
        return [float(np.asarray(v, float).flat[0])] * n

    @staticmethod
    def mean(rows):
        total = 0.0
        for v in rows:  # left to right, as numpy adds a few rows (sum() compensates from 3.12)
            total += v
        return total / len(rows)

    @staticmethod
    def axpy(x, h, k):
        return [a + h * b for a, b in zip(x, k)]

    @staticmethod
    def rk4(x, h6, k1, k2, k3, k4):
        return [a + h6 * (b1 + 2 * b2 + 2 * b3 + b4)
                for a, b1, b2, b3, b4 in zip(x, k1, k2, k3, k4)]

    @staticmethod
    def taps(j, f):
        return int(np.asarray(j).flat[0]), float(np.asarray(f).flat[0])
