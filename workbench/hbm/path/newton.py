"""The one Newton solver of hbm/: PETSc SNES (petsc4py, imported lazily) with our own
convergence test.

:class:`Newton` owns what every corrector of a path problem shares: the
SNES object and its options (line search, prefix, iteration limits), the
residual callback, the convergence test (:class:`NewtonTest`), the run and
its bookkeeping (a solve counts as converged only if our test said so) and
the PETSc objects' lifetime. What differs between problems is the linear
solver (the Jacobian matrix, the KSP and its preconditioner): the caller's
``linear(snes, ksp)`` sets it up (the forced response's shell LU and
finite differences in :mod:`workbench.hbm.forced.corrector`, the backbone's dense
LU and Newton-Krylov in :mod:`workbench.hbm.nlmodes.problem`).

The test, on the residual ``r`` (every equation but a constraint row) and
the unknowns ``x`` (all but the last ``unscaled`` entries): converged when
``max |r| <= tol * max(max |x|, 1)`` with the constraint within
``con_tol``; Newton stalling (the residual not halved over ``stall``
iterations, on a kink of the piecewise-smooth residual) is accepted below
``tol_stall`` (and, with ``give_up_below``, abandoned above
``tol_stall`` once below ``give_up_below``); ``stagnation`` iterations
without halving far from a solution give up; ``max_it`` iterations at most.
"""

from __future__ import annotations

import itertools
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

log = logging.getLogger(__name__)
_ids = itertools.count()


@dataclass(frozen=True)
class NewtonTest:
    tol: float
    tol_stall: float
    max_it: int
    bordered: bool  # the last equation is a constraint row
    unscaled: int = 0  # trailing unknowns left out of the scale of the test
    stall: int = 4
    give_up_below: float | None = 1e-4
    stagnation: int = 0
    con_tol: float = 1e-9


class Newton:
    """Newton with a line search on ``n`` unknowns: ``function(Y, F)`` fills the
    residual ``F`` at ``Y`` (numpy arrays); ``linear(snes, ksp)`` sets the Jacobian and
    the linear solver up. ``options``: more PETSc options for this solver (without the
    prefix); ``step_failures``: let SNES go on after a failed line search (our test
    decides); ``on_step()``: called before the test of every iteration but the first;
    ``stats``: the dict the counters go to (``n_snes``, ``t_snes``, ``ksp_its``,
    ``n_stalled``, ``n_failed``)."""

    def __init__(
        self,
        n: int,
        function: Callable[[np.ndarray, np.ndarray], None],
        linear: Callable[[Any, Any], None],
        test: NewtonTest,
        line_search: str = "bt",
        ls_max_it: int | None = None,
        options: dict[str, object] | None = None,
        step_failures: bool = True,
        on_step: Callable[[], None] | None = None,
        stats: dict[str, Any] | None = None,
    ):
        from petsc4py import PETSc

        self.n, self.test = n, test
        self.max_it = test.max_it
        self.stats = stats if stats is not None else {}
        for k in ("n_snes", "ksp_its", "n_stalled", "n_failed"):
            self.stats.setdefault(k, 0)
        self.stats.setdefault("t_snes", 0.0)
        comm = PETSc.COMM_SELF
        snes = self.snes = PETSc.SNES().create(comm)
        prefix = f"upd_newton{next(_ids)}_"
        snes.setOptionsPrefix(prefix)
        po = PETSc.Options()
        opts: dict[str, object] = {"snes_linesearch_type": line_search}
        if ls_max_it is not None:
            opts["snes_linesearch_max_it"] = ls_max_it
        opts.update(options or {})
        for k, v in opts.items():
            po[f"{prefix}{k}"] = v
        self.F = PETSc.Vec().createSeq(n, comm=comm)

        def residual(snes, X, F):
            out = F.getArray()
            function(X.getArray(readonly=True), out)
            if not np.all(np.isfinite(out)):
                out[:] = np.inf

        snes.setFunction(residual, self.F)
        linear(snes, snes.getKSP())
        snes.setMaxLinearSolveFailures(10**6)
        if step_failures:
            snes.setMaxNonlinearStepFailures(10**6)
        reasons = PETSc.SNES.ConvergedReason
        hist: list[float] = []
        self.own_ok = False
        t = test
        m = n - 1 if t.bordered else n  # equations but the constraint
        mx = m - t.unscaled if t.bordered else n - t.unscaled  # unknowns in the scale

        def converged(snes, it, norms):
            F = snes.getFunction()[0].getArray(readonly=True)
            X = snes.getSolution().getArray(readonly=True)
            if not np.all(np.isfinite(F)):
                return reasons.DIVERGED_FNORM_NAN
            rn = np.abs(F[:m]).max(initial=0.0)
            scale = max(np.abs(X[:mx]).max(initial=0.0), 1.0)
            if it == 0:
                hist.clear()
            elif on_step is not None:
                on_step()
            hist.append(rn)
            if log.isEnabledFor(logging.DEBUG):
                log.debug("it %d |r|_inf %.3e |x|_inf %.3e", it, rn, scale)
            c_ok = not t.bordered or abs(F[-1]) <= t.con_tol
            if rn <= t.tol * scale and c_ok:
                self.own_ok = True
                return reasons.CONVERGED_FNORM_ABS
            # Newton stagnates on a kink of the piecewise-smooth residual (an element that
            # just touches its slip limit): accept below the looser tolerance
            if len(hist) > t.stall and hist[-1] > 0.5 * hist[-1 - t.stall]:
                near = t.give_up_below is None or rn <= t.give_up_below * scale
                if near and rn <= t.tol_stall * scale and c_ok:
                    self.stats["n_stalled"] += 1
                    self.own_ok = True
                    return reasons.CONVERGED_SNORM_RELATIVE
                if t.give_up_below is not None and near:
                    return reasons.DIVERGED_LOCAL_MIN
            # far from a solution and not getting closer (the line search creeps along a
            # kink the step straddles): give up now, a shorter step is cheaper
            stag = t.stagnation
            if stag and len(hist) > stag and hist[-1] > 0.5 * hist[-1 - stag]:
                return reasons.DIVERGED_LOCAL_MIN
            if it >= self.max_it:
                return reasons.DIVERGED_MAX_IT
            return reasons.ITERATING

        snes.setConvergenceTest(converged)
        snes.setTolerances(max_it=self.max_it + 1)
        snes.setFromOptions()
        for k in opts:
            po.delValue(f"{prefix}{k}")
        self.X = PETSc.Vec().createSeq(n, comm=comm)

    def set_max_it(self, max_it: int) -> None:
        """Newton iterations per solve at most (the convergence test's limit)."""
        self.max_it = int(max_it)
        self.snes.setTolerances(max_it=self.max_it + 1)

    def run(self, y0: np.ndarray) -> tuple[np.ndarray, bool, int, int, str]:
        """Solve from ``y0``: (solution, converged, Newton its, linear its, reason)."""
        snes, X, st = self.snes, self.X, self.stats
        X.getArray()[:] = y0
        self.own_ok = False  # set by our convergence test only
        t0 = time.perf_counter()
        try:
            snes.solve(None, X)
        except Exception as e:  # noqa: BLE001 - a PETSc/numerical failure is a failed step
            st["t_snes"] += time.perf_counter() - t0
            log.debug("Newton: %s", e)
            return y0, False, 0, 0, f"exception: {type(e).__name__}: {e}"
        st["t_snes"] += time.perf_counter() - t0
        st["n_snes"] += 1
        reason = snes.getConvergedReason()
        its = snes.getIterationNumber()
        kits = snes.getLinearSolveIterations()
        st["ksp_its"] += kits
        name = reason_name(reason)
        y = X.getArray(readonly=True).copy()
        # a positive reason that our test did not give (SNES stops with "converged" when a
        # failed line search leaves a step below stol |x|, as cp does) is not a solution
        ok = bool(reason > 0 and self.own_ok and np.all(np.isfinite(y)))
        if reason > 0 and not self.own_ok:
            name = f"{name} (declared by SNES with the residual not converged)"
        if not ok:
            st["n_failed"] += 1
        return y, ok, int(its), int(kits), name

    def destroy(self, *more) -> None:
        """Free the PETSc objects (and ``more`` of the caller's)."""
        for o in (self.snes, self.F, self.X, *more):
            o.destroy()


_REASONS: dict[int, str] = {}


def reason_name(reason: int) -> str:
    """The name of a SNES converged reason."""
    if not _REASONS:
        from petsc4py import PETSc

        for k, v in PETSc.SNES.ConvergedReason.__dict__.items():
            if not k.startswith("_") and isinstance(v, int) and k != "ITERATING":
                _REASONS.setdefault(v, k)
    return _REASONS.get(int(reason), str(reason))
