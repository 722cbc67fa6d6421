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
with a backtracking line search, a dense LU of the bordered Jacobian, rebuilt
every third iteration by default: :mod:`.nlmode_corrector`).

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

from ..errors import InputError, check_choice, check_int, check_range
from .epmc import TWO_PI, Epmc
from .epmc_condensed import EpmcCondensed
from .fourier import Fourier
from .nlmode_branch import POINT_ARRAYS, NlModeBranch
from .nlmode_corrector import Snes
from .ports import observation
from .system import System

log = logging.getLogger(__name__)

__all__ = [
    "linear_modes",
    "make_problem",
    "nonlinear_mode",
    "pick_mode",
    "slip_amplitude",
]


# -- the problem: every DOF or condensed onto the contacts -------------------------------
def make_problem(
    system: System,
    fourier: Fourier,
    mode: int,
    outputs: object = None,
    dc_anchor: float = 1e-3,
    space: str = "auto",
):
    """:class:`EpmcCondensed` when the damping is modal and the contacts see fewer
    coordinates than the model has ("auto"), else :class:`Epmc` (all DOFs)."""
    check_choice("space", space, ("auto", "condensed", "physical"))
    if space == "physical" or not system.n_el:
        return Epmc(system, fourier, mode, outputs, dc_anchor)
    n_s = int(system.contacts.active.sum())
    modal = system.C is None
    if not modal:
        from .linear import ModalLinear

        _, modal = ModalLinear.is_modal(system.M, system.regularised_stiffness(), system.C)
    if space == "condensed" or (modal and n_s + 1 < system.n):
        if not modal:
            raise InputError("space", space, "physical (the damping is not modal)")
        return EpmcCondensed(system, fourier, mode, outputs, dc_anchor)
    return Epmc(system, fourier, mode, outputs, dc_anchor)


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
    plateau_points: int = 6,
    jacobian_lag: int = 3,
    linear: str = "auto",
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
    backbone (completed = False), and so does an amplitude that stays within
    0.2 % over ``plateau_points`` points while the damping ratio rises by a
    fifth (an amplitude limit, checked only with ``f1`` and ``levels``: the
    levels still above it would all peak at that amplitude, where the
    synthesis is not valid; 0 turns the check off). Below the first slip
    every contact sticks and the mode is linear: one step crosses that range.
    ``jacobian_lag``: the Jacobian (and its LU) is rebuilt every that many
    Newton iterations, across points (a chord method between rebuilds: the
    LU is most of an iteration's cost; the tolerance on the residual is the
    same, so the points are as accurate); 1 rebuilds it at every iteration.
    ``linear``: "krylov" (the default where the problem is condensed on the
    contacts, :class:`EpmcCondensed`) solves each Newton step by GMRES on the
    exact Jacobian, preconditioned by the LU of an earlier one (refactorised
    only when GMRES struggles; ``jacobian_lag`` is then unused); "dense" the
    LU of the Jacobian itself (:mod:`.nlmode_corrector`).
    Where a point finds the damper out of contact, the step is halved until
    the last point lies within 2 % in amplitude below it. With ``levels``, a point is then solved at
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
    a_slip = slip_amplitude(system, mode)
    if amplitude_range is None:
        lo, hi = (float(v) for v in relative_range)
        check_range("relative_range[0]", lo, 0.0, lo_open=True)
        check_range("relative_range[1]", hi, lo, lo_open=True)
        amplitude_range = (lo * a_slip, hi * a_slip)
    a0, a1 = (float(v) for v in amplitude_range)
    check_range("amplitude_range[0]", a0, 0.0, lo_open=True)
    check_range("amplitude_range[1]", a1, a0, lo_open=True)
    n_steps = check_int("n_steps", n_steps, 1)
    rows: dict[str, list] = {k: [] for k in POINT_ARRAYS}
    lag = check_int("jacobian_lag", jacobian_lag, 1)
    snes = Snes(prob, tol, tol_stall, max_newton, lag=lag, linear=linear)
    # chord iterations converge linearly: more of them per point, same step control
    its_scale = 1.0 if lag == 1 or snes.linear == "krylov" else 2.5
    snes.set_max_it(round(max_newton * its_scale))
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
            raise _Lost(
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
            n_solves = 0
            while True:
                if len(rows["amplitude"]) >= max_points:
                    raise _Stop(f"stopped after max_points = {max_points}", False)
                n_solves += 1
                if n_solves > 5 * max_points:  # refused and halved steps: never without end
                    raise _Stop(
                        f"stopped after {n_solves - 1} corrector solves for "
                        f"{len(rows['amplitude'])} points (steps refused or halved over and "
                        "over); the backbone so far is kept",
                        True,
                    )
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
                    if Y[-1] < s_slip - 1e-9:
                        # every contact sticks below the first slip: the mode is linear
                        # there, so one step goes to the point just below it (a kink)
                        dsn = s_slip - Y[-1]
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
                    # the point exactly at the largest amplitude did not converge: the
                    # converged step past it ends the backbone, so the range is covered
                    log.info(
                        "the point at the largest amplitude %.4g did not converge; the "
                        "backbone ends at the converged step past it (%.4g)",
                        a1,
                        np.exp(Yn[-1]),
                    )
                    try:
                        record(snes.unscaled(Yn)[0], float(np.exp(Yn[-1])), its)
                    except _Lost:
                        raise _Stop(
                            f"the corrector failed at the largest amplitude {a1:.4g} and "
                            "the step past it loses contact: the backbone ends at "
                            f"{np.exp(Y[-1]):.4g}",
                            True,
                        ) from None
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
                try:
                    prev = record(snes.unscaled(Yn)[0], float(np.exp(Yn[-1])), its)
                except _Lost:
                    if Yn[-1] - Y[-1] > np.log(1.02) and ds > 2 * ds_min:
                        ds *= 0.5  # close in on the loss of contact (the last point's
                        continue  # amplitude bounds every level the synthesis can reach)
                    raise
                Y_prev, Y = Y, Yn
                hist.append(Y)
                if f_top > 0:  # only a backbone for given levels stops at a plateau
                    _plateau(rows, plateau_points)
                bar.n = round(min(max(Y[-1] - s0, 0.0), span), 6)
                bar.set_postfix_str(
                    f"{prev['freq_hz']:.4g} Hz, D {prev['damping_ratio']:.3g}", refresh=False
                )
                bar.update(0)
                grow = 1.5 if its <= 4 * its_scale else (0.7 if its > 8 * its_scale else 1.0)
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
        timings = dict(
            total=time.perf_counter() - t_start,
            aft=prob.stats["t_aft"],
            factorisations=snes.n_factor,
            krylov_its=snes.n_krylov,
        )
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

    # a point at a given amplitude is worth more iterations than a continuation step (near
    # the first slip a shakedown of the stuck contacts makes the residual rough: ~20)
    snes.set_max_it(max(snes.max_it, 30))
    for _ in range(3):
        nm = branch()
        added = 0
        for lv in sorted(set(float(v) for v in np.atleast_1d(levels))):
            try:
                s = synthesize(nm, f1v, lv)
            except InputError:
                return
            a = nm.amplitude
            if np.min(np.abs(np.log(a / s.peak_modal_amplitude))) < 1e-3:
                continue  # a point is already there (a repeated solve would duplicate it)
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


def _plateau(rows: dict[str, list], n: int) -> None:
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
        raise _Stop(
            f"the modal amplitude stalls at {a[-1]:.4g} (within 0.2 % over {n} points) while "
            f"the damping ratio rises from {d0:.3g} to {d1:.3g}: an amplitude limit (lift-off "
            "or a stop), where a larger force raises the dissipation, not the amplitude; "
            "the backbone ends here",
            False,
        )


class _Stop(Exception):
    def __init__(self, message: str, failed: bool, completed: bool = False):
        super().__init__(message)
        self.failed, self.completed = failed, completed


class _Lost(_Stop):
    """The damper has lost every contact at the point just solved (not recorded)."""
