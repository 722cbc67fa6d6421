"""A nonlinear mode's backbone as a path problem (:mod:`..path.engine`), and its corrector.

Unknowns ``Y = [y / var_scale, ln a]`` of the EPMC problem (:mod:`.epmc`,
:mod:`.epmc_condensed`) as the corrector (:class:`BackboneCorrector`)
scales them, continued in ``s = ln a``. Metric of the arc length: the shape
relative to its size, frequency and ``xi`` relative to the linear frequency
(a change of a third counts as the whole amplitude range), ``ln a``
relative to the range; the mean position does not count (as
``dc_weight = 0`` in the forced response: a stuck slider's offset jumps
where slip starts). Below the first slip every contact sticks and the mode
is linear: one natural step crosses that range.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from ...errors import InputError, check_choice
from ..path.newton import Newton, NewtonTest
from ..path.problem import LostContact, Solution, Stop
from ..path.rows import Rows
from .epmc import TWO_PI, Epmc
from .record import POINT_ARRAYS

log = logging.getLogger("workbench.hbm.nlmodes.backbone")

KRYLOV_RTOL = 1e-8  # GMRES: relative residual of each Newton step's linear solve
KRYLOV_MAX_ITS = 40  # GMRES iterations per linear solve (no restart below that)
KRYLOV_REBUILD_ITS = 15  # more GMRES iterations than this: refactorise at the next Jacobian


class _Shell:
    """The bordered Jacobian ``[[diag(rs) J diag(s)], [c]]`` as a PETSc shell (``mult``)."""

    def __init__(self, corr: BackboneCorrector):
        self.corr = corr
        self.T = None

    def mult(self, mat, x, y) -> None:
        me = self.corr
        v = x.getArray(readonly=True)
        N = me.n - 1
        u = np.empty(me.n)
        u[:N] = self.T.matvec(np.concatenate([v[:N] * me.s, v[N:]])) * me.rs
        u[N] = me.c @ v
        y.getArray()[:] = u


class BackboneCorrector:
    """Newton (:class:`..path.newton.Newton`, backtracking line search) on the bordered
    system of a backbone point.

    ``linear``: "dense" (the LU of the Jacobian, PETSc's, rebuilt every ``lag``
    iterations across solves: a chord method between rebuilds), "krylov"
    (problems with a ``tangent`` operator, :class:`.epmc_condensed.EpmcCondensed`:
    GMRES on the exact Jacobian applied without forming it, preconditioned by
    the dense LU of an earlier Jacobian, refactorised only when GMRES needs more
    than ``KRYLOV_REBUILD_ITS`` iterations or fails: Newton's convergence at a
    fraction of the factorisations), "auto" (krylov where the problem has a
    ``tangent`` operator). A failed solve on a lagged preconditioner is repeated
    once with a fresh one.

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
        n = self.n = N + 1
        self.s = prob.var_scale()
        self.rs = prob.row_scale()
        self.c = np.zeros(n)
        self.c[-1] = 1.0
        self.c0 = 0.0
        self.shell = _Shell(self) if linear == "krylov" else None
        self._mats: list = []
        me = self

        def function(Y: np.ndarray, out: np.ndarray) -> None:
            # a line-search trial far off (overflow, NaN) is a failed trial, said by inf
            with np.errstate(over="ignore", invalid="ignore"):
                r, _ = me.prob.residual(Y[:N] * me.s, float(np.exp(Y[N])))
            out[:N] = r * me.rs
            out[N] = me.c @ Y - me.c0

        def on_step() -> None:  # the last step's GMRES: refactorise when it struggled
            k_its = me.ksp.getIterationNumber()
            me.n_krylov += k_its
            if k_its > KRYLOV_REBUILD_ITS or me.ksp.getConvergedReason() < 0:
                me.rebuild = True

        lagged = lag > 1 and linear == "dense"  # the Jacobian every `lag` iterations
        self.newton = Newton(
            n,
            function,
            self._linear,
            NewtonTest(tol, tol_stall, max_it, bordered=True, unscaled=2, give_up_below=None),
            line_search=line_search,
            options=(
                {"snes_lag_jacobian": lag, "snes_lag_jacobian_persists": "true"} if lagged else {}
            ),
            step_failures=False,
            on_step=on_step if linear == "krylov" else None,
        )

    def _linear(self, snes, ksp) -> None:
        """The dense LU of the bordered Jacobian, or GMRES preconditioned by a lagged one."""
        from petsc4py import PETSc

        me, n, N = self, self.n, self.n - 1
        comm = PETSc.COMM_SELF
        self.ksp = ksp
        J = PETSc.Mat().createDense((n, n), comm=comm)
        J.setUp()
        self._mats.append(J)

        def bordered(Jd: np.ndarray) -> np.ndarray:
            """The scaled bordered matrix from the Jacobian (N, N + 1) in [y, ln a]."""
            Jf = np.empty((n, n))
            Jf[:N, :N] = (Jd[:, :N] * me.rs[:, None]) * me.s[None, :]
            Jf[:N, N] = Jd[:, N] * me.rs
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
            if me.linear == "krylov":
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

        if self.linear == "krylov":
            A = PETSc.Mat().createPython((n, n), context=self.shell, comm=comm)
            A.setUp()
            self._mats.append(A)
            snes.setJacobian(jacobian, A, J)
            ksp.setType("gmres")
            ksp.setGMRESRestart(KRYLOV_MAX_ITS)
            ksp.setTolerances(rtol=KRYLOV_RTOL, atol=0.0, max_it=KRYLOV_MAX_ITS)
        else:
            snes.setJacobian(jacobian, J, J)
            ksp.setType("preonly")
        ksp.getPC().setType("lu")

    @property
    def max_it(self) -> int:
        return self.newton.max_it

    def set_max_it(self, max_it: int) -> None:
        """Newton iterations per solve at most (the convergence test's limit)."""
        self.newton.set_max_it(max_it)

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
        Y, ok, its = self.newton.run(Y0)[:3]
        if not ok and self.linear == "krylov" and not fresh:
            self.rebuild = True  # a lagged preconditioner may have misled it: once more
            Y, ok, its2 = self.newton.run(Y0)[:3]
            its += its2
        if not ok and self.linear == "krylov":
            self.rebuild = True
        return Y, ok, its

    def destroy(self) -> None:
        self.newton.destroy(*self._mats)


class Backbone:
    """The backbone of ``prob`` over the modal amplitudes ``a_range`` (sqrt(kg) m).

    ``f_top``, ``f1v``: the largest level and the force, to stop once the
    backbone covers that level's peak (0, None: no such stop);
    ``s_slip``: ``ln a`` just below the first slip; ``plateau_points``: the
    amplitude-limit stop (see :func:`.backbone.nonlinear_mode`).
    """

    def __init__(self, prob, snes, a_range, f_top, f1v, s_slip, plateau_points, rule, bar):
        self.prob, self.snes = prob, snes
        self.a0, self.a1 = a_range
        self.start, self.end = np.log(self.a0), np.log(self.a1)
        self.span = self.end - self.start
        self.f_top, self.f1v, self.s_slip = f_top, f1v, s_slip
        self.plateau_points, self.rule, self.bar = plateau_points, rule, bar
        self.rows = Rows(POINT_ARRAYS, extra=("z",))  # z: the unknowns of each point
        self.phi1_ref: np.ndarray | None = None
        self.last: dict[str, Any] = {}
        self.s_last = self.start
        N = self.N = prob.n_unknowns - 2
        mw = np.empty(N + 3)
        mw[:N] = 1.0 / max(float(np.linalg.norm(prob.linear_guess()[:N])), 1e-300)
        mw[:N][prob.dc_mask()[:N]] = 0.0
        mw[N] = mw[N + 1] = 3.0
        mw[N + 2] = 1.0 / self.span
        self.mw = mw

    # -- the corrector ------------------------------------------------------------------
    def _solve(self, Y0: np.ndarray, c=None, Yp=None) -> Solution:
        Y, ok, its = self.snes.solve(Y0, c, Yp)
        return Solution(Y, Y[-1], ok, its, "", Y)

    def first_point(self) -> Solution:
        """The linear mode at the smallest amplitude."""
        Y, ok, its = self.snes.solve(self.snes.scaled(self.prob.linear_guess(), self.start))
        if not ok:
            raise Stop(f"the corrector failed at the first amplitude {self.a0:.4g}", True)
        self.last = self.add(self.snes.unscaled(Y)[0], self.a0, its)
        return Solution(Y, Y[-1], True, its, "", Y)

    def metric(self) -> np.ndarray:
        return self.mw

    def first_direction(self, p: Solution, m: np.ndarray) -> np.ndarray:
        """Along ``ln a``: the linear mode does not change."""
        t = np.zeros(self.N + 3)
        t[-1] = self.span
        return t

    def solve_plane(self, y0, yp, t, m) -> Solution:
        return self._solve(y0, m**2 * t, yp)

    def solve_at(self, guess: np.ndarray, param: float) -> Solution:
        """At ``s = guess[-1]`` (= ``param``): the bordered system with the row ``e_s``."""
        return self._solve(guess)

    def natural_step(self, p: Solution, prev, t: np.ndarray, ds: float) -> Solution:
        """The next amplitude, ``ds`` of the range ahead, the secant extrapolated to it."""
        Y = p.raw
        dsn = ds * self.span
        if Y[-1] < self.s_slip - 1e-9:
            # every contact sticks below the first slip: the mode is linear there, so one
            # step goes to the point just below it (a kink)
            dsn = self.s_slip - Y[-1]
        Yp = Y + t * (dsn / t[-1]) if t[-1] > 1e-12 * self.span else Y.copy()
        Yp[-1] = Y[-1] + dsn
        return self._solve(Yp)

    def end_guess(self, p: Solution, q: Solution) -> np.ndarray:
        Y, Yn = p.raw, q.raw
        th = (self.end - Y[-1]) / (Yn[-1] - Y[-1])
        Yg = Y + th * (Yn - Y)
        Yg[-1] = self.end
        return Yg

    def _w_d(self, Y: np.ndarray) -> tuple[float, float]:
        y, _ = self.snes.unscaled(Y)
        N = self.N
        return y[N], y[N + 1] / (2 * y[N])

    def change(self, p: Solution, q: Solution) -> float:
        """The largest relative change of frequency and damping ratio from p to q."""
        (w0, d0), (w1, d1) = self._w_d(p.raw), self._w_d(q.raw)
        return max(abs(w1 - w0) / w0, abs(d1 - d0) / max(abs(d0), 1e-3))

    def refresh(self) -> None:
        """The corrector renews its own Jacobian (lag, and Krylov's rebuild rule)."""

    # -- one row per point -------------------------------------------------------------
    def record(self, p: Solution, at_end: bool = False) -> None:
        a = self.a1 if at_end else float(np.exp(p.raw[-1]))
        self.last = self.add(self.snes.unscaled(p.raw)[0], a, p.its)
        self.s_last = p.raw[-1]

    def record_past_end(self, p: Solution, q: Solution) -> None:
        """The point exactly at the largest amplitude did not converge: the converged step
        past it ends the backbone, so the range is covered."""
        log.info(
            "the point at the largest amplitude %.4g did not converge; the backbone ends at "
            "the converged step past it (%.4g)",
            self.a1,
            np.exp(q.raw[-1]),
        )
        try:
            self.record(q)
        except LostContact:
            raise Stop(
                f"the corrector failed at the largest amplitude {self.a1:.4g} and the step "
                f"past it loses contact: the backbone ends at {np.exp(p.raw[-1]):.4g}",
                True,
            ) from None

    def add(self, y: np.ndarray, a: float, its: int) -> dict[str, Any]:
        """Record the point of unknowns ``y`` at amplitude ``a`` (the corrector's)."""
        prob = self.prob
        z = (y.copy(), float(a))
        y, a = prob.physical(y, a)
        pt = prob.point(y, a, self.phi1_ref)
        if self.phi1_ref is None:
            self.phi1_ref = pt["phi1"]
        if pt["lost"]:
            raise LostContact(
                f"the damper has lost contact at modal amplitude {a:.4g}: a singular "
                "state; the backbone ends here",
                False,
            )
        self.rows.add(**{k: pt[k] for k in POINT_ARRAYS if k != "newton_its"}, newton_its=its, z=z)
        f_top, f1v = self.f_top, self.f1v
        if (
            f_top > 0
            and a * pt["xi"] * TWO_PI * pt["freq_hz"] > 2.0 * f_top * abs(np.conj(pt["phi1"]) @ f1v)
            and np.any(pt["status"] > 0)
        ):
            raise Stop(
                f"covers the largest level ({f_top:g}): its peak is below modal amplitude {a:.4g}",
                False,
                completed=True,
            )
        return pt

    def after_point(self) -> None:
        if self.f_top > 0:  # only a backbone for given levels stops at a plateau
            plateau(self.rows.cols, self.plateau_points)
        bar, pt = self.bar, self.last
        bar.n = round(min(max(self.s_last - self.start, 0.0), self.span), 6)
        bar.set_postfix_str(f"{pt['freq_hz']:.4g} Hz, D {pt['damping_ratio']:.3g}", refresh=False)
        bar.update(0)

    def say(self, what: str, **ctx) -> str:
        """The words of a stop (see :func:`..path.engine.follow`)."""
        if what == "max_points":
            return f"stopped after max_points = {self.rule.max_points}"
        if what == "max_solves":
            return (
                f"stopped after {ctx['n_solves']} corrector solves for {self.rows.n} points "
                "(steps refused or halved over and over); the backbone so far is kept"
            )
        if what == "failed":
            return (
                f"the corrector failed after modal amplitude {np.exp(ctx['at'].raw[-1]):.4g} "
                "even with the smallest step; the backbone so far is kept"
            )
        if what == "below_start":
            return "the backbone turned back below the smallest amplitude"
        why = "(the mode changes character, or the free damper's mean position does): it ends here"
        if what == "fold_drop":
            return (
                f"the backbone folds back in amplitude after {np.exp(ctx['top']):.4g} and does "
                f"not turn again within a factor 2 {why}"
            )
        if what == "fold_points":
            return (
                f"the backbone folds back in amplitude after {np.exp(ctx['top']):.4g} and has "
                f"not passed it again in {self.rule.fold_points} points {why}"
            )
        if what == "numerical":
            e = ctx["error"]
            return f"stopped by a numerical error: {type(e).__name__}: {e}"
        raise ValueError(f"no words for a stop of kind {what!r}")


def plateau(rows: dict[str, list], n: int) -> None:
    """Stop where the amplitude has stalled over the last ``n`` points while damping grows.

    Over ``n`` points within 0.2 % in modal amplitude while the damping ratio
    rises by more than a fifth, the mode has met an amplitude limit (lift-off
    or a stop): a larger force then raises the dissipation, not the
    amplitude, which a single mode continued in amplitude cannot follow.
    """
    a, d = rows["amplitude"], rows["damping_ratio"]
    if n < 2 or len(a) < n:
        return
    la = np.log(np.asarray(a[-n:], float))
    d0, d1 = float(d[-n]), float(d[-1])
    if la.max() - la.min() < 2e-3 and d1 > 1.2 * d0:
        raise Stop(
            f"the modal amplitude stalls at {a[-1]:.4g} (within 0.2 % over {n} points) while "
            f"the damping ratio rises from {d0:.3g} to {d1:.3g}: an amplitude limit (lift-off "
            "or a stop), where a larger force raises the dissipation, not the amplitude; "
            "the backbone ends here",
            False,
        )
