"""Refining the resonance peaks of a frequency response branch (searches at fixed frequency).

Called by :func:`workbench.hbm.continuation.frequency_response` once the
branch is computed: the largest ``|y(t)|`` and the largest harmonic-1
amplitude of output 0 are each searched between the computed points around
them (one shared grid of samples, then Brent's method from the best point
known), each trial a corrector solve at fixed frequency, and the best point
of each search is inserted.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import brent, fminbound

from .balance import HarmonicBalance
from .corrector import Corrector
from .options import SolverOptions

TWO_PI = 2.0 * np.pi
N_GRID = 15  # samples between the outer neighbours of the peaks


def refine_peaks(
    hb: HarmonicBalance,
    corr: Corrector,
    opts: SolverOptions,
    rec: Any,
    keys: tuple[str, ...] = ("out_amp", "out_h1"),
) -> list[tuple[float, np.ndarray, int, int] | None]:
    """Search for the largest value of each ``key`` of output 0 around its largest computed one.

    ``keys``: "out_amp" (the largest ``|y(t)|`` over the period) and/or
    "out_h1" (the harmonic-1 amplitude): each has its own peak frequency.
    Where the branch is single-valued around the peaks (frequency increasing
    from two points below the lowest peak point to two above the highest),
    the solution is sampled at ``N_GRID`` frequencies spread over that span
    (one grid for all keys: friction makes the top of the curve kinked, so
    it may have several local maxima, a few per cent apart), then for each
    key Brent's method (parabolic steps, golden section where they do not
    shrink the bracket) refines from the best point known inside its two
    neighbours until the bracket is about ``peak_ftol`` (relative) or
    ``peak_iterations`` trials are spent: the result is never below the best
    point known. Each trial is a corrector solve at fixed frequency from the
    interpolated branch, shared by the keys.

    Returns, per key, the best trial (frequency in Hz, x, Newton iterations,
    its position in frequency order) when it beats the computed points, else
    None; :func:`insert_peaks` records them. ``rec``: the branch's recorder
    (``rows``: name -> list per point).
    """
    f = np.array(rec.rows["freq_hz"])
    vals = {k: np.array([a[0] for a in rec.rows[k]]) for k in keys}
    tops = {k: int(np.argmax(v)) for k, v in vals.items()}
    tops = {k: i for k, i in tops.items() if 0 < i < len(f) - 1}  # not at a band end
    if not tops:
        return [None] * len(keys)
    lo, hi = max(min(tops.values()) - 2, 0), min(max(tops.values()) + 2, len(f) - 1)
    if not np.all(np.diff(f[lo : hi + 1]) > 0):
        return [None] * len(keys)
    xs = rec.rows["x"]

    def guess(fq: float) -> np.ndarray:
        j = int(np.clip(np.searchsorted(f[lo : hi + 1], fq) - 1 + lo, lo, hi - 1))
        th = (fq - f[j]) / (f[j + 1] - f[j])
        return xs[j] + th * (xs[j + 1] - xs[j])

    cache: dict[float, tuple[Any, np.ndarray, int]] = {}  # Hz -> (point data, x, its)

    def solve(fq: float) -> Any:
        if fq not in cache:
            r = corr.solve_natural(guess(fq), TWO_PI * fq)
            if not r.converged:  # once more with a fresh LU
                corr.force_refresh = True
                r = corr.solve_natural(guess(fq), TWO_PI * fq)
            pd = (
                hb.point_data(corr.evaluated(r.x, TWO_PI * fq), n_fine=opts.n_fine)
                if r.converged
                else None
            )
            cache[fq] = (pd, r.x, r.its)
        return cache[fq][0]

    grid = np.linspace(f[lo], f[hi], N_GRID + 2)[1:-1]
    for q in grid:
        solve(float(q))
    out: list[tuple[float, np.ndarray, int, int] | None] = []
    for key in keys:
        if key not in tops:
            out.append(None)
            continue
        out.append(_search(key, solve, cache, f[lo : hi + 1], vals[key][lo : hi + 1], grid, opts))
        if out[-1] is not None:
            fq = out[-1][0]
            out[-1] = (*out[-1][:3], int(np.searchsorted(f[lo : hi + 1], fq)) + lo)
    return out


def _search(key: str, solve, cache: dict, fb: np.ndarray, vb: np.ndarray, grid, opts):
    """Brent's method for one key from the best of the branch points ``fb`` and the grid."""

    def value(fq: float) -> float:
        pd = solve(float(fq))
        return -np.inf if pd is None else float(getattr(pd, key)[0])

    known = np.concatenate([fb, grid])
    kval = np.concatenate([vb, [value(q) for q in grid]])
    order = np.argsort(known)
    known, kval = known[order], kval[order]
    k = int(np.argmax(kval))
    a, b = known[max(k - 1, 0)], known[min(k + 1, known.size - 1)]
    fin = kval[np.isfinite(kval)]
    floor = float(fin.min() - np.ptp(fin))

    def cost(fq: float) -> float:  # a failed trial counts as well below every known value
        v = value(fq)
        return -(v if np.isfinite(v) else floor)

    try:  # from the best known point, inside its neighbours (the top may have several maxima)
        brent(cost, brack=(a, known[k], b), tol=0.5 * opts.peak_ftol, maxiter=opts.peak_iterations)
    except ValueError:  # no bracket (a tie with a neighbour, or the best at an end)
        fminbound(cost, a, b, xtol=opts.peak_ftol * 0.5 * (a + b), maxfun=opts.peak_iterations)
    fq = max(cache, key=value)  # every trial so far, the other keys' searches included
    if not np.isfinite(value(fq)) or value(fq) <= vb.max():
        return None
    _, x, its = cache[fq]
    return fq, x, its, -1


def insert_peaks(rec: Any, record, found: list) -> None:
    """Record the points ``refine_peaks`` found, each at its place in frequency order.

    ``found``: its results (None where a search found nothing better), all
    searched on the same branch, so their positions refer to the branch
    before any insertion: the last position (and at one position the
    highest frequency) goes in first. ``record(x, w, its)`` appends a point.
    """
    done: set[float] = set()
    for fq, x, its, pos in sorted((p for p in found if p), key=lambda p: (-p[3], -p[0])):
        if fq in done:
            continue
        done.add(fq)
        record(x, TWO_PI * fq, its)
        for name in rec.rows:
            rec.rows[name].insert(pos, rec.rows[name].pop())
