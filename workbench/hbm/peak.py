"""Refining the resonance peak of a frequency response branch (a search at fixed frequency).

Called by :func:`workbench.hbm.continuation.frequency_response` once the
branch is computed: the largest output amplitude is searched between the
computed points around it (seven samples, then golden section), each trial
a corrector solve at fixed frequency, and the best point is inserted.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .balance import HarmonicBalance
from .corrector import Corrector
from .options import SolverOptions

TWO_PI = 2.0 * np.pi


def refine_peak(
    hb: HarmonicBalance,
    corr: Corrector,
    opts: SolverOptions,
    rec: Any,
    record,
    key: str = "out_amp",
) -> None:
    """Search for the largest ``key`` of output 0 around the largest computed one.

    ``key``: "out_amp" (the largest ``|y(t)|`` over the period) or "out_h1"
    (the harmonic-1 amplitude): each has its own peak frequency. Where the
    branch is single-valued around the peak (frequency increasing through
    the two neighbours on each side), the value is sampled at seven
    frequencies between the outer neighbours (friction makes the top of the
    curve kinked, so it may have local maxima), then a golden-section search
    refines around the best sample until the bracket is narrower than
    ``peak_ftol`` (relative) or ``peak_iterations`` are spent. Each trial is a
    corrector solve at fixed frequency from the interpolated branch. The
    best trial is recorded and inserted in frequency order. ``rec``: the branch's recorder
    (``rows``: name -> list per point); ``record(x, w, its)`` appends a point to it.
    """
    amp = np.array([a[0] for a in rec.rows[key]])
    f = np.array(rec.rows["freq_hz"])
    i = int(np.argmax(amp))
    lo, hi = max(i - 2, 0), min(i + 2, len(f) - 1)
    if i == 0 or i == len(f) - 1 or not np.all(np.diff(f[lo : hi + 1]) > 0):
        return
    xs = rec.rows["x"]

    def guess(fq: float) -> np.ndarray:
        j = int(np.clip(np.searchsorted(f[lo : hi + 1], fq) - 1 + lo, lo, hi - 1))
        th = (fq - f[j]) / (f[j + 1] - f[j])
        return xs[j] + th * (xs[j + 1] - xs[j])

    cache: dict[float, tuple[float, np.ndarray, int]] = {}

    def value(fq: float) -> float:
        if fq not in cache:
            r = corr.solve_natural(guess(fq), TWO_PI * fq)
            if not r.converged:  # once more with a fresh LU
                corr.force_refresh = True
                r = corr.solve_natural(guess(fq), TWO_PI * fq)
            if not r.converged:
                cache[fq] = (-np.inf, r.x, r.its)
            else:
                pd = hb.point_data(r.x, TWO_PI * fq, n_fine=opts.n_fine)
                cache[fq] = (float(getattr(pd, key)[0]), r.x, r.its)
        return cache[fq][0]

    grid = np.linspace(f[lo], f[hi], 9)[1:-1]
    vals = [value(q) for q in grid]
    known = np.concatenate([f[lo : hi + 1], grid])
    kval = np.concatenate([amp[lo : hi + 1], vals])
    order = np.argsort(known)
    known, kval = known[order], kval[order]
    k = int(np.argmax(kval))
    a, b = known[max(k - 1, 0)], known[min(k + 1, known.size - 1)]
    g = (np.sqrt(5) - 1) / 2
    c, d = b - g * (b - a), a + g * (b - a)
    for _ in range(opts.peak_iterations):
        if b - a <= opts.peak_ftol * 0.5 * (a + b):
            break
        if value(c) > value(d):
            b, d = d, c
            c = b - g * (b - a)
        else:
            a, c = c, d
            d = a + g * (b - a)
    fq = max(cache, key=lambda q: cache[q][0])
    best, xb, its = cache[fq]
    if not np.isfinite(best) or best <= amp[i]:
        return
    record(xb, TWO_PI * fq, its)
    pos = int(np.searchsorted(f[lo : hi + 1], fq)) + lo  # keep frequency order there
    for name in rec.rows:
        rec.rows[name].insert(pos, rec.rows[name].pop())
