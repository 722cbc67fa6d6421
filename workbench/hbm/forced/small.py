"""The compiled small-system path: the corrector of a point in one compiled call.

For systems of a few hundred harmonic unknowns or fewer (``N <=
auto_newton_limit``, where the corrector refactors every Newton iteration)
with modal damping, the work of a point (an AFT of a few elements, a small
dense LU) costs microseconds, and the Python and PETSc overhead around it
(SNES callbacks, shell matrices, array wrapping) most of the time.
:class:`SmallCorrector` is then the corrector: the same Newton iterations
as :class:`.corrector.Corrector` with SNES (the same residual, Jacobian, bt
line search and convergence test, see :mod:`.small_kernels`), run by one
compiled call per solve. ``SolverOptions(compiled="off")`` keeps the PETSc
path; tests/test_small.py checks that both give the same branch to round-off.

The kernels are compiled by numba, once per contact law: ahead of time by
``python -m workbench.hbm.forced.small_aot`` (scripts/setup.sh runs it; the module
then loads without numba) or, when that module is missing or out of date,
just in time (cached on disk).
"""

from __future__ import annotations

import logging
import time
import types

import numpy as np

from ..core.balance import Evaluation, HarmonicBalance
from ..core.options import SolverOptions
from .corrector import Corrector

log = logging.getLogger(__name__)

REASONS = {
    0: "CONVERGED_ITERATING",
    1: "CONVERGED_FNORM_ABS",
    2: "CONVERGED_SNORM_RELATIVE",
    3: "CONVERGED_SNORM_RELATIVE",
    4: "DIVERGED_MAX_IT",
    5: "DIVERGED_LOCAL_MIN",
    6: "DIVERGED_FNORM_NAN",
}
_FUNCS = (
    "coef",
    "combine",
    "evaluate",
    "residual",
    "residual_omega",
    "jacobian",
    "_norm",
    "_con_value",
    "_con_row",
    "_func",
    "solve",
    "solve_flat",
    "evaluate_flat",
)
_jit: dict[str, object] = {}


def eligible(hb: HarmonicBalance, opts: SolverOptions) -> bool:
    """Whether the compiled path can run this problem with these options."""
    if opts.compiled == "off" or opts.jacobian != "analytic" or opts.line_search != "bt":
        return False
    if hb.lin.kind != "modal" or not hb.n_el:
        return False
    mode = opts.linear_solver
    if mode == "auto":
        mode = "newton" if hb.N <= opts.auto_newton_limit else "lagged"
    return mode == "newton"


def kernels(law: str) -> tuple[object, object]:
    """The compiled ``(solve, evaluate)`` for contact law ``law`` (ahead of time, else JIT)."""
    from . import small_aot

    pair = (small_aot.load(law, "solve"), small_aot.load(law, "evaluate"))
    if pair[0] is not None and pair[1] is not None:
        return pair
    if law not in _jit:
        from numba import njit

        from ...contact.laws import get_law
        from ...contact.march import _march_py, specialise
        from . import small_kernels as K

        g = dict(K.__dict__)
        g["march"] = specialise(_march_py, get_law(law), "_march")
        for name in _FUNCS:
            f = getattr(K, name)
            copy = types.FunctionType(f.__code__, g, f"{name}_{law}", f.__defaults__)
            copy.__qualname__ = f"{name}_{law}"
            g[name] = njit(cache=True)(copy)
        _jit[law] = (g["solve_flat"], g["evaluate_flat"])
    return _jit[law]


class SmallCorrector(Corrector):
    """The corrector of a small system with the compiled Newton (same interface, no SNES)."""

    def __init__(self, hb: HarmonicBalance, opts: SolverOptions, u_ref: float, w_ref: float):
        super().__init__(hb, opts, u_ref, w_ref)
        self.mode = "compiled"
        from ...contact.laws import get_law
        from ...contact.march import MAX_PERIODS, TOL

        f, el = hb.fourier, hb.el
        self.law = el.law
        self._solve, self._evaluate = kernels(el.law)
        nz, n3, n_s, nh, nt = hb.lin.n_z, hb.n3, hb.n_s, f.nh, f.nt
        Sz = hb.Sz.toarray() if hasattr(hb.Sz, "toarray") else np.asarray(hb.Sz)
        Bz = hb.Bz.toarray() if hasattr(hb.Bz, "toarray") else np.asarray(hb.Bz)
        if hb.space == "condensed":
            V = np.zeros((n3, n_s))
            V[hb.act, np.arange(n_s)] = 1.0
        else:
            V = hb.W.toarray()
        c = np.ascontiguousarray
        self._data = (
            c(f.k, dtype=float),
            c(f.kind, dtype=np.int64),
            c(hb.lin.wn**2, dtype=float),
            c(hb.lin.zeta * hb.lin.wn, dtype=float),
            c(f.E, dtype=float),
            c(f.P, dtype=float),
        )
        self._maps = (c(Sz, dtype=float), c(Bz, dtype=float), c(V, dtype=float))
        self._el = tuple(c(a, dtype=float) for a in (el.mu, el.kt1, el.kt2, el.kn, el.n0))
        self._el += (c(el.lp, dtype=float),)  # the law's own parameters per element
        self._el += (c(hb.kc, dtype=float), c(hb.anchor, dtype=float))
        self._el += (c(el.active, dtype=np.bool_),)
        self._march = (bool(f.has_dc), int(get_law(el.law).n_state), float(TOL), int(MAX_PERIODS))
        n_el = hb.n_el
        self._ws = (
            np.zeros((nh, n3)),  # U
            np.zeros((nh, n3)),  # G
            np.zeros((n_el, 3, nh, 3, nh)),  # D
            np.zeros((n_el, nt, 3)),  # ut
            np.zeros((n_el, nt, 3)),  # f
            np.zeros((n_el, 3, nh)),  # F
            np.zeros((n_el, 3, nh, 3 * nh)),  # J
            np.zeros(n_el, dtype=np.int64),  # n_slip
            np.zeros(n_el, dtype=np.int64),  # n_sep
            np.zeros((n_el, nt), dtype=np.bool_),  # contact
            np.zeros(n_el, dtype=np.int64),  # periods
            np.zeros(n_el, dtype=np.bool_),  # converged
            np.zeros((nh, nz)),  # Yz
            np.zeros(nh * n_s),  # r
            np.zeros((nh, nz)),  # T
        )
        self._lsn = {k: np.ones(2) for k in ("natural", "arclength")}
        self._info = np.zeros(5, dtype=np.int64)
        self._dummy = np.zeros(self.N)

    def _run(self, kind: str, y0: np.ndarray) -> tuple[np.ndarray, bool, int, int, str]:
        hb, opts = self.hb, self.opts
        n = self.N + (1 if kind == "arclength" else 0)
        y = np.zeros(n)
        d = self._dummy
        kcon, cx, cw, c0, mx, mw, xc, wc, ds = 0, d, 0.0, 0.0, d, 0.0, d, 0.0, 1.0
        if kind == "arclength":
            con = self.constraint
            kcon = 2 if con.sphere else 1
            cx, cw, c0 = np.ascontiguousarray(con.cx, dtype=float), float(con.cw), float(con.c0)
            mx = np.ascontiguousarray(np.broadcast_to(con.mx, (self.N,)), dtype=float)
            mw = float(con.mw)
            if con.sphere:
                xc, wc, ds = np.ascontiguousarray(con.xc, dtype=float), float(con.wc), con.ds
        t0 = time.perf_counter()
        reason = self._solve(
            np.ascontiguousarray(y0, dtype=float), kcon, float(self.w_fixed),
            *self._data, np.ascontiguousarray(hb.Pz, dtype=float), *self._maps,
            *self._el, *self._march, *self._ws, self.u_ref, self.w_ref,
            cx, cw, c0, mx, mw, xc, wc, float(ds),
            float(opts.tol), float(opts.tol_stall), int(opts.stagnation), int(opts.max_newton),
            int(opts.line_search_max_it), self._lsn[kind], y, self._info,
        )  # fmt: skip
        dt = time.perf_counter() - t0
        its, own, nfun, nstall = (int(v) for v in self._info[1:5])
        st = self.stats
        st["t_snes"] += dt
        st["n_snes"] += 1
        st["n_factor"] += its
        st["n_stalled"] += nstall
        hb.stats["n_residual"] += nfun
        hb.stats["t_residual"] += dt
        hb.stats["n_jacobian"] += its
        ok = bool(own and reason in (1, 2) and np.all(np.isfinite(y)))
        name = REASONS.get(int(reason), str(reason))
        if not ok:
            st["n_failed"] += 1
        self._keep_evaluation(y, kind)
        return y, ok, its, 0, name

    def evaluation(self, xs: np.ndarray, ws: float) -> Evaluation:
        """The evaluation at scaled (xs, ws): the last one if it is there, else a compiled one."""
        x, w = np.asarray(xs, dtype=float) * self.u_ref, float(ws) * self.w_ref
        ev = self._last(x, w)
        return ev if ev is not None else self._compiled_evaluation(x, w)

    def evaluated(self, x: np.ndarray, omega: float) -> Evaluation:
        """The evaluation at unknowns x (m) and omega (rad/s): the last one if it is there
        (within 4 ulp of omega), else one by the compiled kernel (no numba needed)."""
        ev = self._last(x, omega, ulps=4)
        return ev if ev is not None else self._compiled_evaluation(x, omega)

    def _compiled_evaluation(self, x: np.ndarray, w: float) -> Evaluation:
        hb = self.hb
        self._evaluate(
            np.ascontiguousarray(x, dtype=float), float(w), *self._data,
            np.ascontiguousarray(hb.Pz, dtype=float), *self._maps, *self._el, *self._march,
            *self._ws,
        )  # fmt: skip
        hb.stats["n_residual"] += 1
        return self._keep(np.array(x, dtype=float), float(w))

    def _keep_evaluation(self, y: np.ndarray, kind: str) -> None:
        """The kernel's last evaluation (at ``y``) as an :class:`Evaluation` (no new AFT)."""
        ws = float(y[-1]) if kind == "arclength" else self.w_fixed
        self._keep(y[: self.N] * self.u_ref, ws * self.w_ref)

    def _keep(self, x: np.ndarray, w: float) -> Evaluation:
        """The workspace's evaluation at (x, w) as an :class:`Evaluation` (copied out)."""
        from ..core.aft import AftResult

        hb = self.hb
        f = hb.fourier
        U, G, D, ut, fs, F, J, n_slip, n_sep, contact, periods, _, Yz, r, _ = self._ws
        hb.stats["aft_periods_max"] = max(hb.stats["aft_periods_max"], int(periods.max(initial=0)))
        aft = AftResult(
            F=np.ascontiguousarray(F.transpose(2, 0, 1)),
            J=J.reshape(hb.n_el, 3, f.nh, 3, f.nh).copy(),
            u=ut.copy(),
            f=fs.copy(),
            n_slip=n_slip.copy(),
            n_sep=n_sep.copy(),
            contact=contact.copy(),
            periods=periods.copy(),
        )
        self.ev = Evaluation(x, w, hb.level, U.copy(), G.copy(), D.copy(), aft, Yz.copy(), r.copy())
        return self.ev

    def destroy(self) -> None:
        """Nothing to free (no PETSc objects)."""


def make_corrector(hb: HarmonicBalance, opts: SolverOptions, u_ref: float, w_ref: float):
    """The compiled corrector where :func:`eligible`, else the PETSc SNES one."""
    if eligible(hb, opts):
        try:
            return SmallCorrector(hb, opts, u_ref, w_ref)
        except ImportError as e:  # numba missing: the PETSc path still works
            log.warning("compiled path unavailable (%s): PETSc corrector", e)
    return Corrector(hb, opts, u_ref, w_ref)
