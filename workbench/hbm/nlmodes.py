"""Nonlinear modes by the extended periodic motion concept (EPMC, Krack 2015).

A negative mass-proportional damping term ``-xi M q'`` is added to the
autonomous equation of motion of the reduced model with its friction
contacts,

    M q'' + (C - xi M) q' + K q + W^T f(W q) = f_static,

so that the free motion of a damped mode becomes periodic: ``xi`` (1/s)
supplies exactly the energy the viscous damping and the friction take per
cycle. The periodic motion is expanded in the harmonic list of
:mod:`.fourier` (the same AFT march, contact law and preload balance as the
forced response, :mod:`.balance`) and continued in the modal amplitude
``a`` (sqrt(kg) m): the harmonics are ``Q = a psi`` with the mass
normalisation of the harmonic-1 shape and a phase condition,

    psi_c1^T M psi_c1 + psi_s1^T M psi_s1 = 1,   psi_s1^T M phi = 0

(``phi`` the mass-normalised linear mode with every contact stuck). The
unknowns of one point are ``psi`` (all DOFs, all harmonics), ``omega``
(rad/s) and ``xi``; the modal damping ratio is ``D = xi / (2 omega)``, the
system's own viscous damping included (in the linear limit ``D`` is the
modal ratio ``zeta`` of the mode, and ``omega`` its stuck frequency).

Residual (physical space, per unit modal amplitude), for harmonic ``k``
with ``A = K_r - (k w)^2 M`` and ``B = k w (C - xi M)``::

    Rc_k = A psi_c + B psi_s + W^T Gc_k / a,   Rs_k = A psi_s - B psi_c + W^T Gs_k / a

plus ``K_r psi_0 + W^T (G_0 - f(0)) / a`` for harmonic 0 (``G = f - K_c u``
as in :mod:`.balance`). The Jacobian is analytic (the AFT's exact
derivative for the contacts); each point is solved by PETSc SNES (Newton
with a backtracking line search, a dense LU of the bordered Jacobian).

The point equations live in :mod:`.epmc` (:class:`Epmc` on every DOF,
:class:`EpmcCondensed` on the contact coordinates); this module chooses the
mode and the amplitude range and continues the points (PETSc SNES).

The result, :class:`NlModeBranch` (:mod:`.nlmode_branch`), holds per point the modal amplitude,
frequency, ``xi``, damping ratio, friction energy per element and per
cycle, contact status, the energy balance of the point, the MAC of the
harmonic-1 shape against the low-amplitude one, the share of the motion in
the higher harmonics, the output amplitudes, and ``psi`` (so that
:mod:`.synthesis` can rebuild the forced response at any force level).
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np
import scipy.linalg as sla

from ..errors import InputError, check_int, check_range
from .balance import observation
from .epmc import TWO_PI, Epmc, make_problem
from .epmc_condensed import EpmcCondensed
from .fourier import Fourier
from .nlmode_branch import POINT_ARRAYS, NlModeBranch
from .system import System

log = logging.getLogger(__name__)

__all__ = [
    "Epmc",
    "EpmcCondensed",
    "NlModeBranch",
    "linear_modes",
    "make_problem",
    "nonlinear_mode",
    "pick_mode",
    "slip_amplitude",
]


# -- the corrector: PETSc SNES with the dense analytic Jacobian ------------------------
class _Snes:
    """Newton (SNES, backtracking line search, dense LU) on the bordered system.

    Unknowns ``Y = [y / scale, s]`` with ``s = ln a``; equations
    ``[r(y; e^s) * row_scale, c . (Y - Yp)]``: the constraint ``c`` is ``e_s``
    for a point at a given amplitude, or the secant for a pseudo-arc-length
    step (which passes a fold of the backbone in amplitude).
    """

    def __init__(
        self, prob: Epmc, tol: float, tol_stall: float, max_it: int, line_search: str = "bt"
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
        del po[f"{prefix}snes_linesearch_type"]

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


# -- choosing the mode and the amplitude range -------------------------------------------
def linear_modes(system: System) -> tuple[np.ndarray, np.ndarray]:
    """(w (rad/s), Phi mass-normalised) of the linear system with every contact stuck."""
    lam, phi = sla.eigh(system.regularised_stiffness(), system.M)
    return np.sqrt(np.clip(lam, 0.0, None)), phi


def pick_mode(system: System, f1: object, band_hz: tuple[float, float] | None = None) -> int:
    """The stuck mode the excitation ``f1`` drives most (in ``band_hz`` if given).

    Score ``|phi_j^H f1| / w_j^2``: the static modal response to the force.
    """
    w, phi = linear_modes(system)
    a = np.asarray(f1, dtype=complex).ravel()
    if a.shape != (system.n,):
        raise InputError("f1", f"shape {a.shape}", f"{system.n} complex amplitudes (N)")
    score = np.abs(phi.T @ a) / np.maximum(w, 1e-300) ** 2
    if band_hz is not None:
        f = w / TWO_PI
        inside = (f >= band_hz[0]) & (f <= band_hz[1])
        if inside.any():
            score = np.where(inside, score, -1.0)
    return int(np.argmax(score))


def slip_amplitude(system: System, mode: int) -> float:
    """Modal amplitude (sqrt(kg) m) at which the first element slips or lifts in the stuck mode."""
    if system.contacts is None or not system.n_el:
        return 1.0
    _, phi = linear_modes(system)
    el = system.contacts
    u = np.asarray(el.W @ phi[:, mode]).reshape(el.n_el, 3)
    cand = []
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = el.mu * el.n0 / (el.kt1 * np.abs(u[:, 0]))
        t2 = el.mu * el.n0 / (el.kt2 * np.abs(u[:, 1]))
        nn = el.n0 / (el.kn * np.abs(u[:, 2]))
    for v in (t1, t2, nn):
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            cand.append(float(v.min()))
    return min(cand) if cand else 1.0


# -- the continuation ---------------------------------------------------------------------
def nonlinear_mode(
    system: System,
    mode: int | None = None,
    amplitude_range: tuple[float, float] | None = None,
    relative_range: tuple[float, float] = (0.05, 300.0),
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    outputs: object = None,
    output_names: tuple[str, ...] | None = None,
    f1: object = None,
    band_hz: tuple[float, float] | None = None,
    n_steps: int = 40,
    max_points: int = 400,
    tol: float = 1e-10,
    tol_stall: float = 1e-7,
    max_newton: int = 12,
    max_change: float = 0.25,
    dc_anchor: float = 1e-3,
    space: str = "auto",
    levels: object = None,
    max_fold_points: int = 80,
    refine_ratio: float = 1.02,
    label: str = "",
) -> NlModeBranch:
    """The backbone of one nonlinear mode, continued in modal amplitude.

    ``mode``: index of the stuck linear mode to follow (default: the one
    ``f1`` drives most in ``band_hz``, see :func:`pick_mode`, else mode 0).
    ``amplitude_range`` (sqrt(kg) m), or ``relative_range`` times the modal
    amplitude of the first slip (or lift-off) in the stuck mode. ``n_steps``
    sets the first step (``ln(a1/a0) / n_steps``). Steps in ``ln a`` with a
    secant predictor; where they stall (a fold of the backbone in amplitude),
    pseudo-arc-length steps in ``(psi, w, xi, ln a)`` pass it (a step that
    lands back on a point already computed is refused); the step adapts to
    the Newton iterations and to ``max_change`` (largest relative change of
    frequency or damping ratio per step). With ``f1`` and ``levels`` (the
    excitation levels to synthesise), the backbone stops once its dissipation
    ``a xi w`` exceeds twice the largest level's modal force
    ``|psi_1^H f1|``: every level's peak is then inside it. A fold that the
    amplitude does not pass again within ``max_fold_points`` points ends the
    backbone (completed = False). With ``levels``, a point is then solved at
    each level's synthesised peak where the backbone's segment there spans
    more than ``refine_ratio`` in amplitude. Never raises for a failed solve:
    the branch says ``failed`` and keeps its points.
    """
    t_start = time.perf_counter()
    fourier = Fourier(tuple(harmonics), nt or 0)
    if mode is None:
        mode = pick_mode(system, f1, band_hz) if f1 is not None else 0
    O = observation(system, outputs)
    names = tuple(output_names) if output_names else tuple(f"y{j}" for j in range(O.shape[0]))
    if len(names) != O.shape[0]:
        raise InputError("output_names", list(names), f"{O.shape[0]} names (one per output)")
    prob = make_problem(system, fourier, mode, O, dc_anchor, space)
    if amplitude_range is None:
        a_slip = slip_amplitude(system, mode)
        lo, hi = (float(v) for v in relative_range)
        check_range("relative_range[0]", lo, 0.0, lo_open=True)
        check_range("relative_range[1]", hi, lo, lo_open=True)
        amplitude_range = (lo * a_slip, hi * a_slip)
    a_slip = slip_amplitude(system, mode)
    a0, a1 = (float(v) for v in amplitude_range)
    check_range("amplitude_range[0]", a0, 0.0, lo_open=True)
    check_range("amplitude_range[1]", a1, a0, lo_open=True)
    n_steps = check_int("n_steps", n_steps, 1)
    rows: dict[str, list] = {k: [] for k in POINT_ARRAYS}
    snes = _Snes(prob, tol, tol_stall, max_newton)
    message, failed, completed = "", False, False
    s0, s1 = np.log(a0), np.log(a1)
    phi1_ref = None
    f_top = float(max(np.atleast_1d(levels))) if levels is not None and f1 is not None else 0.0
    f1v = np.asarray(f1, complex).ravel() if f1 is not None else None
    s_slip = float(np.log(0.999 * a_slip)) if system.n_el else -np.inf

    ys: list[tuple[np.ndarray, float]] = []  # the unknowns of every recorded point

    def record(y: np.ndarray, a: float, its: int) -> dict[str, Any]:
        nonlocal phi1_ref
        y_unknowns = (y.copy(), float(a))
        y, a = prob.physical(y, a)
        pt = prob.point(y, a, phi1_ref)
        if phi1_ref is None:
            phi1_ref = pt["phi1"]
        if pt["lost"]:
            raise _Stop(
                f"the damper has lost contact at modal amplitude {a:.4g}: a singular "
                "state; the backbone ends here",
                False,
            )
        for k in POINT_ARRAYS:
            if k != "newton_its":
                rows[k].append(pt[k])
        rows["newton_its"].append(its)
        ys.append(y_unknowns)
        if (
            f_top > 0
            and a * pt["xi"] * TWO_PI * pt["freq_hz"] > 2.0 * f_top * abs(np.conj(pt["phi1"]) @ f1v)
            and np.any(pt["status"] > 0)
        ):
            raise _Stop(
                f"covers the largest level ({f_top:g}): its peak is below modal amplitude {a:.4g}",
                False,
                completed=True,
            )
        return pt

    from ..log import progress_bar

    N = prob.n_unknowns - 2
    span = s1 - s0
    # metric of the arc length: the shape relative to its size, frequency and xi relative to
    # the linear frequency (a change of a third counts as the whole amplitude range), ln a
    # relative to the range
    mw = np.empty(N + 3)
    mw[:N] = 1.0 / max(float(np.linalg.norm(prob.linear_guess()[:N])), 1e-300)
    # the mean position does not count (as dc_weight = 0 in the FRF): a stuck slider's
    # offset jumps where slip starts
    mw[:N][prob.dc_mask()[:N]] = 0.0
    mw[N] = mw[N + 1] = 3.0
    mw[N + 2] = 1.0 / span
    ds = 1.0 / n_steps
    ds_max, ds_min = 2.0 / n_steps, 1e-5
    cos_max = np.cos(np.radians(30.0))

    def norm(v: np.ndarray) -> float:
        return float(np.sqrt(np.sum((mw * v) ** 2)))

    def w_d(Y: np.ndarray) -> tuple[float, float]:
        y, _ = snes.unscaled(Y)
        return y[N], y[N + 1] / (2 * y[N])

    try:
        with progress_bar(f"nlmode {label or mode}", total=round(span, 6), unit="ln a") as bar:
            Y, ok, its = snes.solve(snes.scaled(prob.linear_guess(), s0))
            if not ok:
                raise _Stop(f"the corrector failed at the first amplitude {a0:.4g}", True)
            prev = record(snes.unscaled(Y)[0], a0, its)
            Y_prev: np.ndarray | None = None
            turns = 0
            arc = 0  # > 0: steps left in pseudo-arc-length mode (a fold in amplitude)
            hist = [Y]
            s_top, since_top = float(Y[-1]), 0
            while True:
                if len(rows["amplitude"]) >= max_points:
                    raise _Stop(f"stopped after max_points = {max_points}", False)
                if Y_prev is None:
                    t = np.zeros(N + 3)
                    t[-1] = span  # along ln a: the linear mode does not change
                else:
                    t = (Y - Y_prev) / norm(Y - Y_prev)
                if arc:  # the plane normal to the secant, a predictor along it
                    Yp = Y + ds * t
                    Yn, ok, its = snes.solve(Yp, mw**2 * t, Yp)
                else:  # the next amplitude, the secant extrapolated to it as predictor
                    dsn = ds * span
                    if Y[-1] < s_slip - 1e-9 < Y[-1] + dsn:
                        dsn = s_slip - Y[-1]  # a point just below the first slip (a kink)
                    Yp = Y + t * (dsn / t[-1]) if t[-1] > 1e-12 * span else Y.copy()
                    Yp[-1] = Y[-1] + dsn
                    Yn, ok, its = snes.solve(Yp)
                if ok:
                    (w0, d0), (w1, d1) = w_d(Y), w_d(Yn)
                    change = max(abs(w1 - w0) / w0, abs(d1 - d0) / max(abs(d0), 1e-3))
                    step = Yn - Y
                    cosang = float(np.sum(mw**2 * step * t)) / max(norm(step), 1e-300)
                    if (
                        (change > max_change or (arc and cosang < cos_max))
                        and ds > 2 * ds_min
                        and turns < 4
                    ):
                        ok = False
                        turns += 1
                    elif cosang < 0.0 and Y_prev is not None:
                        ok = False  # back along the branch behind us: never accepted
                    elif len(hist) > 2 and min(norm(Yn - h) for h in hist[:-2]) < 0.3 * ds:
                        ok = False  # retracing the branch already computed
                if not ok:
                    ds *= 0.5
                    if not arc and ds < 1e-3 / n_steps and Y_prev is not None:
                        arc, ds = 8, 1.0 / n_steps  # natural stepping stalls: a fold?
                        continue
                    if ds < ds_min:
                        raise _Stop(
                            f"the corrector failed after modal amplitude "
                            f"{np.exp(Y[-1]):.4g} even with the smallest step; the backbone "
                            "so far is kept",
                            True,
                        )
                    continue
                turns = 0
                if Yn[-1] >= s1:  # the last point exactly at the largest amplitude
                    th = (s1 - Y[-1]) / (Yn[-1] - Y[-1])
                    Yg = Y + th * (Yn - Y)
                    Yg[-1] = s1
                    Ye, ok_e, its_e = snes.solve(Yg)
                    if ok_e:
                        record(snes.unscaled(Ye)[0], a1, its_e)
                    break
                if Yn[-1] < s0:
                    raise _Stop("the backbone turned back below the smallest amplitude", False)
                if arc:  # back to stepping in amplitude once it increases again
                    arc = arc - 1 if Yn[-1] > Y[-1] else 8
                    if Yn[-1] < s_top - np.log(2.0):
                        raise _Stop(
                            f"the backbone folds back in amplitude after {np.exp(s_top):.4g} "
                            "and does not turn again within a factor 2 (the mode changes "
                            "character, or the free damper's mean position does): it ends "
                            "here",
                            False,
                        )
                if Yn[-1] > s_top:
                    s_top, since_top = float(Yn[-1]), 0
                else:
                    since_top += 1
                    if since_top > max_fold_points:
                        raise _Stop(
                            f"the backbone folds back in amplitude after {np.exp(s_top):.4g} "
                            f"and has not passed it again in {max_fold_points} points (the "
                            "mode changes character, or the free damper's mean position "
                            "does): it ends here",
                            False,
                        )
                Y_prev, Y = Y, Yn
                hist.append(Y)
                prev = record(snes.unscaled(Y)[0], float(np.exp(Y[-1])), its)
                bar.n = round(min(max(Y[-1] - s0, 0.0), span), 6)
                bar.set_postfix_str(
                    f"{prev['freq_hz']:.4g} Hz, D {prev['damping_ratio']:.3g}", refresh=False
                )
                bar.update(0)
                grow = 1.5 if its <= 4 else (0.7 if its > 8 else 1.0)
                ds = float(np.clip(ds * grow, ds_min, ds_max))
            completed = True
    except _Stop as stop:
        message, failed, completed = str(stop), stop.failed, stop.completed
        (log.warning if failed else log.info)("%s", message)
    except (np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError) as e:
        failed = True
        message = f"stopped by a numerical error: {type(e).__name__}: {e}"
        log.warning("%s", message)
    n_el = system.n_el
    prob_phys = prob.phys if isinstance(prob, EpmcCondensed) else prob

    def branch() -> NlModeBranch:
        arr: dict[str, np.ndarray] = {}
        shapes = dict(
            friction_energy=(0, n_el),
            status=(0, n_el),
            out_amp=(0, O.shape[0]),
            out_h1=(0, O.shape[0]),
            psi=(0, fourier.nh * system.n),
        )
        for k, v in rows.items():
            arr[k] = np.array(v) if v else np.zeros(shapes.get(k, (0,)))
        arr["status"] = arr["status"].astype(np.int8)
        arr["newton_its"] = arr["newton_its"].astype(int)
        timings = dict(total=time.perf_counter() - t_start, aft=prob.stats["t_aft"])
        return NlModeBranch(
            mode=mode,
            f_stuck_hz=prob.w_lin / TWO_PI,
            linear_hz=prob.wn / TWO_PI,
            harmonics=fourier.harmonics,
            nt=fourier.nt,
            n=system.n,
            output_names=names,
            completed=completed,
            failed=failed,
            message=message or ("reached the largest amplitude" if completed else ""),
            timings=timings,
            label=label,
            lin_phi=prob_phys.phi_all,
            lin_c=prob_phys.c_all,
            obs=O,
            **arr,
        )

    try:
        if f_top > 0 and len(ys) >= 2:
            _refine_at_peaks(branch, snes, record, rows, ys, f1v, levels, refine_ratio)
    except (_Stop, np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError) as e:
        log.info("refinement at the peaks stopped: %s", e)
    finally:
        snes.destroy()
    return branch()


def _refine_at_peaks(branch, snes, record, rows, ys, f1v, levels, ratio: float) -> None:
    """Add solved points at the synthesised peak of every level where the backbone is coarse.

    For each level (up to three passes) the peak's modal amplitude is found
    on the current backbone; if its segment spans more than ``ratio`` in
    amplitude and increases monotonically, the point at the peak's
    amplitude is solved (predictor: the segment's unknowns interpolated in
    ``ln a``) and inserted in order. The synthesis is then exact to the
    point solved, not to an interpolation over a coarse segment.
    """
    from .synthesis import synthesize

    for _ in range(3):
        nm = branch()
        added = 0
        for lv in sorted(set(float(v) for v in np.atleast_1d(levels))):
            try:
                s = synthesize(nm, f1v, lv)
            except InputError:
                return
            a = nm.amplitude
            j = int(np.searchsorted(a, s.peak_modal_amplitude))
            if not 0 < j < a.size or a[j] / a[j - 1] <= ratio or np.any(np.diff(a[: j + 1]) <= 0):
                continue
            (y0, p0), (y1, p1) = ys[j - 1], ys[j]
            # the continuation parameter of the target (the physical amplitude is a_M)
            th = np.log(s.peak_modal_amplitude / a[j - 1]) / np.log(a[j] / a[j - 1])
            pt = float(np.exp(np.log(p0) + th * (np.log(p1) - np.log(p0))))
            Yg = snes.scaled(y0 + th * (y1 - y0), np.log(pt))
            Y, ok, its = snes.solve(Yg)
            if not ok:
                continue
            n_before = len(rows["amplitude"])
            record(snes.unscaled(Y)[0], float(np.exp(Y[-1])), its)
            if len(rows["amplitude"]) == n_before:
                continue
            if not a[j - 1] < rows["amplitude"][-1] < a[j]:  # off its segment: dropped
                for key in rows:
                    rows[key].pop()
                ys.pop()
                continue
            for key in rows:  # move the new point into amplitude order
                rows[key].insert(j, rows[key].pop())
            ys.insert(j, ys.pop())
            added += 1
            nm = branch()
        if not added:
            return


class _Stop(Exception):
    def __init__(self, message: str, failed: bool, completed: bool = False):
        super().__init__(message)
        self.failed, self.completed = failed, completed
