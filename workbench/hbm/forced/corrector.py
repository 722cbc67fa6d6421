"""Newton corrector: PETSc SNES (petsc4py, imported lazily) with the analytic Jacobian.

The unknowns are scaled, ``xs = x / u_ref`` and ``ws = w / w_ref``, so
that every entry is of order one. Two systems are solved:

* natural: ``r(x, w) = 0`` at fixed ``w``;
* arc-length: ``[r(x, w); t . (z(x, w) - z_p)] = 0``, the pseudo-arc-length
  constraint in the continuation metric ``z = (a_x xs, a_w ws)``.

The Jacobian operator is a PETSc shell matrix whose product is exact
(:meth:`HarmonicBalance.jvp` bordered by ``dr/dw`` and the constraint).
The preconditioner is a shell holding a dense LU of ``dr/dx`` (scipy),
bordered for the arc-length system; when it is refreshed is the linear
solver policy:

* ``newton``: every Newton iteration (KSP preonly: plain Newton);
* ``lagged``: GMRES preconditioned by the last LU, refreshed when GMRES
  needed ``refresh_ksp_its`` iterations or failed;
* ``chord``: the last LU alone (KSP preonly), refreshed only on request.

With ``jacobian = "fd"`` SNES builds a dense finite-difference Jacobian
itself and factors it with PETSc's LU (for comparison studies).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..core.balance import Evaluation, HarmonicBalance
from ..core.options import SolverOptions
from ..path.newton import Newton, NewtonTest

log = logging.getLogger(__name__)


@dataclass
class CorrectorResult:
    x: np.ndarray  # (N,) unknowns, m
    omega: float  # rad/s
    converged: bool
    its: int
    ksp_its: int
    reason: str


class Constraint:
    """Arc-length constraint in scaled variables ``y = (xs, ws)`` with metric weights ``m``.

    Plane (pseudo-arc-length): ``sum_j m_j t_j (y_j - yp_j) = 0``. Sphere
    (``center`` given): ``sum_j m_j (y_j - c_j)^2 = ds^2``, which still cuts a
    branch that turns by more than 90 degrees at a kink (a fold at a
    stick/slip or contact transition), where every plane ahead misses it.
    """

    def __init__(
        self,
        tx: np.ndarray,
        tw: float,
        mx: np.ndarray | float,
        mw: float,
        xp: np.ndarray,
        wp: float,
        center: tuple[np.ndarray, float] | None = None,
        ds: float = 0.0,
    ):
        self.mx, self.mw = mx, mw
        self.sphere = center is not None
        if self.sphere:
            self.xc, self.wc = center
            self.ds = ds
        self.cx = tx * mx  # plane row on xs
        self.cw = tw * mw  # plane entry on ws
        self.c0 = float(self.cx @ xp + self.cw * wp)

    def value(self, xs: np.ndarray, ws: float) -> float:
        if self.sphere:
            d2 = float(np.sum(self.mx * (xs - self.xc) ** 2) + self.mw * (ws - self.wc) ** 2)
            return (d2 - self.ds**2) / (2 * self.ds)
        return float(self.cx @ xs + self.cw * ws) - self.c0

    def row(self, xs: np.ndarray, ws: float) -> tuple[np.ndarray, float]:
        if self.sphere:
            return self.mx * (xs - self.xc) / self.ds, float(self.mw * (ws - self.wc) / self.ds)
        return self.cx, self.cw


class Factorization:
    """A factorised Jacobian ``dr/dx`` (scaled) at one state, with ``dr/dws`` for bordering.

    Only the columns of elements whose contact Jacobian is not zero enter the
    factorisation: with ``J = I + E U_P^T`` (``E`` the non-trivial columns
    ``P``), ``J^-1 b = b - E (I + E_P)^-1 b_P``, so a mostly stuck state
    factors a small matrix. ``single=True`` factors in float32 (half the
    time); :meth:`solve` then refines with the exact product when asked.
    """

    def __init__(
        self,
        hb: HarmonicBalance,
        ev: Evaluation,
        jw: np.ndarray,
        single: bool = False,
        reduce: bool = True,
    ):
        """``ev``: the evaluation at the state (:meth:`HarmonicBalance.evaluate`); ``jw``:
        ``dr/dw`` there in the caller's scaling (the bordering column)."""
        self.hb, self.ev = hb, ev
        self.N = hb.N
        self.P: np.ndarray | None = None
        self.E: np.ndarray | None = None
        nonlin, anchored = (
            hb.element_classes(ev)
            if hb.n_el and hb.space == "condensed"
            else (np.arange(hb.n_el), np.zeros(0, int))
        )
        if reduce and hb.space == "condensed" and nonlin.size < hb.n_el:
            C1, c1 = (
                hb.jacobian_columns(ev, nonlin)
                if nonlin.size
                else (np.zeros((self.N, 0)), np.zeros(0, int))
            )
            C2, c2 = hb.anchor_columns(anchored)
            self.E = np.hstack([C1, C2])
            self.P = np.concatenate([c1, c2]).astype(int)
            M = self.E[self.P].copy()
            M.flat[:: M.shape[0] + 1] += 1.0
        else:
            M = hb.dense_jacobian(ev, dtype=np.float32 if single else np.float64)
        self.size = M.shape[0]
        dtype = np.float32 if single else np.float64
        self.lu = sla.lu_factor(M.astype(dtype), check_finite=False) if self.size else None
        self.dtype = dtype
        self.z2 = self.solve(jw, refine=1 if single else 0)

    def _solve_once(self, b: np.ndarray) -> np.ndarray:
        if self.P is None:
            return sla.lu_solve(self.lu, b.astype(self.dtype), check_finite=False).astype(float)
        if self.size == 0:
            return b.copy()
        y = sla.lu_solve(self.lu, b[self.P].astype(self.dtype), check_finite=False).astype(float)
        return b - self.E @ y

    def solve(self, b: np.ndarray, refine: int = 0) -> np.ndarray:
        """``J^-1 b``; ``refine`` steps of iterative refinement with the exact product."""
        x = self._solve_once(b)
        for _ in range(refine):
            r = b - self.hb.jvp(self.ev, x)
            x = x + self._solve_once(r)
        return x

    def solve_bordered(
        self, r: np.ndarray, s: float, cx: np.ndarray, cw: float
    ) -> tuple[np.ndarray, float]:
        """Solve ``[[J, jw], [cx, cw]] [a; b] = [r; s]`` by block elimination."""
        z1 = self.solve(r)
        den = cw - cx @ self.z2
        if abs(den) <= 1e-14 * (abs(cw) + np.abs(cx).sum() * max(np.abs(self.z2).max(), 1)):
            return z1, 0.0
        b = (s - cx @ z1) / den
        return z1 - b * self.z2, float(b)


class Corrector:
    """SNES-based corrector for one :class:`HarmonicBalance` (scaled unknowns)."""

    def __init__(self, hb: HarmonicBalance, opts: SolverOptions, u_ref: float, w_ref: float):
        self.hb, self.opts = hb, opts
        self.u_ref, self.w_ref = float(u_ref), float(w_ref)
        self.N = hb.N
        mode = opts.linear_solver
        if mode == "auto":
            mode = "newton" if self.N <= opts.auto_newton_limit else "lagged"
        if opts.jacobian == "fd":
            mode = "fd"
        self.mode = mode
        self.lu: Factorization | None = None
        prec = opts.factor_precision
        # single precision only under GMRES (lagged), which restores double accuracy
        self.single = mode == "lagged" and (
            prec == "single" or (prec == "auto" and self.N > opts.single_above)
        )
        self.lu_state: tuple[np.ndarray, float] | None = None
        self.force_refresh = False
        self.constraint: Constraint | None = None
        self.w_fixed = 0.0
        self._snes: dict[str, Newton] = {}
        self.stats = dict(
            n_factor=0, t_factor=0.0, n_snes=0, t_snes=0.0, ksp_its=0, n_stalled=0, n_failed=0
        )
        # the last evaluation (SNES asks for the residual, then the Jacobian at the same point)
        self.ev: Evaluation | None = None

    # -- scaled problem --------------------------------------------------------
    def _last(self, x: np.ndarray, omega: float, ulps: int = 0) -> Evaluation | None:
        """The last evaluation if it is at (x, omega) (omega within ``ulps`` ulp), else None."""
        ev = self.ev
        if (
            ev is not None
            and abs(ev.omega - omega) <= ulps * np.spacing(abs(omega))
            and ev.level == self.hb.level
            and np.array_equal(ev.x, x)
        ):
            return ev
        return None

    def evaluation(self, xs: np.ndarray, ws: float) -> Evaluation:
        """The evaluation at scaled (xs, ws): the last one if it is there, else a new one."""
        x, w = np.asarray(xs, dtype=float) * self.u_ref, float(ws) * self.w_ref
        ev = self._last(x, w)
        if ev is None:
            ev = self.ev = self.hb.evaluate(x, w)
        return ev

    def evaluated(self, x: np.ndarray, omega: float) -> Evaluation:
        """The evaluation at unknowns x (m) and omega (rad/s): the last one if it is there.

        A converged solve ends with the residual evaluated at its solution, so the
        point's outputs need no new AFT. (A solve at fixed frequency works on
        ``omega / w_ref``: its evaluation may sit an ulp or two off ``omega``.)
        """
        ev = self._last(x, omega, ulps=4)
        return ev if ev is not None else self.hb.evaluate(x, omega)

    def _res(self, xs: np.ndarray, ws: float) -> np.ndarray:
        return self.evaluation(xs, ws).r / self.u_ref

    def _jw(self, xs: np.ndarray, ws: float) -> np.ndarray:
        return self.hb.residual_omega(self.evaluation(xs, ws)) * (self.w_ref / self.u_ref)

    def factor(self, xs: np.ndarray, ws: float) -> Factorization:
        """Assemble and factor dr/dx at (xs, ws); keep it as the preconditioner."""
        t0 = time.perf_counter()
        self.lu = Factorization(
            self.hb,
            self.evaluation(xs, ws),
            self._jw(xs, ws),
            single=self.single,
            reduce=self.opts.reduce_factor,
        )
        self.lu_state = (xs.copy(), ws)
        self.stats["n_factor"] += 1
        self.stats["t_factor"] += time.perf_counter() - t0
        return self.lu

    # -- the Newton solver (one per kind) ------------------------------------------------
    def _get_snes(self, kind: str) -> Newton:
        if kind in self._snes:
            return self._snes[kind]
        n = self.N + (1 if kind == "arclength" else 0)
        corr = self

        def split(a: np.ndarray) -> tuple[np.ndarray, float]:
            if kind == "arclength":
                return a[:-1], float(a[-1])
            return a, corr.w_fixed

        def function(Y: np.ndarray, out: np.ndarray) -> None:
            xs, ws = split(Y)
            r = corr._res(xs, ws)
            if kind == "arclength":
                out[:-1] = r
                out[-1] = corr.constraint.value(xs, ws)
            else:
                out[:] = r

        opts = self.opts
        newton = Newton(
            n,
            function,
            self._finite_differences(kind, n) if opts.jacobian == "fd" else self._shell_lu(kind, n),
            NewtonTest(
                tol=opts.tol,
                tol_stall=opts.tol_stall,
                max_it=opts.max_newton,
                bordered=kind == "arclength",
                stagnation=opts.stagnation,
            ),
            line_search=opts.line_search,
            ls_max_it=opts.line_search_max_it if opts.line_search == "bt" else None,
            stats=self.stats,
        )
        self._snes[kind] = newton
        return newton

    def _finite_differences(self, kind: str, n: int):
        """The linear solver of ``jacobian = "fd"``: forward differences of the (bordered)
        residual, column by column (n + 1 residual evaluations per Newton iteration, for
        comparison on small models), factored by a dense LU."""
        corr = self

        def linear(snes, ksp) -> None:
            from petsc4py import PETSc

            fd: dict[str, object] = {}

            def fvalue(y: np.ndarray) -> np.ndarray:
                xs, ws = (y[:-1], float(y[-1])) if kind == "arclength" else (y, corr.w_fixed)
                r = corr._res(xs, ws)
                if kind == "arclength":
                    return np.append(r, corr.constraint.value(xs, ws))
                return r

            class FdShell:
                def mult(self, mat, X, Y):
                    Y.getArray()[:] = fd["J"] @ X.getArray(readonly=True)

            class FdPre:
                def setUp(self, pc):
                    fd["lu"] = sla.lu_factor(fd["J"], check_finite=False)
                    corr.stats["n_factor"] += 1

                def apply(self, pc, X, Y):
                    Y.getArray()[:] = sla.lu_solve(fd["lu"], X.getArray(readonly=True))

            def fd_jacobian(snes, X, Amat, Pmat):
                y = X.getArray(readonly=True).copy()
                f0 = fvalue(y)
                J = np.empty((n, n))
                for j in range(n):
                    h = 1e-7 * max(abs(y[j]), 1.0)
                    yj = y.copy()
                    yj[j] += h
                    J[:, j] = (fvalue(yj) - f0) / h
                fd["J"] = J
                Amat.assemble()

            A = PETSc.Mat().createPython((n, n), FdShell(), comm=PETSc.COMM_SELF)
            A.setUp()
            snes.setJacobian(fd_jacobian, A, A)
            ksp.setType("preonly")
            ksp.getPC().setType("python")
            ksp.getPC().setPythonContext(FdPre())

        return linear

    def _shell_lu(self, kind: str, n: int):
        """The linear solver of the analytic Jacobian: the exact product as a shell matrix,
        preconditioned by the LU of ``dr/dx`` (:class:`Factorization`), refreshed by the
        mode's rule (newton: every iteration; lagged: GMRES, when it struggled; chord: on
        request)."""
        corr = self

        def linear(snes, ksp) -> None:
            from petsc4py import PETSc

            state: dict[str, object] = {}

            class Shell:
                def mult(self, mat, X, Y):
                    v = X.getArray(readonly=True)
                    xs, ws = state["x"], state["w"]
                    out = Y.getArray()
                    ev = corr.evaluation(xs, ws)
                    if kind == "arclength":
                        jv = corr.hb.jvp(ev, v[:-1])
                        out[:-1] = jv + state["jw"] * v[-1]
                        cx, cw = state["row"]
                        out[-1] = cx @ v[:-1] + cw * v[-1]
                    else:
                        out[:] = corr.hb.jvp(ev, v)

            class Pre:
                def setUp(self, pc):
                    xs, ws = state["x"], state["w"]
                    last_its = ksp.getIterationNumber()
                    bad = ksp.getConvergedReason() < 0
                    need = (
                        corr.lu is None
                        or corr.force_refresh
                        or corr.mode == "newton"
                        or (
                            corr.mode == "lagged" and (last_its >= corr.opts.refresh_ksp_its or bad)
                        )
                    )
                    if need:
                        corr.factor(xs, ws)
                        corr.force_refresh = False

                def apply(self, pc, X, Y):
                    r = X.getArray(readonly=True)
                    out = Y.getArray()
                    if kind == "arclength":
                        a, b = corr.lu.solve_bordered(r[:-1], r[-1], *state["row"])
                        out[:-1] = a
                        out[-1] = b
                    else:
                        out[:] = corr.lu.solve(r)

            A = PETSc.Mat().createPython((n, n), Shell(), comm=PETSc.COMM_SELF)
            A.setUp()

            def jacobian(snes, X, Amat, Pmat):
                a = X.getArray(readonly=True)
                xs, ws = (a[:-1], float(a[-1])) if kind == "arclength" else (a, corr.w_fixed)
                state["x"], state["w"] = xs.copy(), ws
                if kind == "arclength":
                    state["jw"] = corr._jw(xs, ws)
                    state["row"] = corr.constraint.row(xs, ws)
                Amat.assemble()

            snes.setJacobian(jacobian, A, A)
            opts = corr.opts
            if corr.mode == "lagged":
                ksp.setType("gmres")
                ksp.setPCSide(PETSc.PC.Side.RIGHT)
                ksp.setTolerances(rtol=opts.ksp_rtol, atol=0.0, max_it=opts.ksp_max_it)
                ksp.setGMRESRestart(opts.ksp_max_it)
            else:
                ksp.setType("preonly")
            pc = ksp.getPC()
            pc.setType("python")
            pc.setPythonContext(Pre())

        return linear

    # -- solves --------------------------------------------------------------------
    def _run(self, kind: str, y0: np.ndarray) -> tuple[np.ndarray, bool, int, int, str]:
        return self._get_snes(kind).run(y0)

    def solve_natural(self, x0: np.ndarray, omega: float) -> CorrectorResult:
        """Solve r(x, w) = 0 at fixed w from x0 (m)."""
        self.w_fixed = omega / self.w_ref
        y, ok, its, kits, why = self._run("natural", x0 / self.u_ref)
        return CorrectorResult(y * self.u_ref, omega, ok, its, kits, why)

    def solve_arclength(self, x0: np.ndarray, w0: float, con: Constraint) -> CorrectorResult:
        """Solve the bordered system from (x0, w0) with the constraint ``con`` (scaled)."""
        self.constraint = con
        y0 = np.concatenate([x0 / self.u_ref, [w0 / self.w_ref]])
        y, ok, its, kits, why = self._run("arclength", y0)
        return CorrectorResult(y[:-1] * self.u_ref, float(y[-1]) * self.w_ref, ok, its, kits, why)

    def tangent(self, xs: np.ndarray, ws: float) -> tuple[np.ndarray, float]:
        """Unit-free tangent (dxs, 1) of the branch at a point (dws = 1), from the LU there."""
        if (
            self.lu is None
            or self.lu_state is None
            or not (self.lu_state[1] == ws and np.array_equal(self.lu_state[0], xs))
        ):
            self.factor(xs, ws)
        return -self.lu.z2, 1.0

    def destroy(self) -> None:
        for newton in self._snes.values():
            newton.destroy()
        self._snes.clear()
