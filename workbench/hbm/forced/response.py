"""Frequency response curves: predictor, corrector, step rule and stop rule in one short loop.

:func:`frequency_response` solves the first point at the band start with
the frequency fixed, then follows the branch with pseudo-arc-length
continuation: a secant (or tangent) predictor of length ``ds`` in the
normalised metric ``z = (x / xi, w / band)`` (``xi`` the largest solution
norm met so far, so amplitudes and frequency both count), the SNES
corrector on the bordered system, an adaptive step (aimed at
``target_newton`` iterations, halved on failure or when the curve turns
by more than ``max_angle_deg``), until the frequency leaves the band; the
last point is put exactly on the band end. Turning points pass because
the frequency is an unknown. ``continuation = "frequency"`` steps the
frequency instead (it stops at the first turning point, for comparison).

At every accepted point: outputs, contact status and friction energies,
the energy balance, and Hill's stability. On any failure (the corrector
cannot converge even with the smallest step, the damper loses contact)
the loop stops, and the branch computed so far is returned with
``failed = True`` and a message.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import numpy as np

from ...errors import InputError, check_range
from ..core.balance import HarmonicBalance
from ..core.fourier import Fourier, default_nt
from ..core.options import SolverOptions
from ..core.ports import observation
from ..core.system import System
from ..path.engine import NUMERICAL, follow, norm
from ..path.problem import LostContact, Solution, Stop
from ..path.rows import Rows
from ..path.step import StepRule
from ..stability.along_path import HOW_NONE, StabilityPath
from ..stability.hill import STABLE, UNKNOWN
from .branch import _ARRAYS, Branch
from .corrector import Constraint, Corrector
from .peak import insert_peaks, refine_peaks
from .small import make_corrector

log = logging.getLogger(__name__)

TWO_PI = 2.0 * np.pi
_DTYPES = dict(
    stable=bool, stability=np.int8, stability_how=np.int8, status=np.int8, newton_its=int
)


class ForcedResponse:
    """The forced response at one level as a path problem (:mod:`..path.engine`).

    Unknowns ``x`` (m) and ``w`` (rad/s), scaled ``y = (x / u_ref, w / w_ref)``.
    Metric: ``|dy|^2 = sum (a_j dy_j)^2`` with ``a = (c_j / xi, 1 / band)``: the
    unknowns relative to the largest solution norm met so far (``c_j =
    dc_weight`` for the mean components, 1 otherwise) and the frequency
    relative to the band. A point's row: outputs, contact status, energies,
    Hill's verdict (:class:`..stability.along_path.StabilityPath`).
    """

    def __init__(self, hb, corr, opts, level, band_hz, u_ref, path, timings, bar, progress):
        self.hb, self.corr, self.opts, self.level = hb, corr, opts, level
        self.f_lo, self.f_hi = band_hz
        self.start, self.end = TWO_PI * self.f_lo, TWO_PI * self.f_hi
        self.u_ref, self.w_ref = u_ref, corr.w_ref
        self.path, self.timings, self.bar, self.progress = path, timings, bar, progress
        self.rows = Rows(_ARRAYS)
        self.band_s = (self.end - self.start) / self.start
        self.xi = 1e-300  # the largest scaled solution norm so far
        self.N = hb.N
        self.cw = np.ones(self.N)
        if hb.fourier.has_dc:
            self.cw[: hb.n_s] = opts.dc_weight

    # -- the corrector, in scaled variables ------------------------------------------
    def y_of(self, x: np.ndarray, w: float) -> np.ndarray:
        return np.concatenate([x / self.u_ref, [w / self.w_ref]])

    def _sol(self, res) -> Solution:
        y = self.y_of(res.x, res.omega) if res.converged else None
        return Solution(y, res.omega, res.converged, res.its, res.reason, res.x)

    def first_point(self) -> Solution:
        """Frequency fixed at the band start; the level raised in steps if need be."""
        hb, corr, w0 = self.hb, self.corr, self.start
        res = corr.solve_natural(hb.stuck_solution(w0), w0)
        if not res.converged and self.level > 0:
            res = _ramp_level(hb, corr, w0, self.level)
        if not res.converged:
            raise Stop(
                f"the corrector failed at the band start f = {self.f_lo:.6g} Hz "
                f"(SNES: {res.reason})",
                failed=True,
            )
        self.add(res.x, w0, res.its)
        return Solution(self.y_of(res.x, w0), w0, True, res.its, res.reason, res.x)

    def metric(self) -> np.ndarray:
        xi = max(self.xi, 1e-300)
        return np.concatenate([self.cw / xi, [1.0 / self.band_s]])

    def tangent(self, p: Solution) -> np.ndarray:
        tx, tw = self.corr.tangent(p.raw / self.u_ref, p.param / self.w_ref)
        return np.concatenate([tx, [tw]])

    def first_direction(self, p: Solution, m: np.ndarray) -> np.ndarray:
        """The tangent at the first point, frequency increasing."""
        t = self.tangent(p)
        t /= norm(t, m)
        return t

    def _constraint(self, t, m, yp, center=None, ds=0.0) -> Constraint:
        nx = self.N
        return Constraint(t[:nx], t[nx], m[:nx] ** 2, m[nx] ** 2, yp[:nx], yp[nx], center, ds)

    def _arclength(self, y0: np.ndarray, con: Constraint) -> Solution:
        nx = self.N
        return self._sol(self.corr.solve_arclength(y0[:nx] * self.u_ref, y0[nx] * self.w_ref, con))

    def solve_plane(self, y0, yp, t, m) -> Solution:
        return self._arclength(y0, self._constraint(t, m, yp))

    def solve_sphere(self, p, yp, t, m, ds) -> Solution:
        nx = self.N
        return self._arclength(yp, self._constraint(t, m, yp, (p.y[:nx], p.y[nx]), ds))

    def solve_at(self, guess: np.ndarray, param: float) -> Solution:
        return self._sol(self.corr.solve_natural(guess, param))

    def natural_step(self, p: Solution, prev: Solution | None, t, ds: float) -> Solution:
        """Frequency stepping: ``ds`` in rad/s, the secant extrapolated as the guess."""
        x, w = p.raw, p.param
        wn = min(w + ds, self.end)
        guess = (
            x
            if prev is None or self.opts.predictor == "constant"
            else x + (x - prev.raw) * (wn - w) / (w - prev.param)
        )
        return self.solve_at(guess, wn)

    def end_guess(self, p: Solution, q: Solution) -> np.ndarray:
        return p.raw + (self.end - p.param) / (q.param - p.param) * (q.raw - p.raw)

    def change(self, p: Solution, q: Solution) -> float:
        """Not watched: the forced response's steps are held by angle and correction."""
        return 0.0

    def refresh(self) -> None:
        self.corr.force_refresh = True

    def after_point(self) -> None:
        """Nothing to check: the row and the progress bar are done in :meth:`record`."""

    def record(self, p: Solution, at_end: bool = False) -> None:
        self.add(p.raw, p.param, p.its)

    # -- one row per point -------------------------------------------------------------
    def add(self, x: np.ndarray, w: float, its: int) -> None:
        """Record the point (x, w) solved in ``its`` Newton iterations."""
        hb, corr, opts, timings = self.hb, self.corr, self.opts, self.timings
        t0 = time.perf_counter()
        ev = corr.evaluated(x, w)
        pd = hb.point_data(ev, n_fine=opts.n_fine)
        timings["post"] += time.perf_counter() - t0
        if pd.lost_contact:
            raise LostContact(
                f"the damper has lost contact at f = {w / TWO_PI:.6g} Hz: at some instant of the "
                "period no closed contact holds a body that only its contacts support (a "
                "singular state); lower the excitation or raise the preload",
                failed=True,
            )
        if self.path is not None:
            verdict, max_real, how = self.path.at_point(ev)
        else:
            verdict, max_real, how = UNKNOWN, float("nan"), HOW_NONE
        self.rows.add(
            freq_hz=w / TWO_PI,
            stable=verdict == STABLE,
            stability=verdict,
            stability_how=how,
            newton_its=its,
            energy_residual=pd.energy_residual,
            accuracy=pd.accuracy,
            out_amp=pd.out_amp,
            out_h1=pd.out_h1,
            out_rms=pd.out_rms,
            out_harm=pd.out_harm,
            status=pd.status,
            friction_energy=pd.friction_energy,
            x=x.copy(),
            work_ext=pd.work_ext,
            work_visc=pd.work_visc,
            work_friction=pd.work_friction,
            work_normal=pd.work_normal,
            max_floquet_real=max_real,
        )
        xd = x / self.u_ref
        if hb.fourier.has_dc:
            xd = xd.copy()
            xd[: hb.n_s] *= opts.dc_weight
        self.xi = max(self.xi, float(np.linalg.norm(xd)))
        n = self.rows.n
        f, f_lo, f_hi = w / TWO_PI, self.f_lo, self.f_hi
        self.bar.n = round(min(max(f - f_lo, 0.0), f_hi - f_lo), 6)
        self.bar.set_postfix_str(f"{f:.4g} Hz, {n} pts", refresh=False)
        self.bar.update(0)  # redraws at most every 0.5 s
        if self.progress is not None:
            self.progress((f - f_lo) / (f_hi - f_lo), f, n)

    def say(self, what: str, **ctx) -> str:
        """The words of a stop (see :func:`..path.engine.follow`)."""
        opts, n = self.opts, self.rows.n
        arc = opts.continuation == "arclength"
        if what == "max_points":
            at = f" at f = {ctx['at'].param / TWO_PI:.6g} Hz" if arc else ""
            return f"stopped after max_points = {opts.max_points} points{at}"
        if what == "failed" and arc:
            return (
                f"the corrector failed at f = {ctx['at'].param / TWO_PI:.6g} Hz after "
                f"{n} points ({_why(ctx['sol'].reason)}) even with the smallest "
                f"step ds_min = {opts.ds_min:g}; the branch so far is kept"
            )
        if what == "failed":
            return (
                f"frequency stepping failed at f = {ctx['sol'].param / TWO_PI:.6g} Hz (SNES: "
                f"{ctx['sol'].reason}), a turning point? continuation = 'arclength' passes "
                "them; the branch so far is kept"
            )
        if what == "end_failed":
            return (
                f"the branch passed the band end but the corrector failed at exactly "
                f"f = {self.end / TWO_PI:.6g} Hz (SNES: {ctx['sol'].reason}); the last point "
                f"kept is at {ctx['at'].param / TWO_PI:.6g} Hz"
            )
        if what == "below_start":
            return f"the branch turned back below the band start after {n} points"
        if what == "numerical":
            e = ctx["error"]
            at = f" after f = {self.rows.cols['freq_hz'][-1]:.6g} Hz" if n else ""
            return f"stopped by a numerical error{at} ({n} points kept): {type(e).__name__}: {e}"
        raise ValueError(f"no words for a stop of kind {what!r}")


def frequency_response(
    system: System,
    f1: np.ndarray,
    level: float,
    band_hz: tuple[float, float],
    outputs: object = None,
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    options: SolverOptions | None = None,
    output_names: tuple[str, ...] | None = None,
    progress: Callable[[float, float, int], None] | None = None,
    label: str = "",
) -> Branch:
    """The forced response curve of ``system`` over ``band_hz`` at one excitation level.

    ``f1`` (n, complex, N per unit level): the harmonic-1 force,
    ``f(t) = level * Re(f1 exp(i w t))``, so the phase of each entry sets
    the phase of that DOF's force (an inter-blade phase angle, say).
    ``outputs``: DOF indices or an (n_out, n) observation matrix (default
    every DOF). ``harmonics``: the harmonic list (must include 1); ``nt``
    samples per period (default :func:`..core.fourier.default_nt`).
    ``progress(fraction_of_band, freq_hz, n_points)`` is called after each
    point; a progress bar on stderr shows the frequency reached.
    Never raises for a failed solve: the returned :class:`Branch` says
    ``failed`` and keeps the points computed before.
    """
    opts = options or SolverOptions()
    t_start = time.perf_counter()
    level = check_range("level", level, 0.0)
    try:
        f_lo, f_hi = (float(v) for v in band_hz)
    except (TypeError, ValueError):
        raise InputError("band_hz", band_hz, "two frequencies (start, end) in Hz") from None
    check_range("band_hz[0]", f_lo, 0.0, lo_open=True, unit="Hz")
    check_range("band_hz[1]", f_hi, f_lo, lo_open=True, unit="Hz")
    fourier = Fourier(tuple(harmonics), nt or 0)
    O = observation(system, outputs)
    names = tuple(output_names) if output_names else tuple(f"y{j}" for j in range(O.shape[0]))
    if len(names) != O.shape[0]:
        raise InputError("output_names", list(names), f"{O.shape[0]} names (one per output)")
    hb = HarmonicBalance(system, f1, fourier, O, level, opts.space, opts.backend, opts.dc_anchor)
    return follow_balance(hb, (f_lo, f_hi), opts, names, progress, label, t_start)


def follow_balance(
    hb,
    band_hz: tuple[float, float],
    opts: SolverOptions,
    names: tuple[str, ...],
    progress: Callable[[float, float, int], None] | None = None,
    label: str = "",
    t_start: float | None = None,
) -> Branch:
    """The forced response of a built balance problem (``hb``: a
    :class:`..core.balance.HarmonicBalance` or another problem with its methods, e.g.
    :class:`..core.sector.SectorBalance`) over ``band_hz`` at its level."""
    t_start = time.perf_counter() if t_start is None else t_start
    f_lo, f_hi = band_hz
    level, fourier, el = hb.level, hb.fourier, hb.el
    n_el = hb.n_el
    w0, w1 = TWO_PI * f_lo, TWO_PI * f_hi
    # scales: the stuck linear response at the band ends
    u_ref = max(
        np.abs(hb.stuck_solution(w0)).max(initial=0.0),
        np.abs(hb.stuck_solution(w1)).max(initial=0.0),
    )
    if el is not None and n_el:
        slip = el.mu * el.n0 / np.maximum(np.maximum(el.kt1, el.kt2), 1e-300)
        u_ref = max(u_ref, float(slip.max()) * 1e-3)
    u_ref = u_ref if u_ref > 0 else 1e-9
    corr = make_corrector(hb, opts, u_ref, w0)
    timings = dict(setup=time.perf_counter() - t_start, stability=0.0, post=0.0)
    path = StabilityPath(hb, corr, opts) if opts.stability else None

    from ...log import progress_bar

    bar_ctx = progress_bar(
        f"frf {label or f'level {level:g}'}", total=round(f_hi - f_lo, 6), unit="Hz"
    )
    bar = bar_ctx.__enter__()
    fr = ForcedResponse(hb, corr, opts, level, (f_lo, f_hi), u_ref, path, timings, bar, progress)
    out = follow(fr, StepRule.forced(opts, w1 - w0))
    message, failed, completed = out.message, out.failed, out.completed
    rows = fr.rows
    try:
        try:
            if opts.refine_peak and rows.n >= 3:
                t0 = time.perf_counter()
                insert_peaks(rows, fr.add, refine_peaks(hb, corr, opts, rows))
                timings["peak"] = time.perf_counter() - t0
        except Stop as stop:  # a lost contact found while refining: report, keep the branch
            message = message or str(stop)
            failed = failed or stop.failed
        if path is not None:  # the verdicts decided once the branch is complete
            try:
                path.finish(rows.cols)
            except NUMERICAL as e:
                path.abandon(rows.cols, f"{type(e).__name__}: {e}")
    finally:
        bar_ctx.__exit__(None, None, None)
        corr.destroy()
    if path is not None:
        timings["stability"] = path.time
        corr.stats.update({f"stability_{k}": v for k, v in path.summary().items()})
        corr.stats["n_stability_unknown"] = path.stats["n_unknown"]
    lost = corr.stats.get("peak_trials_lost_contact") or []
    if lost:  # trials between branch points that found the damper without contact: not used
        note = (
            f"the peak search found the damper without contact at {len(lost)} trial "
            f"frequenc{'y' if len(lost) == 1 else 'ies'} ({', '.join(f'{q:.6g}' for q in lost)} "
            "Hz), not used: the top of the curve may lie where no contact holds it"
        )
        log.warning("%s%s", f"{label}: " if label else "", note)
        message = f"{message or ('reached the band end' if completed else '')}; {note}"

    n_out, nh = len(names), fourier.nh
    empty = dict(
        out_amp=(0, n_out),
        out_h1=(0, n_out),
        out_rms=(0, n_out),
        out_harm=(0, nh, n_out),
        status=(0, n_el),
        friction_energy=(0, n_el),
        x=(0, hb.N),
    )
    arrays = rows.arrays(empty, _DTYPES)
    timings["total"] = time.perf_counter() - t_start
    st = dict(hb.stats)
    st.update(corr.stats)
    st["mode"] = corr.mode
    st["n_unknowns"] = hb.N
    st["backend"] = hb.lin.kind
    st["u_ref_m"] = u_ref
    st["t_per_residual"] = st["t_residual"] / max(st["n_residual"], 1)
    st["t_per_jacobian"] = (st["t_jacobian"] + 0.0) / max(st["n_jacobian"], 1)
    st["t_per_factor"] = st["t_factor"] / max(st["n_factor"], 1)
    st["accuracy_warning"] = _accuracy_warning(fourier, arrays, opts)
    if st["accuracy_warning"]:
        log.warning("%s%s", f"{label}: " if label else "", st["accuracy_warning"])
    from ...config import record_to_dict

    return Branch(
        level=level,
        band_hz=(f_lo, f_hi),
        harmonics=fourier.harmonics,
        nt=fourier.nt,
        output_names=names,
        space=hb.space,
        completed=completed,
        failed=failed,
        message=message or ("reached the band end" if completed else ""),
        timings=timings,
        stats=st,
        options=record_to_dict(opts),
        label=label,
        **arrays,
    )


def _accuracy_warning(fourier: Fourier, arrays: dict, opts: SolverOptions) -> str:
    """The accuracy warning of a branch ("" if none): nt small, or the indicator too large."""
    out = []
    hmax = max(fourier.harmonics)
    if fourier.nt < 8 * hmax:
        out.append(
            f"nt = {fourier.nt} samples per period is few for harmonics up to {hmax} "
            f"(at least {8 * hmax}; the default is {default_nt(fourier.harmonics)})"
        )
    acc = np.asarray(arrays.get("accuracy", []), dtype=float)
    if acc.size and np.nanmax(acc, initial=0.0) > opts.accuracy_tol:
        i = int(np.nanargmax(acc))
        out.append(
            f"the loop energy and the harmonic work of the contacts differ by "
            f"{acc[i]:.2g} of the excitation work at f = {arrays['freq_hz'][i]:.6g} Hz "
            f"(accuracy_tol {opts.accuracy_tol:g}): raise nt (and the harmonics)"
        )
    return "; ".join(out)


def _ramp_level(hb: HarmonicBalance, corr: Corrector, w: float, level: float):
    """The first point by raising the excitation from a small level (natural continuation).

    Used when Newton from the stuck linear guess fails at the band start
    (a guess far from a strongly nonlinear solution): each level starts from
    the solution at the previous one; a failed level halves the increment
    (down to 1/256 of the level).
    """
    lv = level / 16
    hb.set_level(lv)
    res = corr.solve_natural(hb.stuck_solution(w), w)
    step = lv
    why = res.reason
    while res.converged and lv < level and step >= level / 256:
        nxt = min(lv + step, level)
        hb.set_level(nxt)
        corr.force_refresh = True
        trial = corr.solve_natural(res.x * (nxt / lv), w)
        if trial.converged:
            res, lv = trial, nxt
            step *= 1.5
        else:
            why = trial.reason
            step *= 0.5
    hb.set_level(level)
    if lv < level:
        res.converged = False
        res.reason = f"{why}; raising the level from {level / 16:g} stopped at {lv:g}"
    return res


def _why(reason: str) -> str:
    """The last corrector failure in words: a PETSc reason is quoted as SNES's."""
    first = reason.split(" ")[0]
    return f"SNES: {reason}" if first.isupper() or first.lstrip("-").isdigit() else reason
