"""Refining the resonance peaks of a frequency response branch (searches at fixed frequency).

Called by :func:`workbench.hbm.forced.response.frequency_response` once the
branch is computed: the largest ``|y(t)|`` and the largest harmonic-1
amplitude of output 0 are each searched between the computed points around
them (one shared grid of samples, then Brent's method from the best point
known), each trial a corrector solve at fixed frequency, and the best point
of each search is inserted.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.balance import HarmonicBalance
from ..core.options import SolverOptions
from ..path.rows import Rows
from .corrector import Corrector

TWO_PI = 2.0 * np.pi
N_GRID = 15  # samples between the outer neighbours of the peaks


def refine_peaks(
    hb: HarmonicBalance,
    corr: Corrector,
    opts: SolverOptions,
    rows: Rows,
    keys: tuple[str, ...] = ("out_amp", "out_h1"),
) -> list[tuple[float, np.ndarray, int, int] | None]:
    """Search for the largest value of each ``key`` of output 0 around its largest computed one.

    ``keys``: "out_amp" (the largest ``|y(t)|`` over the period) and/or
    "out_h1" (the harmonic-1 amplitude): each has its own peak frequency.
    Each key's span runs from two branch points below its largest one to
    two above (overlapping spans are merged, so close peaks share one
    grid). Where the branch is single-valued over the span (frequency
    increasing), the solution is sampled at ``N_GRID`` frequencies spread
    over it (friction makes the top of the curve kinked, so it may have
    several local maxima, a few per cent apart), then Brent's method
    (parabolic steps, golden section where they do not shrink the bracket)
    refines from the best point known inside its two neighbours until the
    bracket is about ``peak_ftol`` (relative) or about ``peak_iterations``
    iterations are spent: the result is a trial that beats every branch
    point, or nothing (branch points keep their recorded values, they are
    not solved again). Each trial is a corrector solve at fixed frequency
    from the interpolated branch, shared by the keys.

    A trial that does not converge, or converges onto a state where the
    damper has lost contact (singular: the continuation stops at such a
    point), counts as failed and is never chosen; the frequencies of the
    latter are listed in ``corr.stats["peak_trials_lost_contact"]`` (set only
    when there are any).

    Returns, per key, the best trial (frequency in Hz, x, Newton iterations,
    its position in frequency order) when it beats the computed points, else
    None; :func:`insert_peaks` records them. ``rows``: the branch's points.
    """
    f = np.array(rows.cols["freq_hz"])
    vals = {k: np.array([a[0] for a in rows.cols[k]]) for k in keys}
    tops = {k: int(np.argmax(v)) for k, v in vals.items()}
    tops = {k: i for k, i in tops.items() if 0 < i < len(f) - 1}  # not at a band end
    spans = {k: (max(i - 2, 0), min(i + 2, len(f) - 1)) for k, i in tops.items()}
    if len(spans) == 2:  # overlapping spans share one grid; distant peaks get one each
        (l1, h1), (l2, h2) = spans.values()
        if max(l1, l2) <= min(h1, h2):
            spans = dict.fromkeys(spans, (min(l1, l2), max(h1, h2)))
    xs = rows.cols["x"]
    lost: list[float] = []  # Hz of trials without contact, for the branch message
    cache: dict[float, tuple[Any, np.ndarray, int]] = {}  # Hz -> (point data, x, its)
    found: dict[str, tuple[float, np.ndarray, int, int] | None] = {}
    for key, (lo, hi) in spans.items():
        fb = f[lo : hi + 1]
        if not np.all(np.diff(fb) > 0):  # a fold near the top: no single-valued bracket
            found[key] = None
            continue
        branch = dict(zip(fb.tolist(), vals[key][lo : hi + 1].tolist(), strict=True))

        def guess(fq: float, lo=lo, hi=hi, fb=fb) -> np.ndarray:
            j = int(np.clip(np.searchsorted(fb, fq) - 1 + lo, lo, hi - 1))
            th = (fq - f[j]) / (f[j + 1] - f[j])
            return xs[j] + th * (xs[j + 1] - xs[j])

        def solve(fq: float, guess=guess) -> Any:
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
                if pd is not None and pd.lost_contact:  # a singular state: never a peak
                    lost.append(fq)
                    pd = None
                cache[fq] = (pd, r.x, r.its)
            return cache[fq][0]

        grid = np.linspace(fb[0], fb[-1], N_GRID + 2)[1:-1]
        hit = _search(key, solve, cache, branch, grid, opts)
        found[key] = hit and (*hit, int(np.searchsorted(fb, hit[0])) + lo)
    if lost:
        corr.stats["peak_trials_lost_contact"] = lost
    return [found.get(k) for k in keys]


def _search(key: str, solve, cache: dict, branch: dict, grid, opts):
    """Brent's method for one key from the best of the branch points and the grid.

    ``branch``: frequency -> recorded value of the branch points (never solved
    again). Returns (frequency, x, its) of the best trial when it beats them.
    """

    def value(fq: float) -> float:
        fq = float(fq)
        if fq in branch:
            return branch[fq]
        pd = solve(fq)
        return -np.inf if pd is None else float(getattr(pd, key)[0])

    from scipy.optimize import brent, fminbound

    known = np.array(sorted({*branch, *map(float, grid)}))
    kval = np.array([value(q) for q in known])
    k = int(np.argmax(kval))
    fin = kval[np.isfinite(kval)]
    floor = float(fin.min() - np.ptp(fin))

    def cost(fq: float) -> float:  # a failed trial counts as well below every known value
        v = value(fq)
        return -(v if np.isfinite(v) else floor)

    if 0 < k < known.size - 1 and kval[k] > max(kval[k - 1], kval[k + 1]):
        # from the best known point, inside its neighbours (the top may have several maxima)
        a, c = known[k - 1], known[k + 1]
        brent(cost, brack=(a, known[k], c), tol=0.5 * opts.peak_ftol, maxiter=opts.peak_iterations)
    else:  # no bracket (a tie with a neighbour, or the best at an end of the span)
        a, c = known[max(k - 1, 0)], known[min(k + 1, known.size - 1)]
        fminbound(cost, a, c, xtol=opts.peak_ftol * 0.5 * (a + c), maxfun=opts.peak_iterations)
    # the other key's trials count too, where they lie inside this span (the position
    # returned for insertion is within it)
    lo, hi = min(branch), max(branch)
    trials = [q for q in cache if lo < q < hi and q not in branch]
    if not trials:
        return None
    fq = max(trials, key=value)
    if not np.isfinite(value(fq)) or value(fq) <= max(branch.values()):
        return None
    _, x, its = cache[fq]
    return fq, x, its


def insert_peaks(rows: Rows, record, found: list) -> None:
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
        rows.insert_last_at(pos)
