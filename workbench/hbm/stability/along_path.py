"""Where Hill's method runs along a branch, and what every other point is told.

Hill's verdict (:mod:`.hill`) costs a factorisation of the harmonic
balance Jacobian and an eigen-solve, as much as the rest of a point or
several times more. Along a branch it is established where it can change
and carried between, and every point says which (``how``):

* ``HOW_LINEAR``, every contact stuck all period (the contact Jacobian is
  the stuck stiffness, apart from the mean-position anchor on harmonic 0):
  Hill's problem is then that of a linear system. It splits by harmonic,
  the copies of one exponent differ by ``i k w`` only, so the real parts of
  the exponents are the same at every such point of the branch, whatever
  the frequency. The first stuck point is checked; when it is stable, every
  later stuck point is stable with the same largest real part: established,
  not carried.
* ``HOW_HILL``, checked at the point: the first point, the first point of
  every stretch where some contact slips, every point where some contact
  opens during the period (the contact Jacobian jumps where samples open
  and close, and the exponents with it: on the heavy rig's wedge in phase
  an exponent of +101 1/s appears for three points between two checks at
  -4 1/s), and then ahead of the least-damped exponent: with ``m`` the
  largest real part over ``w`` at the last two checks of the stretch, the
  next check comes at half the distance (in points) at which ``m``
  extrapolates to the imaginary axis,
  at least the next point, at most ``stability_stride`` points on (the next
  point after an unknown verdict or a change of verdict). When the branch
  is done: both band ends, the peaks of ``|y(t)|`` and of the harmonic-1
  amplitude, the points around every fold, and bisection between any two
  checked points of different verdicts (unknown included) until they are
  neighbours.
* ``HOW_CARRIED``, between two checked (or linear) points of the same
  definite verdict: that verdict as :data:`CARRIED_STABLE` or
  :data:`CARRIED_UNSTABLE`, never plain stable or unstable; between two
  unknown checks, unknown (``HOW_NONE``: never computed).

What this can miss: an exponent that crosses the imaginary axis and back
between two checks whose own exponents give no sign of it (the
extrapolation sees the least-damped exponent move toward the axis and
checks densely there; an exponent that jumps, at a stick/slip transition,
is checked densely only if the checks around it notice). Such points are
labelled carried. ``stability_stride = 1`` checks every point.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from .hill import (
    CARRIED_STABLE,
    CARRIED_UNSTABLE,
    STABLE,
    UNKNOWN,
    UNSTABLE,
    Stability,
    hill_arpack,
    hill_dense,
)
from .hill import unknown as stability_unknown

log = logging.getLogger(__name__)

HOW_NONE, HOW_HILL, HOW_LINEAR, HOW_CARRIED = 0, 1, 2, 3
HOW_NAMES = {
    HOW_NONE: "not computed",
    HOW_HILL: "Hill's method at the point",
    HOW_LINEAR: "every contact stuck: the linear system's verdict",
    HOW_CARRIED: "carried from the checked neighbours",
}
PENDING = -9  # internal: a verdict decided when the branch is done
TWO_PI = 2.0 * np.pi


class StabilityPath:
    """Hill's verdicts along one branch: checks where the verdict can change, carried between.

    :meth:`at_point` is called for every point as it is recorded (in
    continuation order) and returns ``(verdict, max_real, how)``, with the
    verdict :data:`PENDING` when it is decided later; :meth:`finish` decides
    those once the branch (and its peak points) is complete.
    """

    def __init__(self, hb, corr, opts):
        self.hb, self.corr, self.opts = hb, corr, opts
        self.stride = max(int(opts.stability_stride), 1)
        self.v0: np.ndarray | None = None  # ARPACK start vector (the last check's)
        self.hill: dict = {}  # the branch's dense Hill blocks, ARPACK's exponent count
        self.linear: Stability | None = None  # the stuck state's verdict, once established
        self.n_calls = 0
        self.stretch: list[tuple[int, int, float]] = []  # (call, verdict, max Re / w) checks
        self.due = 0  # call index from which a check is due in a non-linear stretch
        self.stats = dict(n_hill=0, n_linear=0, n_carried=0, n_bisect=0, n_unknown=0)
        self.time = 0.0

    # -- one check -------------------------------------------------------------
    def check(self, ev) -> Stability:
        """Hill's verdict at the evaluation ``ev`` of a solution (dense or ARPACK)."""
        t0 = time.perf_counter()
        hb, corr, opts = self.hb, self.corr, self.opts
        w = ev.omega
        size = 2 * hb.lin.n_z * hb.fourier.nh
        if size <= opts.hill_dense_limit:
            if self.hill.get("parts") is None:
                self.hill["parts"] = hb.hill_parts()
            d0, d1, d2 = hb.hill_dense(ev, self.hill["parts"])
            st = hill_dense(d0, d1, d2, w, hb.fourier.harmonics, opts.unstable_tol)
        else:
            lu = corr.factor(ev.x / corr.u_ref, w / corr.w_ref)
            refine = 1 if lu.dtype == np.float32 else 0
            size, op = hb.hill_shift_invert(lu.ev, lambda b: lu.solve(b, refine=refine))
            try:
                st = hill_arpack(
                    size,
                    op,
                    w,
                    hb.fourier.harmonics,
                    max(opts.n_floquet, self.hill.get("k") or 0),
                    opts.unstable_tol,
                    v0=self.v0,
                    n_max=opts.n_floquet_max,
                )
            except Exception as e:  # noqa: BLE001 - ARPACK breakdown: say so, keep the point
                log.warning("Hill's method failed at %.6g Hz (%s): unknown", w / TWO_PI, e)
                st = stability_unknown(f"ARPACK failed: {e}", "arpack")
            # the next check starts with about the exponents this one found inside the disc
            # |lambda| <= w/2 (it grows again by doubling when they do not cover it)
            if st.n_exp:
                self.hill["k"] = min(st.n_exp, max(opts.n_floquet, math.ceil(1.25 * st.n_disc) + 2))
            if st.start is not None:
                self.v0 = st.start
        self.stats["n_hill"] += 1
        if st.verdict == UNKNOWN:
            self.stats["n_unknown"] += 1
        self.time += time.perf_counter() - t0
        return st

    # -- inline, as points are recorded --------------------------------------------
    def at_point(self, ev, force: bool = False) -> tuple[int, float, int]:
        """``(verdict, max_real, how)`` of a new point; the verdict may be :data:`PENDING`."""
        k = self.n_calls
        self.n_calls += 1
        if self._is_linear(ev):
            self.stretch = []
            if self.linear is not None:
                self.stats["n_linear"] += 1
                return self.linear.verdict, self.linear.max_real, HOW_LINEAR
            st = self.check(ev)
            if st.verdict == STABLE:  # a damped linear system: every stuck point is too
                self.linear = st
            return st.verdict, st.max_real, HOW_HILL
        if force or not self.stretch or k >= self.due or self._separates(ev):
            st = self.check(ev)
            self._schedule(k, st, ev.omega)
            return st.verdict, st.max_real, HOW_HILL
        return PENDING, float("nan"), HOW_NONE

    def _is_linear(self, ev) -> bool:
        """Every contact stuck and closed all period (its Jacobian the stuck stiffness)."""
        hb = self.hb
        if not hb.n_el:
            return True
        nonlin, _ = hb.element_classes(ev)
        return nonlin.size == 0

    @staticmethod
    def _separates(ev) -> bool:
        """Some contact opens during the period: checked at every such point (the contact
        Jacobian jumps where samples open and close, and the exponents with it)."""
        return ev.aft is not None and bool(np.any(ev.aft.n_sep))

    def _schedule(self, k: int, st: Stability, omega: float) -> None:
        """The call index of the next check of this non-linear stretch, after a check at ``k``."""
        m = st.max_real / omega if np.isfinite(st.max_real) else np.nan
        self.stretch.append((k, st.verdict, m))
        if len(self.stretch) > 2:
            self.stretch.pop(0)
        gap = self.stride
        if st.verdict == UNKNOWN or not np.isfinite(m):
            gap = 1
        elif len(self.stretch) == 1:
            gap = min(2, self.stride)
        else:
            (ka, va, ma), (kb, vb, mb) = self.stretch
            if va != vb or not np.isfinite(ma):
                gap = 1
            else:
                rate = (mb - ma) / max(kb - ka, 1)  # per point; toward the axis: sign of -mb
                toward = rate if mb < 0 else -rate
                if toward > 0:
                    gap = int(np.clip(np.floor(0.5 * abs(mb) / toward), 1, self.stride))
        self.due = k + gap

    # -- when the branch is done -------------------------------------------------
    def finish(self, rows: dict[str, list]) -> None:
        """Decide every pending verdict of the recorder's ``rows`` (final point order).

        Checks both band ends, the peaks, the points around folds and, by
        bisection, between checked points of different verdicts; carries the
        rest (see the module docstring). Updates ``stability``, ``stable``,
        ``max_floquet_real`` and ``stability_how`` in place.
        """
        v = rows["stability"]
        n = len(v)
        if not n:
            return
        f = np.asarray(rows["freq_hz"], dtype=float)
        must = {0, n - 1}
        for key in ("out_amp", "out_h1"):
            vals = [a[0] for a in rows[key]] if rows[key] and len(rows[key][0]) else []
            if vals:
                must.add(int(np.argmax(vals)))
        d = np.diff(f)
        for i in range(1, n - 1):
            if d[i - 1] * d[i] < 0:  # a turning point of the frequency: a fold near i
                must.update((i - 1, i, i + 1))
        for i in sorted(must):
            self._check_row(rows, i)
        while True:
            resolved = [i for i in range(n) if v[i] != PENDING]
            todo = []
            for a, b in zip(resolved[:-1], resolved[1:], strict=True):
                if b - a < 2:
                    continue
                va, vb = _definite(v[a]), _definite(v[b])
                if va == vb:
                    fill = {STABLE: CARRIED_STABLE, UNSTABLE: CARRIED_UNSTABLE}.get(va, UNKNOWN)
                    how = HOW_CARRIED if va in (STABLE, UNSTABLE) else HOW_NONE
                    for i in range(a + 1, b):
                        v[i] = fill
                        rows["stable"][i] = False
                        rows["max_floquet_real"][i] = float("nan")
                        rows["stability_how"][i] = how
                        self.stats["n_carried"] += how == HOW_CARRIED
                else:
                    todo.append((a + b) // 2)
            if not todo:
                break
            for i in todo:
                self.stats["n_bisect"] += 1
                self._check_row(rows, i)

    def abandon(self, rows: dict[str, list], why: str) -> None:
        """Leave every verdict still pending unknown (a numerical failure while deciding them)."""
        log.warning("stability of the remaining points not decided (%s): unknown", why)
        for i, v in enumerate(rows["stability"]):
            if v == PENDING:
                rows["stability"][i] = UNKNOWN
                rows["stable"][i] = False
                rows["stability_how"][i] = HOW_NONE

    def _check_row(self, rows: dict[str, list], i: int) -> None:
        """Hill's method at row ``i`` when its verdict is pending (its evaluation recomputed)."""
        if rows["stability"][i] != PENDING:
            return
        st = self.check(self._row_evaluation(rows, i))
        rows["stability"][i] = st.verdict
        rows["stable"][i] = st.stable
        rows["max_floquet_real"][i] = st.max_real
        rows["stability_how"][i] = HOW_HILL

    def _row_evaluation(self, rows: dict[str, list], i: int):
        """The evaluation at row ``i`` of the branch (recomputed from its unknowns)."""
        x = np.asarray(rows["x"][i], dtype=float)
        return self.corr.evaluated(x, TWO_PI * float(rows["freq_hz"][i]))

    def summary(self) -> dict[str, float | int]:
        """Counts of each kind of verdict and the time spent in Hill's method (s)."""
        return {**self.stats, "t_hill": self.time}


def _definite(v: int) -> int:
    """The verdict a checked or linear point contributes to carrying (unknown stays unknown)."""
    return {STABLE: STABLE, UNSTABLE: UNSTABLE}.get(int(v), UNKNOWN)
