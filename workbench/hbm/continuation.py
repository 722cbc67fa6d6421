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

from ..errors import InputError, check_range
from .balance import HarmonicBalance
from .branch import _ARRAYS, Branch
from .corrector import Constraint, Corrector
from .fourier import Fourier, default_nt
from .options import SolverOptions
from .peak import insert_peaks, refine_peaks
from .ports import observation
from .small import make_corrector
from .stability import STABLE, UNKNOWN
from .stability_path import HOW_NONE, StabilityPath
from .system import System

log = logging.getLogger(__name__)

TWO_PI = 2.0 * np.pi


class _Stop(Exception):
    def __init__(self, message: str, failed: bool, completed: bool = False):
        super().__init__(message)
        self.failed, self.completed = failed, completed


class _Recorder:
    """Collects the points of a branch; builds the Branch record at the end."""

    def __init__(self):
        self.rows: dict[str, list] = {k: [] for k in _ARRAYS}

    def add(self, **kw) -> None:
        for k, v in kw.items():
            self.rows[k].append(v)

    def arrays(self, n_out: int, nh: int, n_el: int, N: int) -> dict[str, np.ndarray]:
        shapes = dict(
            out_amp=(0, n_out),
            out_h1=(0, n_out),
            out_rms=(0, n_out),
            out_harm=(0, nh, n_out),
            status=(0, n_el),
            friction_energy=(0, n_el),
            x=(0, N),
        )
        out = {}
        for k, v in self.rows.items():
            if v:
                out[k] = np.array(v)
            else:
                out[k] = np.zeros(shapes.get(k, (0,)))
        out["stable"] = out["stable"].astype(bool)
        out["stability"] = out["stability"].astype(np.int8)
        out["stability_how"] = out["stability_how"].astype(np.int8)
        out["status"] = out["status"].astype(np.int8)
        out["newton_its"] = out["newton_its"].astype(int)
        return out


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
    samples per period (default :func:`.fourier.default_nt`).
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
    w0, w1 = TWO_PI * f_lo, TWO_PI * f_hi
    # scales: the stuck linear response at the band ends
    u_ref = max(
        np.abs(hb.stuck_solution(w0)).max(initial=0.0),
        np.abs(hb.stuck_solution(w1)).max(initial=0.0),
    )
    if system.contacts is not None and system.n_el:
        el = system.contacts
        slip = el.mu * el.n0 / np.maximum(np.maximum(el.kt1, el.kt2), 1e-300)
        u_ref = max(u_ref, float(slip.max()) * 1e-3)
    u_ref = u_ref if u_ref > 0 else 1e-9
    corr = make_corrector(hb, opts, u_ref, w0)
    band_s = (w1 - w0) / w0
    rec = _Recorder()
    timings = dict(setup=time.perf_counter() - t_start, stability=0.0, post=0.0)
    # loop state: largest solution norm, points
    state = dict(xi=1e-300, n=0)
    path = StabilityPath(hb, corr, opts) if opts.stability else None
    message, failed, completed = "", False, False

    from ..log import progress_bar

    bar_ctx = progress_bar(
        f"frf {label or f'level {level:g}'}", total=round(f_hi - f_lo, 6), unit="Hz"
    )
    bar = bar_ctx.__enter__()

    def record(x: np.ndarray, w: float, its: int) -> None:
        t0 = time.perf_counter()
        ev = corr.evaluated(x, w)
        pd = hb.point_data(ev, n_fine=opts.n_fine)
        timings["post"] += time.perf_counter() - t0
        if pd.lost_contact:
            raise _Stop(
                f"the damper has lost contact at f = {w / TWO_PI:.6g} Hz: at some instant of the "
                "period no closed contact holds a body that only its contacts support (a "
                "singular state); lower the excitation or raise the preload",
                failed=True,
            )
        if path is not None:
            verdict, max_real, how = path.at_point(ev)
        else:
            verdict, max_real, how = UNKNOWN, float("nan"), HOW_NONE
        rec.add(
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
        xd = x / u_ref
        if fourier.has_dc:
            xd = xd.copy()
            xd[: hb.n_s] *= opts.dc_weight
        state["xi"] = max(state["xi"], float(np.linalg.norm(xd)))
        state["n"] += 1
        f = w / TWO_PI
        bar.n = round(min(max(f - f_lo, 0.0), f_hi - f_lo), 6)
        bar.set_postfix_str(f"{f:.4g} Hz, {state['n']} pts", refresh=False)
        bar.update(0)  # redraws at most every 0.5 s
        if progress is not None:
            progress((f - f_lo) / (f_hi - f_lo), f, state["n"])

    try:
        # -- first point: frequency fixed at the band start ----------------------
        x0 = hb.stuck_solution(w0)
        res = corr.solve_natural(x0, w0)
        if not res.converged and level > 0:
            res = _ramp_level(hb, corr, w0, level)
        if not res.converged:
            raise _Stop(
                f"the corrector failed at the band start f = {f_lo:.6g} Hz (SNES: {res.reason})",
                failed=True,
            )
        record(res.x, w0, res.its)
        if opts.continuation == "arclength":
            completed = _arclength(hb, corr, opts, res.x, w0, w0, w1, band_s, u_ref, state, record)
        else:
            completed = _stepping(hb, corr, opts, res.x, w0, w0, w1, record)
    except _Stop as stop:
        message, failed, completed = str(stop), stop.failed, stop.completed
        (log.warning if failed else log.info)("%s", message)
    except (np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError) as e:
        # a numerical breakdown inside the loop: report it, keep the branch so far
        log.debug("continuation stopped", exc_info=True)
        n = len(rec.rows["freq_hz"])
        at = f" after f = {rec.rows['freq_hz'][-1]:.6g} Hz" if n else ""
        failed = True
        message = f"stopped by a numerical error{at} ({n} points kept): {type(e).__name__}: {e}"
        log.warning("%s", message)
    try:
        try:
            if opts.refine_peak and len(rec.rows["freq_hz"]) >= 3:
                t0 = time.perf_counter()
                insert_peaks(rec, record, refine_peaks(hb, corr, opts, rec))
                timings["peak"] = time.perf_counter() - t0
        except _Stop as stop:  # a lost contact found while refining: report, keep the branch
            message = message or str(stop)
            failed = failed or stop.failed
        if path is not None:  # the verdicts decided once the branch is complete
            try:
                path.finish(rec.rows)
            except (np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError) as e:
                path.abandon(rec.rows, f"{type(e).__name__}: {e}")
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

    arrays = rec.arrays(O.shape[0], fourier.nh, system.n_el, hb.N)
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
    from ..config import record_to_dict

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


def _arclength(
    hb,
    corr: Corrector,
    opts: SolverOptions,
    x: np.ndarray,
    w: float,
    w0: float,
    w1: float,
    band_s: float,
    u_ref: float,
    state: dict,
    record,
) -> bool:
    """Pseudo-arc-length continuation in the scaled variables ``y = (x / u_ref, w / w_ref)``.

    Metric: ``|dy|^2 = sum (a_j dy_j)^2`` with ``a = (c_j / xi, 1 / band)``: the unknowns
    relative to the largest solution norm met so far (``c_j = dc_weight`` for the mean
    components, 1 otherwise) and the frequency relative to the band.
    """
    w_ref = corr.w_ref
    ds = opts.ds0
    cos_max = np.cos(np.radians(opts.max_angle_deg))
    nx = x.size
    cw = np.ones(nx)
    if hb.fourier.has_dc:
        cw[: hb.n_s] = opts.dc_weight

    def weights() -> np.ndarray:
        xi = max(state["xi"], 1e-300)
        return np.concatenate([cw / xi, [1.0 / band_s]])

    def norm(v: np.ndarray, a: np.ndarray) -> float:
        return float(np.sqrt(np.sum((a * v) ** 2)))

    def y_of(xv: np.ndarray, wv: float) -> np.ndarray:
        return np.concatenate([xv / u_ref, [wv / w_ref]])

    # first direction: the tangent at the first point, frequency increasing
    tx, tw = corr.tangent(x / u_ref, w / w_ref)
    a = weights()
    t = np.concatenate([tx, [tw]])
    t /= norm(t, a)
    prev: np.ndarray | None = None
    turns = 0  # halvings of this step for a sharp turn; a kink (stick/slip transition) stays
    while True:
        if state["n"] >= opts.max_points:
            raise _Stop(
                f"stopped after max_points = {opts.max_points} points at f = {w / TWO_PI:.6g} Hz",
                failed=False,
            )
        a = weights()
        yc = y_of(x, w)
        if prev is not None and opts.predictor == "tangent":
            tx, tw = corr.tangent(x / u_ref, w / w_ref)
            tt = np.concatenate([tx, [tw]])
            tt /= norm(tt, a)
            t = tt if np.sum(a * a * tt * t) >= 0 else -tt
        elif prev is not None:  # secant (and the constant predictor's constraint)
            t = (yc - prev) / norm(yc - prev, a)
        yp = yc + ds * t
        con = Constraint(t[:nx], t[nx], a[:nx] ** 2, a[nx] ** 2, yp[:nx], yp[nx])
        y0 = yc if opts.predictor == "constant" else yp
        res = corr.solve_arclength(y0[:nx] * u_ref, y0[nx] * w_ref, con)
        if not res.converged and prev is not None:
            # the plane ahead may miss a branch that turns sharply at a kink (a fold at a
            # stick/slip or contact transition): cut it with the sphere of radius ds instead
            sph = Constraint(
                t[:nx],
                t[nx],
                a[:nx] ** 2,
                a[nx] ** 2,
                yp[:nx],
                yp[nx],
                center=(yc[:nx], yc[nx]),
                ds=ds,
            )
            res = corr.solve_arclength(yp[:nx] * u_ref, yp[nx] * w_ref, sph)
            if res.converged and norm(y_of(res.x, res.omega) - prev, a) < 0.5 * ds:
                res.converged = False  # the sphere's other cut: back where we came from
            if not res.converged:
                # a fold exactly at a kink can turn the branch back almost on itself: try
                # the plane ahead along the secant with its frequency part reversed, and keep
                # the point only if it is off the incoming piece
                tr = t.copy()
                tr[nx] = -tr[nx]
                tr /= norm(tr, a)
                ypr = yc + ds * tr
                ref = Constraint(tr[:nx], tr[nx], a[:nx] ** 2, a[nx] ** 2, ypr[:nx], ypr[nx])
                res = corr.solve_arclength(ypr[:nx] * u_ref, ypr[nx] * w_ref, ref)
                if res.converged:
                    d = y_of(res.x, res.omega) - yc
                    along = np.sum(a * a * d * t)  # the incoming piece runs along -t
                    off = norm(d - along * t, a)
                    if along >= 0 or off < 0.05 * norm(d, a):
                        res.converged = False
                        res.reason = "converged back onto the incoming branch (rejected)"
        if not res.converged:
            ds *= 0.5
            corr.force_refresh = True
            if ds < opts.ds_min:
                raise _Stop(
                    f"the corrector failed at f = {w / TWO_PI:.6g} Hz after "
                    f"{state['n']} points ({_why(res.reason)}) even with the smallest "
                    f"step ds_min = {opts.ds_min:g}; the branch so far is kept",
                    failed=True,
                )
            continue
        ynew = y_of(res.x, res.omega)
        sec = ynew - yc
        cosang = np.sum(a * a * sec * t) / max(norm(sec, a), 1e-300)
        corr_ratio = norm(ynew - yp, a) / ds  # how far the corrector moved off the predictor
        if (
            (cosang < cos_max or corr_ratio > opts.max_correction)
            and ds > 2 * opts.ds_min
            and turns < 3
        ):
            # a sharp turn, or a correction so large that the corrector may have landed on
            # another branch: halve (three times at most; what is still sharp then is a kink
            # of the branch, where a stick/slip or contact transition changes its slope)
            ds *= 0.5
            turns += 1
            continue
        turns = 0
        if res.omega > w1:
            end = _band_end(corr, x, w, res.x, res.omega, w1)
            if not end.converged:
                raise _Stop(
                    f"the branch passed the band end but the corrector failed at exactly "
                    f"f = {w1 / TWO_PI:.6g} Hz (SNES: {end.reason}); the last point kept is "
                    f"at {w / TWO_PI:.6g} Hz",
                    failed=True,
                )
            record(end.x, w1, end.its)
            return True
        if res.omega < w0 * (1 - 1e-12):
            raise _Stop(
                f"the branch turned back below the band start after {state['n']} points",
                failed=False,
            )
        prev = yc
        x, w = res.x, res.omega
        record(x, w, res.its)
        if res.its > opts.target_newton:  # a slow corrector: a fresh LU for the next step
            corr.force_refresh = True
        factor = 2.0 if res.its == 0 else np.clip(np.sqrt(opts.target_newton / res.its), 0.5, 2.0)
        ds = float(np.clip(ds * factor, opts.ds_min, opts.ds_max))


def _band_end(corr: Corrector, x: np.ndarray, w: float, xn: np.ndarray, wn: float, w1: float):
    """The solution exactly at the band end ``w1``, between the last point (x, w) and the
    step (xn, wn) that passed it: from the interpolated guess (with the current LU, then a
    fresh one), then from the step's own solution, then by frequency steps from the last
    point (halved while they fail). Returns the last corrector result tried."""
    interpolated = x + (w1 - w) / (wn - w) * (xn - x)
    end = corr.solve_natural(interpolated, w1)
    for guess in (interpolated, xn):
        if end.converged:
            return end
        corr.force_refresh = True
        end = corr.solve_natural(guess, w1)
    xc, wc, dw = x, w, w1 - w
    while not end.converged and dw > 1e-3 * (w1 - w):  # a stick/slip kink before the end
        wt = min(wc + dw, w1)
        corr.force_refresh = True
        trial = corr.solve_natural(xc, wt)
        if trial.converged:
            xc, wc = trial.x, wt
            if wt >= w1:
                return trial
        else:
            dw *= 0.5
            end = trial
    return end


def _stepping(
    hb, corr: Corrector, opts: SolverOptions, x: np.ndarray, w: float, w0: float, w1: float, record
) -> bool:
    dw = opts.ds0 * (w1 - w0)
    dw_min, dw_max = opts.ds_min * (w1 - w0), opts.ds_max * (w1 - w0)
    prev: tuple[np.ndarray, float] | None = None
    n = 1
    while w < w1 * (1 - 1e-14):
        if n >= opts.max_points:
            raise _Stop(f"stopped after max_points = {opts.max_points} points", failed=False)
        wn = min(w + dw, w1)
        guess = (
            x
            if prev is None or opts.predictor == "constant"
            else x + (x - prev[0]) * (wn - w) / (w - prev[1])
        )
        res = corr.solve_natural(guess, wn)
        if not res.converged:
            dw *= 0.5
            corr.force_refresh = True
            if dw < dw_min:
                raise _Stop(
                    f"frequency stepping failed at f = {wn / TWO_PI:.6g} Hz (SNES: "
                    f"{res.reason}), a turning point? continuation = 'arclength' passes "
                    "them; the branch so far is kept",
                    failed=True,
                )
            continue
        prev = (x, w)
        x, w = res.x, wn
        record(x, w, res.its)
        if res.its > opts.target_newton:
            corr.force_refresh = True
        n += 1
        factor = 2.0 if res.its == 0 else np.clip(np.sqrt(opts.target_newton / res.its), 0.5, 2.0)
        dw = float(np.clip(dw * factor, dw_min, dw_max))
    return True
