"""The corrector of the nonlinear-mode continuation (:mod:`.nlmodes`): PETSc SNES.

Newton with a backtracking line search and a dense LU of the bordered
Jacobian (the point equations of :mod:`.epmc` plus one constraint row), with
its Jacobian optionally rebuilt only every few iterations (a chord method).
"""

from __future__ import annotations

import logging

import numpy as np

from .epmc import Epmc

log = logging.getLogger("workbench.hbm.nlmodes")


class Snes:
    """Newton (SNES, backtracking line search, dense LU) on the bordered system.

    Unknowns ``Y = [y / scale, s]`` with ``s = ln a``; equations
    ``[r(y; e^s) * row_scale, c . (Y - Yp)]``: the constraint ``c`` is ``e_s``
    for a point at a given amplitude, or the secant for a pseudo-arc-length
    step (which passes a fold of the backbone in amplitude).
    """

    def __init__(
        self,
        prob: Epmc,
        tol: float,
        tol_stall: float,
        max_it: int,
        line_search: str = "bt",
        lag: int = 1,
    ):
        from petsc4py import PETSc

        self.prob = prob
        N = prob.n_unknowns
        n = N + 1
        self.n = n
        comm = PETSc.COMM_SELF
        self.snes = PETSc.SNES().create(comm)
        prefix = f"upd_epmc{id(self)}_"
        self.snes.setOptionsPrefix(prefix)
        po = PETSc.Options()
        po[f"{prefix}snes_linesearch_type"] = line_search
        if lag > 1:  # the Jacobian every `lag` iterations, counted across solves
            po[f"{prefix}snes_lag_jacobian"] = lag
            po[f"{prefix}snes_lag_jacobian_persists"] = "true"
        self.F = PETSc.Vec().createSeq(n, comm=comm)
        self.X = PETSc.Vec().createSeq(n, comm=comm)
        self.J = PETSc.Mat().createDense((n, n), comm=comm)
        self.J.setUp()
        self.s = prob.var_scale()
        self.rs = prob.row_scale()
        self.c = np.zeros(n)
        self.c[-1] = 1.0
        self.c0 = 0.0
        me = self

        def function(snes, X, F):
            Y = X.getArray(readonly=True)
            # a line-search trial far off (overflow, NaN) is a failed trial, said by inf
            with np.errstate(over="ignore", invalid="ignore"):
                r, _ = me.prob.residual(Y[:N] * me.s, float(np.exp(Y[N])))
            out = F.getArray()
            out[:N] = r * me.rs
            out[N] = me.c @ Y - me.c0
            if not np.all(np.isfinite(out)):
                out[:] = np.inf

        def jacobian(snes, X, A, P):
            Y = X.getArray(readonly=True)
            a = float(np.exp(Y[N]))
            y = Y[:N] * me.s
            r0, _, Jd = me.prob.residual(y, a, want_jac=True)
            Jf = np.empty((n, n))
            Jf[:N, :N] = (Jd * me.rs[:, None]) * me.s[None, :]
            h = 1e-6  # d r / d ln a: one more residual (the contact term alone depends on a)
            r1, _ = me.prob.residual(y, a * np.exp(h))
            Jf[:N, N] = (r1 - r0) / h * me.rs
            Jf[N] = me.c
            A.setValues(range(n), range(n), Jf.ravel())  # row-major
            A.assemble()

        self.snes.setFunction(function, self.F)
        self.snes.setJacobian(jacobian, self.J, self.J)
        ksp = self.snes.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        reasons = PETSc.SNES.ConvergedReason
        hist: list[float] = []
        self.ok = False

        def converged(snes, it, norms):
            F = snes.getFunction()[0].getArray(readonly=True)
            X = snes.getSolution().getArray(readonly=True)
            if not np.all(np.isfinite(F)):
                return reasons.DIVERGED_FNORM_NAN
            rn = float(np.abs(F[:N]).max())
            scale = max(float(np.abs(X[: N - 2]).max()), 1.0)
            if it == 0:
                hist.clear()
            hist.append(rn)
            c_ok = abs(F[N]) <= 1e-9
            if rn <= tol * scale and c_ok:
                me.ok = True
                return reasons.CONVERGED_FNORM_ABS
            if len(hist) > 4 and hist[-1] > 0.5 * hist[-5] and rn <= tol_stall * scale and c_ok:
                me.ok = True  # Newton stalls on a kink (stick/slip transition)
                return reasons.CONVERGED_SNORM_RELATIVE
            if it >= max_it:
                return reasons.DIVERGED_MAX_IT
            return reasons.ITERATING

        self.snes.setConvergenceTest(converged)
        self.snes.setTolerances(max_it=max_it + 1)
        self.snes.setMaxLinearSolveFailures(10**6)
        self.snes.setFromOptions()
        for key in ("linesearch_type", "lag_jacobian", "lag_jacobian_persists"):
            po.delValue(f"{prefix}snes_{key}")

    def scaled(self, y: np.ndarray, s: float) -> np.ndarray:
        return np.concatenate([y / self.s, [s]])

    def unscaled(self, Y: np.ndarray) -> tuple[np.ndarray, float]:
        return Y[:-1] * self.s, float(Y[-1])

    def solve(
        self, Y0: np.ndarray, c: np.ndarray | None = None, Yp: np.ndarray | None = None
    ) -> tuple[np.ndarray, bool, int]:
        """From ``Y0`` with the constraint ``c . (Y - Yp) = 0`` (default: ``s = Y0[-1]``)."""
        if c is None:
            self.c = np.zeros(self.n)
            self.c[-1] = 1.0
            self.c0 = float(Y0[-1])
        else:
            self.c = np.asarray(c, float)
            self.c0 = float(self.c @ (Y0 if Yp is None else Yp))
        self.X.getArray()[:] = Y0
        self.ok = False
        try:
            self.snes.solve(None, self.X)
        except Exception as e:  # noqa: BLE001 - a PETSc/numerical failure is a failed step
            log.debug("EPMC corrector: %s", e)
            return Y0, False, 0
        Y = self.X.getArray(readonly=True).copy()
        ok = bool(self.snes.getConvergedReason() > 0 and self.ok and np.all(np.isfinite(Y)))
        return Y, ok, int(self.snes.getIterationNumber())

    def destroy(self) -> None:
        for o in (self.snes, self.F, self.X, self.J):
            o.destroy()
