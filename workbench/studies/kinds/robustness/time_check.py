"""The robustness study's check of the harmonic balance against time integration.

On small models (:data:`TIME_MODELS`, at most 200 DOFs: the dense time
integration of :mod:`workbench.hbm.timedomain.timeint`), the HBM branch is computed
and, at its suspect points (peak, turning points, a Hill-unstable and a
separated point), a time integration is started on the HBM orbit and its
steady amplitude compared with the branch's (cached per model).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ....errors import SolveError
from ....io import digest, write_json

log = logging.getLogger(__name__)


def turning_points(freq_hz: np.ndarray) -> np.ndarray:
    """Indices of the points where the frequency increment along the branch changes sign."""
    f = np.asarray(freq_hz, dtype=float)
    if f.size < 3:
        return np.zeros(0, dtype=int)
    df = np.diff(f)
    keep = np.flatnonzero(np.abs(df) > 1e-9 * max(np.abs(f).max(), 1.0))
    s = np.sign(df[keep])
    flips = np.flatnonzero(s[1:] != s[:-1])
    return keep[flips + 1]  # the point where the new direction starts


@dataclass(frozen=True)
class TimeModel:
    """A small model (<= 200 DOFs) whose HBM branch is checked by time integration."""

    build: Callable[[], Any]  # -> ExampleModel
    level: float
    harmonics: tuple[int, ...]
    why: str
    max_periods: int = 2000
    steps_per_period: int = 1024
    tol: float = 1e-7  # relative change of the state over a period that counts as periodic


def _two_dof():
    from ....hbm.io.examples import two_dof_contact

    return two_dof_contact(zeta=0.005)


def _sdof_light():
    from ....hbm.io.examples import sdof_jenkins

    return sdof_jenkins(zeta=1e-4)


TIME_MODELS: dict[str, TimeModel] = {
    "two-dof-separating": TimeModel(
        _two_dof,
        3.0,
        tuple(range(6)),
        "two-DOF 3-D contact example (harmonics 0-5, as its study file), damping 0.5 %, "
        "level 3 N: separation, turning points and Hill-unstable pieces",
    ),
    "sdof-light-damping": TimeModel(
        _sdof_light,
        1.0,
        tuple(range(8)),
        "single-DOF Jenkins oscillator with damping 0.01 % (the lightest damping)",
        max_periods=6000,
        tol=1e-6,
    ),
}


def suspect_points(freq_hz, amp, stability, status, max_points: int = 4) -> list[tuple[int, str]]:
    """Indices of points where the HBM is suspect, with why: peak, turning points, unstable,
    separation (at most ``max_points``, distinct). ``stability``: Hill's verdicts (1 stable,
    0 unstable, -1 unknown; a bool array reads as stable / unstable)."""
    f = np.asarray(freq_hz)
    a = np.asarray(amp)
    v = np.asarray(stability).astype(int)
    out: list[tuple[int, str]] = [(int(np.argmax(a)), "peak")]
    for j in turning_points(f)[:2]:
        out.append((int(j), "turning point"))
    bad = np.flatnonzero(v == 0)
    if bad.size:
        out.append((int(bad[np.argmax(a[bad])]), "Hill-unstable"))
    stat = np.asarray(status)
    if stat.size:
        sep = np.flatnonzero(stat.max(axis=1) >= 2 if stat.ndim == 2 else stat >= 2)
        sep = sep[v[sep] == 1] if sep.size else sep
        if sep.size:
            out.append((int(sep[np.argmax(a[sep])]), "separation"))
    seen: dict[int, str] = {}
    for i, why in out:
        seen[i] = f"{seen[i]}, {why}" if i in seen else why
    return list(seen.items())[:max_points]


def time_check(name: str, tm: TimeModel) -> dict[str, Any]:
    """HBM branch of a small model and time integrations started on it at its suspect points."""
    from ....hbm.core.balance import HarmonicBalance
    from ....hbm.core.fourier import Fourier
    from ....hbm.core.options import SolverOptions
    from ....hbm.forced.response import frequency_response
    from ....hbm.timedomain.timeint import time_response

    ex = tm.build()
    # Hill's method at every point: the time integrations check its verdicts themselves
    opts = SolverOptions(stability_stride=1)
    t0 = time.perf_counter()
    b = frequency_response(
        ex.system,
        ex.f1,
        tm.level,
        ex.band_hz,
        outputs=ex.outputs,
        harmonics=tm.harmonics,
        options=opts,
        label=f"time check {name}",
    )
    hb = HarmonicBalance(
        ex.system,
        ex.f1,
        Fourier(b.harmonics, b.nt),
        ex.outputs,
        tm.level,
        opts.space,
        opts.backend,
        opts.dc_anchor,
    )
    rows = []
    for i, why in suspect_points(b.freq_hz, b.out_amp[:, 0], b.stability, b.status):
        w = 2 * np.pi * b.freq_hz[i]
        q0, v0 = hb.fourier.state_at(hb.response(b.x[i], w), w)
        ts = time.perf_counter()
        try:
            tr = time_response(
                ex.system,
                ex.f1,
                tm.level,
                b.freq_hz[i],
                ex.outputs,
                harmonics=tm.harmonics,
                steps_per_period=tm.steps_per_period,
                max_periods=tm.max_periods,
                tol=tm.tol,
                q0=q0,
                v0=v0,
            )
        except SolveError as e:  # not periodic within max_periods: keep the last period
            tr = e.partial
        a_hbm, a_ti = float(b.out_amp[i, 0]), float(tr.amplitude[0])
        rows.append(
            {
                "model": name,
                "point": i,
                "why": why,
                "freq_hz": float(b.freq_hz[i]),
                "hill_stable": bool(b.stable[i]),
                "hill_verdict": b.stability_name(i),
                "hbm_amplitude": a_hbm,
                "ti_amplitude": a_ti,
                "diff_pct": 100.0 * (a_ti - a_hbm) / a_hbm,
                "hbm_h1": float(b.out_h1[i, 0]),
                "ti_h1": float(tr.h1_amplitude[0]),
                "ti_periods": int(tr.periods),
                "ti_converged": bool(tr.converged),
                "ti_s": time.perf_counter() - ts,
            }
        )
    return {
        "model": name,
        "why": tm.why,
        "level": tm.level,
        "n_dofs": ex.system.n,
        "harmonics": list(tm.harmonics),
        "failed": bool(b.failed),
        "message": b.message,
        "freq_hz": b.freq_hz.tolist(),
        "amp": b.out_amp[:, 0].tolist(),
        "stable": b.stable.tolist(),
        "stability": b.stability.astype(int).tolist(),
        "points": rows,
        "wall_s": time.perf_counter() - t0,
    }


def branch_amplitudes_at(freq_hz, amp, fq: float) -> np.ndarray:
    """Every amplitude of a branch at frequency ``fq`` (linear between neighbouring points)."""
    f, a = np.asarray(freq_hz, float), np.asarray(amp, float)
    out = []
    for j in range(f.size - 1):
        d0, d1 = f[j] - fq, f[j + 1] - fq
        if d0 == 0.0:
            out.append(a[j])
        elif d0 * d1 < 0:
            out.append(a[j] + (a[j + 1] - a[j]) * (fq - f[j]) / (f[j + 1] - f[j]))
    if f.size and f[-1] == fq:
        out.append(a[-1])
    return np.array(out)


def compare_with_branch(check: dict[str, Any]) -> None:
    """Add to each time-integration row the HBM solution nearest to it at its frequency.

    Near a fold several periodic solutions coexist: a time integration started
    on one may settle on another. ``nearest_hbm_amplitude`` is the branch's
    amplitude (at that frequency) closest to the time-integration amplitude and
    ``diff_nearest_pct`` the difference to it.
    """
    for r in check["points"]:
        cands = branch_amplitudes_at(check["freq_hz"], check["amp"], r["freq_hz"])
        cands = np.append(cands, r["hbm_amplitude"])
        k = int(np.argmin(np.abs(cands - r["ti_amplitude"])))
        r["n_hbm_solutions"] = int(len(set(np.round(cands / cands.max(), 6))))
        r["nearest_hbm_amplitude"] = float(cands[k])
        r["diff_nearest_pct"] = 100.0 * (r["ti_amplitude"] - cands[k]) / cands[k]


def time_checks(
    cache_dir: Path | None, *, force: bool = False, names: list[str] | None = None
) -> list[dict[str, Any]]:
    """:func:`time_check` of every model of :data:`TIME_MODELS` (cached), with a progress bar."""
    from ....log import progress
    from ...engine.plan import _SOLVER_CODE

    out = []
    for name in progress(
        names or list(TIME_MODELS), "robustness: HBM vs time integration", unit="model"
    ):
        tm = TIME_MODELS[name]
        key = digest(
            {
                "time-check": name,
                "level": tm.level,
                "harmonics": tm.harmonics,
                "why": tm.why,
                "max_periods": tm.max_periods,
                "tol": tm.tol,
                "spp": tm.steps_per_period,
                "code": _SOLVER_CODE(),
            }
        )
        path = None if cache_dir is None else cache_dir / f"time-{name}-{key}.json"
        if path is not None and path.is_file() and not force:
            import json

            try:
                rec = json.loads(path.read_text())
                compare_with_branch(rec)
                out.append(rec)
                continue
            except (OSError, ValueError):
                pass
        rec = time_check(name, tm)
        if path is not None:
            write_json(path, rec)
        compare_with_branch(rec)
        out.append(rec)
    return out
