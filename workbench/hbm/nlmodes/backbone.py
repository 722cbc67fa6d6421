"""Nonlinear modes by the extended periodic motion concept (EPMC, Krack 2015).

A negative mass-proportional damping term ``-xi M q'`` is added to the
autonomous equation of motion of the reduced model with its friction
contacts,

    M q'' + (C - xi M) q' + K q + W^T f(W q) = f_static,

so that the free motion of a damped mode becomes periodic: ``xi`` (1/s)
supplies exactly the energy the viscous damping and the friction take per
cycle. The periodic motion is expanded in the harmonic list of
:mod:`..core.fourier` (the same AFT march, contact law and preload balance as the
forced response, :mod:`..core.balance`) and continued in the modal amplitude
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
as in :mod:`..core.balance`). The Jacobian is analytic (the AFT's exact
derivative for the contacts); each point is solved by PETSc SNES (Newton
with a backtracking line search, a dense LU of the bordered Jacobian, rebuilt
every third iteration by default: :class:`.problem.BackboneCorrector`).

The point equations live in :mod:`.epmc` (:class:`Epmc` on every DOF,
:class:`EpmcCondensed` on the contact coordinates); this module chooses the
mode and the amplitude range and continues the points (PETSc SNES).

The result, :class:`NlModeBranch` (:mod:`.record`), holds per point the modal amplitude,
frequency, ``xi``, damping ratio, friction energy per element and per
cycle, contact status, the energy balance of the point, the MAC of the
harmonic-1 shape against the low-amplitude one, the share of the motion in
the higher harmonics, the output amplitudes, and ``psi`` (so that
:mod:`.synthesis` can rebuild the forced response at any force level).
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.linalg as sla

from ...errors import InputError, check_choice, check_int, check_range
from ..core.fourier import Fourier
from ..core.ports import observation
from ..core.system import System
from ..path.engine import NUMERICAL, follow
from ..path.problem import Stop
from ..path.rows import Rows
from ..path.step import StepRule
from .epmc import TWO_PI, Epmc
from .epmc_condensed import EpmcCondensed
from .problem import Backbone, BackboneCorrector
from .record import NlModeBranch

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
        from ..core.linear import ModalLinear

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
    LU of the Jacobian itself (:class:`.problem.BackboneCorrector`).
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
    lag = check_int("jacobian_lag", jacobian_lag, 1)
    snes = BackboneCorrector(prob, tol, tol_stall, max_newton, lag=lag, linear=linear)
    # chord iterations converge linearly: more of them per point, same step control
    its_scale = 1.0 if lag == 1 or snes.linear == "krylov" else 2.5
    snes.set_max_it(round(max_newton * its_scale))
    f_top = float(max(np.atleast_1d(levels))) if levels is not None and f1 is not None else 0.0
    f1v = np.asarray(f1, complex).ravel() if f1 is not None else None
    s_slip = float(np.log(0.999 * a_slip)) if system.n_el else -np.inf
    rule = StepRule.backbone(n_steps, max_points, max_change, max_fold_points, its_scale)

    from ...log import progress_bar

    span = np.log(a1) - np.log(a0)
    with progress_bar(f"nlmode {label or mode}", total=round(span, 6), unit="ln a") as bar:
        bb = Backbone(prob, snes, (a0, a1), f_top, f1v, s_slip, plateau_points, rule, bar)
        out = follow(bb, rule)
    message, failed, completed = out.message, out.failed, out.completed
    rows = bb.rows
    n_el = system.n_el
    prob_phys = prob.phys if isinstance(prob, EpmcCondensed) else prob

    def branch() -> NlModeBranch:
        shapes = dict(
            friction_energy=(0, n_el),
            status=(0, n_el),
            out_amp=(0, O.shape[0]),
            out_h1=(0, O.shape[0]),
            psi=(0, fourier.nh * system.n),
        )
        arr = rows.arrays(shapes, dict(status=np.int8, newton_its=int))
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
        if f_top > 0 and rows.n >= 2:
            _refine_at_peaks(branch, snes, bb.add, rows, f1v, levels, refine_ratio)
    except (Stop, *NUMERICAL) as e:
        log.info("refinement at the peaks stopped: %s", e)
    finally:
        snes.destroy()
    return branch()


def _refine_at_peaks(branch, snes, record, rows: Rows, f1v, levels, ratio: float) -> None:
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
            (y0, p0), (y1, p1) = rows.cols["z"][j - 1], rows.cols["z"][j]
            # the continuation parameter of the target (the physical amplitude is a_M)
            th = np.log(s.peak_modal_amplitude / a[j - 1]) / np.log(a[j] / a[j - 1])
            pt = float(np.exp(np.log(p0) + th * (np.log(p1) - np.log(p0))))
            Yg = snes.scaled(y0 + th * (y1 - y0), np.log(pt))
            Y, ok, its = snes.solve(Yg)
            if not ok:
                continue
            n_before = rows.n
            record(snes.unscaled(Y)[0], float(np.exp(Y[-1])), its)
            if rows.n == n_before:
                continue
            if not a[j - 1] < rows.cols["amplitude"][-1] < a[j]:  # off its segment: dropped
                rows.pop_last()
                continue
            rows.insert_last_at(j)  # the new point into amplitude order
            added += 1
            nm = branch()
        if not added:
            return
