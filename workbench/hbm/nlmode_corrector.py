"""The corrector of the nonlinear-mode continuation (:mod:`.nlmodes`): PETSc SNES.

Newton with a backtracking line search on the bordered system (the point
equations of :mod:`.epmc` plus one constraint row). Two linear solvers:

* ``"dense"``: a dense LU of the Jacobian, optionally rebuilt only every few
  iterations (a chord method);
* ``"krylov"`` (problems with a ``tangent`` operator, :class:`.EpmcCondensed`):
  GMRES on the exact Jacobian applied without forming it, preconditioned by
  the dense LU of an earlier Jacobian, refactorised only when GMRES needs
  more than ``KRYLOV_REBUILD_ITS`` iterations or fails (a Newton-Krylov method
  with a lagged preconditioner: Newton's convergence at a fraction of the
  factorisations).
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import InputError
from .epmc import Epmc

log = logging.getLogger("workbench.hbm.nlmodes")

KRYLOV_RTOL = 1e-8  # GMRES: relative residual of each Newton step's linear solve
KRYLOV_MAX_ITS = 40  # GMRES iterations per linear solve (no restart below that)
KRYLOV_REBUILD_ITS = 15  # more GMRES iterations than this: refactorise at the next Jacobian


class _Shell:
    """The bordered Jacobian ``[[diag(rs) J diag(s)], [c]]`` as a PETSc shell (``mult``)."""

    def __init__(self, snes: Snes):
        self.snes = snes
        self.T = None

    def mult(self, mat, x, y) -> None:
        me = self.snes
        v = x.getArray(readonly=True)
        N = me.n - 1
        u = np.empty(me.n)
        u[:N] = self.T.matvec(np.concatenate([v[:N] * me.s, v[N:]])) * me.rs
        u[N] = me.c @ v
        y.getArray()[:] = u


class Snes:
    """Newton (SNES, backtracking line search) on the bordered system.

    ``linear``: "dense" (LU of the Jacobian, rebuilt every ``lag`` iterations),
    "krylov" (GMRES with a lagged LU preconditioner, see the module), "auto"
    (krylov where the problem has a ``tangent`` operator). A failed solve on a
    lagged preconditioner is repeated once with a fresh one.

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
        linear: str = "auto",
    ):
        from petsc4py import PETSc

        from ..errors import check_choice

        check_choice("linear", linear, ("auto", "dense", "krylov"))
        if linear == "auto":
            linear = "krylov" if hasattr(prob, "tangent") else "dense"
        elif linear == "krylov" and not hasattr(prob, "tangent"):
            raise InputError("linear", linear, "dense (this problem has no Jacobian operator)")
        self.linear = linear
        self.n_factor = 0  # dense Jacobians formed (and factorised)
        self.n_krylov = 0  # GMRES iterations in all
        self.rebuild = True  # the preconditioner is refactorised at the next Jacobian

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
        if lag > 1 and linear == "dense":  # the Jacobian every `lag` iterations, across solves
            po[f"{prefix}snes_lag_jacobian"] = lag
            po[f"{prefix}snes_lag_jacobian_persists"] = "true"
        self.F = PETSc.Vec().createSeq(n, comm=comm)
        self.X = PETSc.Vec().createSeq(n, comm=comm)
        self.J = PETSc.Mat().createDense((n, n), comm=comm)
        self.J.setUp()
        self.shell = None
        if linear == "krylov":
            self.shell = _Shell(self)
            self.A = PETSc.Mat().createPython((n, n), context=self.shell, comm=comm)
            self.A.setUp()
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

        def bordered(J: np.ndarray) -> np.ndarray:
            """The scaled bordered matrix from the Jacobian (N, N + 1) in [y, ln a]."""
            Jf = np.empty((n, n))
            Jf[:N, :N] = (J[:, :N] * me.rs[:, None]) * me.s[None, :]
            Jf[:N, N] = J[:, N] * me.rs
            Jf[N] = me.c
            return Jf

        def set_dense(P, Jf: np.ndarray) -> None:
            P.setValues(range(n), range(n), Jf.ravel())  # row-major
            P.assemble()
            me.n_factor += 1

        def jacobian(snes, X, A, P):
            Y = X.getArray(readonly=True)
            a = float(np.exp(Y[N]))
            y = Y[:N] * me.s
            if linear == "krylov":
                _, _, T = me.prob.tangent(y, a)
                me.shell.T = T
                if me.rebuild:  # else P (and its LU) stays: the preconditioner is lagged
                    set_dense(P, bordered(T.dense()))
                    me.rebuild = False
                A.assemble()
                return
            r0, _, Jd = me.prob.residual(y, a, want_jac=True)
            h = 1e-6  # d r / d ln a: one more residual (the contact term alone depends on a)
            r1, _ = me.prob.residual(y, a * np.exp(h))
            set_dense(P, bordered(np.column_stack([Jd, (r1 - r0) / h])))

        self.snes.setFunction(function, self.F)
        ksp = self.snes.getKSP()
        if linear == "krylov":
            self.snes.setJacobian(jacobian, self.A, self.J)
            ksp.setType("gmres")
            ksp.setGMRESRestart(KRYLOV_MAX_ITS)
            ksp.setTolerances(rtol=KRYLOV_RTOL, atol=0.0, max_it=KRYLOV_MAX_ITS)
        else:
            self.snes.setJacobian(jacobian, self.J, self.J)
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
            elif linear == "krylov":  # the last step's GMRES: refactorise when it struggled
                k_its = ksp.getIterationNumber()
                me.n_krylov += k_its
                if k_its > KRYLOV_REBUILD_ITS or ksp.getConvergedReason() < 0:
                    me.rebuild = True
            hist.append(rn)
            c_ok = abs(F[N]) <= 1e-9
            if rn <= tol * scale and c_ok:
                me.ok = True
                return reasons.CONVERGED_FNORM_ABS
            if len(hist) > 4 and hist[-1] > 0.5 * hist[-5] and rn <= tol_stall * scale and c_ok:
                me.ok = True  # Newton stalls on a kink (stick/slip transition)
                return reasons.CONVERGED_SNORM_RELATIVE
            if it >= me.max_it:
                return reasons.DIVERGED_MAX_IT
            return reasons.ITERATING

        self.snes.setConvergenceTest(converged)
        self.set_max_it(max_it)
        self.snes.setMaxLinearSolveFailures(10**6)
        self.snes.setFromOptions()
        for key in ("linesearch_type", "lag_jacobian", "lag_jacobian_persists"):
            po.delValue(f"{prefix}snes_{key}")

    def set_max_it(self, max_it: int) -> None:
        """Newton iterations per solve at most (the convergence test's limit)."""
        self.max_it = int(max_it)
        self.snes.setTolerances(max_it=self.max_it + 1)

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
        fresh = self.rebuild
        Y, ok, its = self._solve(Y0)
        if not ok and self.linear == "krylov" and not fresh:
            self.rebuild = True  # a lagged preconditioner may have misled it: once more
            Y, ok, its2 = self._solve(Y0)
            its += its2
        if not ok and self.linear == "krylov":
            self.rebuild = True
        return Y, ok, its

    def _solve(self, Y0: np.ndarray) -> tuple[np.ndarray, bool, int]:
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
        for o in (self.snes, self.F, self.X, self.J) + ((self.A,) if self.shell else ()):
            o.destroy()
