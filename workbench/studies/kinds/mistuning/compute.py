"""Mistuning study: sampled blade mistuning on a bladed disk, per damper the amplification of
the worst blade without damper, with the damper stuck and with the damper in friction.

For each damper one disk sector is meshed (the bladed-disk study's sectors and options:
``n-blades``, mesh sizes, contact points, ``sector-modes``, ``damper-modes``) and its
mistuning model built once per rank
(:func:`workbench.pipeline.mistuning.build_mistuning_model`: the tuned sector model at every
nodal diameter and the projections of the sector stiffness on its cyclic basis). The
patterns are :mod:`.patterns`' (one frequency deviation ``df_j`` per blade, stiffness
``(1 + df_j)^2``); the tuned disk (every ``df_j = 0``) is solved once more per damper and EO
as the reference.

A *task* is one (damper, EO, pattern or the tuned disk, configuration); a configuration is
``none`` (the dampers removed, linear), ``stuck`` (every contact pair bonded, linear) or one
force of ``forces`` (the dampers in friction: the harmonic-balance sweep of the mistuned
whole disk, :func:`workbench.pipeline.mistuning.mistuned_forced_response`). Each gives every
blade's peak response (its response point along the excitation direction) per newton of
force and the frequency of that peak:

- linear: :func:`workbench.pipeline.mistuning.blade_peaks` (the receptance, m/N: 100
  frequencies and the natural ones in the band, then each blade's maximum refined) over
  ``[0.9 (1 + min df), 1.1 (1 + max df)]`` times the tuned disk's first frequency at the
  EO's nodal diameter (no damper: the bladed sector's own; stuck: with the damper stuck);
- friction: the sweep over ``[0.95 (1 + min df), 1.03 (1 + max df)]`` times the tuned stuck
  frequency (``min df``, ``max df`` taken with 0), harmonics ``harmonics``, AFT samples a
  multiple of N (:func:`aft_samples`); a blade's peak is the top of its harmonic-1
  amplitude along the curve (:func:`curve_peak`: the largest point refined by a parabola
  through ``1 / a^2``), divided by the force.

A peak on the first or last point of its band, or of a curve that stopped before the band
end, is a lower bound and is flagged so. The amplification factor of a pattern in a
configuration is its worst blade's peak over the tuned disk's worst blade's peak in the same
configuration (damper, EO, force).

Each task is kept in ``out/cache/mistuning/<digest>.json``; the digest covers the sector's
own digest, the contact parameters, the reduction's sizes, the modal damping, the EO, the
pattern's stiffness deviations, the configuration (force, harmonics, AFT samples, points
per curve) and the sources of the solver, the FE reduction and this module, so a study
killed part way (kill -9 included: each file is written whole or not at all) resumes where
it stopped and a second run reuses every task; ``force`` recomputes. The tasks are handed
to whichever MPI rank is free (:func:`workbench.studies.engine.schedule.run_tasks`), the
dearest (friction, largest force) first.
"""

from __future__ import annotations

import json
import logging
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ....io import code_version, digest, write_json
from ...engine.plan import disk_code_version
from ...engine.schedule import run_tasks, schedule_efficiency, study_comm
from ...engine.spec import StudySpec
from ..bladed_disk.compute import disk_sectors, study_eos
from ..bladed_disk.outputs import eo_nd, nd_and_direction
from .patterns import Patterns, study_patterns
from .write import TUNED, amplification, config_key, write_outputs

log = logging.getLogger(__name__)

LINEAR = ("none", "stuck")
LINEAR_BAND = (0.9, 1.1)  # times the tuned frequency, widened by the pattern's spread
FRICTION_BAND = (0.95, 1.03)
N_FREQ = 100  # frequencies of a linear scan (and the natural ones) before the peaks are refined


def _code() -> str:
    """The sources a task's result depends on: the bladed disk's (the solver and the FE
    package, :func:`disk_code_version`) and this module."""
    return digest([disk_code_version(), code_version(Path(__file__).parent, ("compute.py",))], 12)


def task_key(rec, cp, spec: StudySpec, eo: int, delta: np.ndarray, config, code: str) -> str:
    """The cache key of one (damper sector, EO, pattern, configuration) task."""
    fric = not isinstance(config, str)
    return digest(
        {
            "kind": "mistuning",
            "sector": rec.digest,
            "contact": repr(cp),
            "sector_modes": int(spec.bladed_disk.sector_modes),
            "damper_modes": int(spec.bladed_disk.damper_modes),
            "zeta": float(spec.damping),
            "eo": int(eo),
            "deviations": [float(v) for v in delta],
            "config": config_key(config),
            "harmonics": [int(h) for h in spec.harmonics] if fric else None,
            "nt": aft_samples(spec, rec.n_blades) if fric else None,
            "max_points": int(spec.max_points) if fric else None,
            "code": code,
        }
    )


def tuned_frequencies(mm, eo: int) -> dict[str, float]:
    """The tuned disk's first frequency (Hz) at the nodal diameter of ``eo``'s harmonic 1:
    without the dampers (the bladed sector's own) and with them stuck."""
    import scipy.linalg as sla

    from ....hbm.core.fourier import Fourier
    from ....hbm.core.sector import SectorBalance

    k = nd_and_direction(eo, mm.n_blades)[0]
    blk = mm.model.nd[k]
    lam = sla.eigh(blk.K, blk.M, eigvals_only=True, subset_by_index=[0, 0])[0]
    stuck = SectorBalance(mm.model, eo, Fourier((0, 1), 8)).stuck_frequencies(1, 1)[0]
    return {"none": math.sqrt(max(lam, 0.0)) / (2 * math.pi), "stuck": float(stuck)}


def band_of(f0: float, df: np.ndarray, linear: bool) -> tuple[float, float]:
    """The frequency band (Hz) of a pattern ``df`` around the tuned frequency ``f0``."""
    lo, hi = LINEAR_BAND if linear else FRICTION_BAND
    return f0 * (1 + min(float(df.min()), 0.0)) * lo, f0 * (1 + max(float(df.max()), 0.0)) * hi


def solve_task(mm, eo: int, df: np.ndarray, config, spec: StudySpec) -> dict[str, Any]:
    """One task's record: every blade's peak per newton (m/N), its frequency (Hz), whether
    it is a lower bound; a friction task also keeps its curves (for the figures)."""
    from ....pipeline.mistuning import blade_peaks

    t0 = time.perf_counter()
    delta = (1.0 + df) ** 2 - 1.0
    f0 = tuned_frequencies(mm, eo)
    rec: dict[str, Any] = {"eo": int(eo), "config": config_key(config)}
    if isinstance(config, str):
        band = band_of(f0[config], df, True)
        peak, at = blade_peaks(mm, delta, eo, band, config, N_FREQ)
        half = 0.5 * (band[1] - band[0]) / (N_FREQ - 1)  # within half a step of a band end
        edge = (at <= band[0] + half) | (at >= band[1] - half)
        rec.update(completed=True, message="linear", n_points=N_FREQ, lower=edge.tolist())
    else:
        from ....hbm.core.options import SolverOptions
        from ....pipeline.mistuning import mistuned_forced_response

        band = band_of(f0["stuck"], df, False)
        # every blade alike: no peak search for output 0 alone (each blade's top is refined
        # below); AFT samples a multiple of N, so the tuned disk's blades see the same samples
        opts = SolverOptions(stability=False, max_points=int(spec.max_points), refine_peak=False)
        harmonics = tuple(int(h) for h in spec.harmonics)
        nt = aft_samples(spec, mm.n_blades)
        label = f"EO {eo} {float(config):g} N"
        br = mistuned_forced_response(
            mm, delta, eo, float(config), band, harmonics, nt, opts, label
        )
        fz = np.asarray(br.freq_hz, dtype=float)
        amp = np.asarray(br.out_h1, dtype=float)
        if amp.size:
            top = [curve_peak(fz, amp[:, j]) for j in range(amp.shape[1])]
            peak = np.array([t[0] for t in top]) / float(config)
            at = np.array([t[1] for t in top])
            i = amp.argmax(axis=0)
            edge = (i == 0) | (i == amp.shape[0] - 1) | (not br.completed)
        else:
            peak = at = np.full(mm.n_blades, np.nan)
            edge = np.ones(mm.n_blades, dtype=bool)
        rec.update(
            completed=bool(br.completed),
            message=str(br.message),
            n_points=int(len(fz)),
            lower=np.asarray(edge, dtype=bool).tolist(),
            force_n=float(config),
            freq_hz=[float(v) for v in fz],
            amp_m=[[float(f"{v:.6g}") for v in row] for row in amp.T],
        )
    rec.update(
        band_hz=[float(band[0]), float(band[1])],
        tuned_hz=f0,
        peak_m_per_n=[float(v) for v in peak],
        peak_hz=[float(v) for v in at],
        wall_s=time.perf_counter() - t0,
    )
    return rec


def aft_samples(spec: StudySpec, n_blades: int) -> int:
    """AFT samples per period: ``nt``, or the smallest multiple of N at least the solver's
    default for the harmonics (each blade of a tuned disk then sees the same samples,
    shifted, and the tuned blades' peaks agree)."""
    from ....hbm.core.fourier import default_nt

    if spec.nt is not None:
        return int(spec.nt)
    need = default_nt(tuple(int(h) for h in spec.harmonics))
    return n_blades * math.ceil(need / n_blades)


def curve_peak(f: np.ndarray, a: np.ndarray) -> tuple[float, float]:
    """The top ``(amplitude, frequency)`` of a sampled curve: its largest point, refined by
    the parabola through ``1 / a^2`` at that point and its two neighbours (a linear
    resonance's ``1 / |H|^2`` is close to a parabola in frequency near its peak); the point
    itself where the parabola has no minimum between the neighbours above it (a band end, a
    kinked top)."""
    i = int(np.argmax(a))
    if i == 0 or i == len(a) - 1 or not np.all(a[i - 1 : i + 2] > 0):
        return float(a[i]), float(f[i])
    x, y = f[i - 1 : i + 2], 1.0 / a[i - 1 : i + 2] ** 2
    c2, c1, c0 = np.polyfit(x - x[1], y, 2)
    if c2 <= 0:
        return float(a[i]), float(f[i])
    xv = -c1 / (2 * c2)
    yv = c0 - c1 * c1 / (4 * c2)
    if not (x[0] - x[1] < xv < x[2] - x[1]) or yv <= 0 or 1 / np.sqrt(yv) < a[i]:
        return float(a[i]), float(f[i])
    return float(1 / np.sqrt(yv)), float(x[1] + xv)


def plan_tasks(spec: StudySpec, pats: Patterns, eos: list[int]) -> list[tuple]:
    """Every task ``(damper, eo, pattern, config)``, dearest first: friction at the largest
    force first, the tuned disk before the patterns, the linear tasks last."""
    forces = sorted((float(f) for f in spec.forces), reverse=True)
    patterns = [TUNED, *range(pats.n_patterns)]
    return [
        (d, e, p, c)
        for c in (*forces, *LINEAR)
        for p in patterns
        for e in eos
        for d in spec.dampers
    ]


def run_mistuning(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Compute every task (resuming from ``out``), the amplification factors, figures and
    report; the JSON summary."""
    from ....assembly.params import load_contact_params
    from ....log import bars_enabled, stage
    from ....post.provenance import contact_args

    out = Path(out)
    comm = study_comm()
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    eos = study_eos(spec)
    pats = study_patterns(spec)
    n_b = int(spec.bladed_disk.n_blades)
    cp = load_contact_params(**contact_args(spec.as_dict()))
    with stage(timings, "disk sectors (geometry)"):
        recs = disk_sectors(spec, out, comm)
    cache = out / "cache" / "mistuning"
    cache.mkdir(parents=True, exist_ok=True)
    code = _code()

    def df_of(p: int) -> np.ndarray:
        return np.zeros(n_b) if p == TUNED else pats.df[p]

    plan = plan_tasks(spec, pats, eos)
    keys = [task_key(recs[d], cp, spec, e, (1 + df_of(p)) ** 2 - 1, c, code) for d, e, p, c in plan]
    todo = None
    if rank == 0:  # a key once (a pattern of zeros is the tuned disk)
        first = list({key: k for k, key in reversed(list(enumerate(keys)))}.values())[::-1]
        todo = [k for k in sorted(first) if force or not (cache / f"{keys[k]}.json").is_file()]
    if comm is not None:
        todo = comm.bcast(todo, root=0)
    log.info(
        "%d tasks (%d dampers x %d EOs x %d patterns and the tuned disk x %d configurations):"
        " %d to compute, %d cached",
        len(plan),
        len(spec.dampers),
        len(eos),
        pats.n_patterns,
        len(LINEAR) + len(spec.forces),
        len(todo),
        len(plan) - len(todo),
    )
    models: dict[str, Any] = {}

    def model(d: str):
        from ....pipeline.mistuning import build_mistuning_model

        if d not in models:  # every ND 0..N/2, once per damper on this rank
            models[d] = build_mistuning_model(
                recs[d],
                cp,
                int(spec.bladed_disk.sector_modes),
                int(spec.bladed_disk.damper_modes),
                float(spec.damping),
            )
        return models[d]

    def work(k: int) -> dict[str, Any]:
        d, e, p, c = plan[todo[k]]
        rec = {"damper": d, "pattern": p, **solve_task(model(d), e, df_of(p), c, spec)}
        write_json(cache / f"{keys[todo[k]]}.json", rec)
        if not bars_enabled():
            log.info(
                "task %d/%d on rank %d: %s EO %d %s %s: worst blade %.4g m/N (%.1f s)",
                k + 1,
                len(todo),
                rank,
                d,
                e,
                "tuned" if p == TUNED else f"pattern {p + 1}",
                rec["config"],
                max(rec["peak_m_per_n"]),
                rec["wall_s"],
            )
        return {"wall_s": rec["wall_s"]}

    with stage(timings, "tasks (wall)"):
        records = run_tasks(len(todo), work, comm, desc=f"{spec.name}: patterns") if todo else []
    sched = schedule_efficiency(records, size)
    summary: dict[str, Any] = {}
    if rank == 0:
        tasks = []
        computed = {todo[r["k"]] for r in records}
        for i, key in enumerate(keys):
            t = json.loads((cache / f"{key}.json").read_text())
            # a pattern of zeros shares the tuned disk's file: the plan says which task it is
            t["damper"], t["pattern"] = plan[i][0], plan[i][2]
            t["cached"] = i not in computed
            tasks.append(t)
        summary = {
            "study": spec.name,
            "kind": "mistuning",
            "out": str(out),
            "report": str(out / "report.html"),
            "ranks": size,
            "n_blades": n_b,
            "eos": eos,
            "eo_nd": eo_nd(eos, n_b),
            "n_patterns": pats.n_patterns,
            "std_percent": pats.std_percent,
            "sampling": pats.sampling,
            "seed": pats.seed,
            "n_tasks": len(plan),
            "n_computed": len(todo),
            "n_reused": len(plan) - len(todo),
            "schedule": {k: v for k, v in sched.items() if k != "busy_per_rank_s"},
        }
        timings["total"] = time.perf_counter() - t_start
        summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
        curves = worst_linear_curves(spec, out, tasks, pats, recs, cp, code, model)
        write_outputs(spec, out, tasks, pats, curves, summary, timings)
    if comm is not None:
        summary = comm.bcast(summary, root=0)
    return summary


def worst_linear_curves(spec, out, tasks, pats, recs, cp, code, model) -> dict[tuple, dict]:
    """The linear curves the figures draw: per (damper, EO, linear configuration) every
    blade's receptance (m/N) of the worst pattern (largest amplification factor) and of the
    tuned disk over their bands, 300 frequencies; cached beside the tasks."""
    from ....pipeline.mistuning import linear_blade_response

    n_b = int(spec.bladed_disk.n_blades)
    af = amplification(tasks)
    got: dict[tuple, dict] = {}
    for (d, e, c), a in af.items():
        if c not in LINEAR or not np.isfinite(a["af"]).any():
            continue
        p = int(np.nanargmax(a["af"]))
        for which, q in (("worst", p), ("tuned", TUNED)):
            df = np.zeros(n_b) if q == TUNED else pats.df[q]
            delta = (1 + df) ** 2 - 1
            key = task_key(recs[d], cp, spec, e, delta, c, code)
            path = out / "cache" / "mistuning" / f"curve_{key}.json"
            if not path.is_file():
                t = a["tasks"][q]
                f = np.linspace(*t["band_hz"], 300)
                amp = np.abs(linear_blade_response(model(d), delta, e, f, c))
                write_json(
                    path,
                    {"freq_hz": f.tolist(), "amp_m_per_n": [list(r) for r in amp.T.tolist()]},
                )
            got[(d, e, c, which)] = {"pattern": q, **json.loads(path.read_text())}
    return got
