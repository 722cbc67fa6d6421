"""Bladed-disk study: dampers x engine orders x forces on one cyclic sector of a tuned disk.

For each damper one disk sector is meshed (:func:`workbench.geometry.disk_build.build_disk_sector`,
its own cache), its fan diagram computed with the damper stuck
(:func:`workbench.fe.cyclic.fan`) and, per rank, its sector harmonic-balance
model built at every nodal diameter (ND) 0..N/2
(:func:`workbench.pipeline.sector.build_sector_model`). A *case* is one
(damper, engine order, force): :func:`workbench.pipeline.sector.sector_forced_response`
over 0.9..1.1 times the first stuck frequency of the EO's ND, and its peak
(largest ``|y|`` of the response point along the excitation, m), the peak's
frequency and the friction energy per sector and cycle there.

Each case is kept in ``out/cache/bladed_disk/<digest>.json``; the digest
covers the disk sector's own digest (geometry, mesh, N), the contact
parameters, the reduction's sizes, the EO, the force, the harmonics and the
solver's and the FE package's sources
(:func:`workbench.studies.engine.plan.disk_code_version`), so a
study killed part way resumes where it stopped and a second run reuses every
case; ``force`` recomputes. The cases are handed to whichever MPI rank is free
(:func:`workbench.studies.engine.schedule.run_tasks`).

The answer: per damper and force its worst EO (the largest peak) and, per
EO and force, the damper with the smallest peak. After the cases, one task
per damper (:mod:`.post`, cached too): the coupling screen at every ND and,
at the damper's worst peak (largest force), the sector's field (VTU) and
Hill's stability on the whole disk. The files: :mod:`.outputs`.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ....errors import InputError
from ....io import digest, write_json
from ...engine.plan import disk_code_version
from ...engine.schedule import run_tasks, study_comm
from ...engine.spec import StudySpec
from .outputs import eo_nd, write_outputs

log = logging.getLogger(__name__)

RECORD_VERSION = 2  # 2: a case keeps its peak's unknowns and every point's contact status
# The mean (harmonic-0) unknowns count in the continuation's arc length. At EO 0 the
# damper's mean position drifts at the slip onset while the harmonics and the frequency
# barely move; with weight 0 the step does not see that drift and the corrector, asked to
# jump the mean, stops (the cone's EO-0 30 N branch at 434.27 Hz, before its resonance).
# Elsewhere the curve is the same: peaks within 1.2e-5 of weight 0 on the shipped study.
DC_WEIGHT = 1.0


def study_eos(spec: StudySpec) -> list[int]:
    """The study's engine orders: ``eos`` in order without repeats, or every EO 0..N/2."""
    n = int(spec.bladed_disk.n_blades)
    if n < 2:
        raise InputError("n-blades", n, "a whole number >= 2")
    eos = list(spec.bladed_disk.eos) or list(range(n // 2 + 1))
    for e in eos:
        if isinstance(e, bool) or not float(e).is_integer() or e < 0:
            raise InputError("eos", e, "whole numbers >= 0")
    return list(dict.fromkeys(int(e) for e in eos))


def disk_sectors(spec: StudySpec, out: Path, comm) -> dict[str, Any]:
    """Every damper's disk sector, built on rank 0 (gmsh is serial), loaded by the others."""
    import dolfinx  # noqa: F401 - collective PETSc initialisation before rank 0 builds

    from ....errors import run_on_root
    from ....geometry.disk_build import DiskSector, build_disk_sector

    o = spec.bladed_disk
    mesh = {
        k: float(v)
        for k, v in (
            ("contact_size_mm", spec.contact_mesh_size),
            ("damper_size_mm", o.damper_mesh_size),
        )
        if v is not None
    }
    recs = {}
    for damper in spec.dampers:
        folder = out / "cache" / "disk" / damper

        def build(d=damper, f=folder):
            return build_disk_sector(
                d,
                f,
                geometry_file=spec.geometry,
                n_blades=int(spec.bladed_disk.n_blades),
                size_mm=spec.mesh_size,
                overrides=_overrides(d, mesh, o.contact_points),
            )

        if comm is None:
            recs[damper] = build()
        else:
            rec = run_on_root(comm, build, "disk build")
            recs[damper] = rec if comm.rank == 0 else DiskSector.load(folder / "disk.h5")
    return recs


def _overrides(damper: str, mesh: dict, points: int | None) -> dict | None:
    """The geometry overrides of the study's mesh sizes and contact points for ``damper``."""
    over: dict[str, Any] = {"rig": {"mesh": mesh}} if mesh else {}
    if points is not None:
        pts = {"wedge": {"n_contact_rows": 2, "n_contact_per_row": int(points)}}
        over[damper] = pts.get(damper, {"n_contact_points": int(points)})
    return over or None


def case_key(rec, cp, spec: StudySpec, eo: int, force_n: float) -> str:
    """The cache key of one (damper sector, EO, force) case."""
    return digest(
        {
            "kind": "bladed_disk",
            "sector": rec.digest,
            "contact": repr(cp),
            "sector_modes": int(spec.bladed_disk.sector_modes),
            "damper_modes": int(spec.bladed_disk.damper_modes),
            "zeta": float(spec.damping),
            "harmonics": [int(h) for h in spec.harmonics],
            "nt": None if spec.nt is None else int(spec.nt),
            "max_points": int(spec.max_points),
            "eo": int(eo),
            "force_n": float(force_n),
            "code": disk_code_version(),
            "record": RECORD_VERSION,
            "dc_weight": DC_WEIGHT,
        }
    )


def solve_case(
    model, eo: int, force_n: float, harmonics: tuple[int, ...], nt=None, max_points: int = 400
) -> dict[str, Any]:
    """One case's record: the sector's forced response at ``eo`` and ``force_n`` and its peak
    (``nt`` AFT samples, None: the solver's default; at most ``max_points`` points)."""
    from ....hbm.core.options import SolverOptions
    from ....pipeline.sector import sector_forced_response

    t0 = time.perf_counter()
    opts = SolverOptions(dc_weight=DC_WEIGHT, max_points=int(max_points))
    br, info = sector_forced_response(model, eo, force_n, None, harmonics, nt, options=opts)
    from ....contact.law import STATUS_NAMES

    amp = np.asarray(br.out_amp[:, 0], dtype=float)
    i = int(amp.argmax()) if len(amp) else -1
    status = np.asarray(br.status, dtype=int).reshape(len(amp), -1)
    return {
        "eo": int(eo),
        "force_n": float(force_n),
        "nd": int(info["nd_of_harmonic"]["1"]),
        "direction": info["direction_of_harmonic"]["1"],
        "stuck_hz": float(info["stuck_hz"][0]),
        "completed": bool(br.completed),
        "message": str(br.message),
        "n_points": int(len(amp)),
        "peak_m": float(amp[i]) if i >= 0 else None,
        "peak_hz": float(br.freq_hz[i]) if i >= 0 else None,
        "friction_energy_j": float(np.sum(br.friction_energy[i])) if i >= 0 else None,
        "freq_hz": [float(v) for v in br.freq_hz],
        "amp_m": [float(v) for v in amp],
        # per point the status of every pair (0 stuck .. 3 full separation, STATUS_NAMES)
        "status": status.tolist(),
        "side": [int(v) for v in model.side],  # 0: this sector's platform, 1: the next one's
        "status_at_peak": (
            {n: int(np.sum(status[i] == s)) for s, n in enumerate(STATUS_NAMES)} if i >= 0 else {}
        ),
        # the peak point's unknowns (SectorBalance's layout): the field at the peak
        "x_peak": [float(v) for v in br.x[i]] if i >= 0 else [],
        "wall_s": time.perf_counter() - t0,
    }


def answer(cases: list[dict], dampers: list[str], forces: list[float], eos: list[int]):
    """The answer tables: per (damper, force) the worst EO (largest peak); per (EO, force) the
    damper with the smallest peak. Cases without a peak are left out."""
    peak = {(c["damper"], c["force_n"], c["eo"]): c for c in cases if c["peak_m"] is not None}
    worst, best = [], []
    for d in dampers:
        for f in forces:
            got = [peak[(d, f, e)] for e in eos if (d, f, e) in peak]
            if got:
                w = max(got, key=lambda c: c["peak_m"])
                worst.append(
                    {
                        "damper": d,
                        "force_n": f,
                        "worst_eo": w["eo"],
                        "nd": w["nd"],
                        "direction": w["direction"],
                        "worst_peak_m": w["peak_m"],
                        "peak_hz": w["peak_hz"],
                        "peak_at_band_edge": w.get("peak_at_band_edge", False),
                        # EOs whose branch stopped early: their peak is a lower bound
                        "stopped_eos": " ".join(str(c["eo"]) for c in got if not c["completed"]),
                    }
                )
    for e in eos:
        for f in forces:
            got = [peak[(d, f, e)] for d in dampers if (d, f, e) in peak]
            if got:
                b = min(got, key=lambda c: c["peak_m"])
                best.append(
                    {
                        "eo": e,
                        "nd": b["nd"],
                        "direction": b["direction"],
                        "force_n": f,
                        "best_damper": b["damper"],
                        "best_stopped_early": not b["completed"],  # its peak: a lower bound
                        **{f"{c['damper']}_peak_m": c["peak_m"] for c in got},
                    }
                )
    return worst, best


def run_bladed_disk(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Compute every case (resuming from ``out``), the answer tables, figures and report."""
    from ....assembly.params import load_contact_params
    from ....fe.cyclic import assemble_sector, fan
    from ....log import bars_enabled, stage
    from ....post.provenance import contact_args

    out = Path(out)
    comm = study_comm()
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    eos = study_eos(spec)
    n_b = int(spec.bladed_disk.n_blades)
    forces = [float(f) for f in spec.forces]
    harmonics = tuple(int(h) for h in spec.harmonics)
    cp = load_contact_params(**contact_args(spec.as_dict()))
    with stage(timings, "disk sectors (geometry)"):
        recs = disk_sectors(spec, out, comm)
    cache = out / "cache" / "bladed_disk"
    cache.mkdir(parents=True, exist_ok=True)

    with stage(timings, "fan diagrams"):
        fans = {}
        for d, rec in recs.items():
            path = (
                cache / f"fan_{digest([rec.digest, repr(cp), spec.bladed_disk.fan_families])}.json"
            )
            if path.is_file() and not force:
                fans[d] = np.array(__import__("json").loads(path.read_text()))
                continue
            fans[d] = fan(
                assemble_sector(rec, cp, with_damper=True), spec.bladed_disk.fan_families, comm
            )
            if rank == 0:
                write_json(path, fans[d].tolist())

    plan = [(d, e, f) for d in spec.dampers for e in eos for f in forces]
    keys = [case_key(recs[d], cp, spec, e, f) for d, e, f in plan]
    todo = [k for k, key in enumerate(keys) if force or not (cache / f"{key}.json").is_file()]
    log.info(
        "%d cases (%d dampers x %d EOs x %d forces): %d to compute, %d cached",
        len(plan),
        len(spec.dampers),
        len(eos),
        len(forces),
        len(todo),
        len(plan) - len(todo),
    )
    models: dict[str, Any] = {}

    def work(k: int) -> dict[str, Any]:
        from ....pipeline.sector import build_sector_model

        d, e, f = plan[todo[k]]
        if d not in models:  # every ND 0..N/2, once per damper on this rank
            models[d] = build_sector_model(
                recs[d],
                cp,
                None,
                n_modes=int(spec.bladed_disk.sector_modes),
                n_damper_modes=int(spec.bladed_disk.damper_modes),
                zeta=float(spec.damping),
            )
        rec = {"damper": d, **solve_case(models[d], e, f, harmonics, spec.nt, spec.max_points)}
        write_json(cache / f"{keys[todo[k]]}.json", rec)
        if not bars_enabled():
            log.info(
                "case %d/%d on rank %d: %s EO %d (ND %d %s) %g N: peak %.4g m at %.2f Hz (%.1f s)",
                k + 1,
                len(todo),
                rank,
                d,
                e,
                rec["nd"],
                rec["direction"],
                f,
                rec["peak_m"] or float("nan"),
                rec["peak_hz"] or float("nan"),
                rec["wall_s"],
            )
        return {"wall_s": rec["wall_s"]}

    with stage(timings, "cases (wall)"):
        records = run_tasks(len(todo), work, comm, desc=f"{spec.name}: cases") if todo else []
    import json

    computed = {todo[r["k"]] for r in records}
    cases = []
    for i, key in enumerate(keys):
        c = json.loads((cache / f"{key}.json").read_text())
        c["cached"] = i not in computed
        amp = c["amp_m"]  # a peak on the band's first or last point is not a resonance peak
        c["peak_at_band_edge"] = bool(amp) and int(np.argmax(amp)) in (0, len(amp) - 1)
        cases.append(c)
    worst, best = answer(cases, list(spec.dampers), forces, eos)
    with stage(timings, "screen and worst-peak fields"):
        post = _post(spec, out, recs, cp, plan, keys, cases, worst, models, comm, force)
    summary: dict[str, Any] = {
        "study": spec.name,
        "kind": "bladed_disk",
        "out": str(out),
        "report": str(out / "report.html"),
        "ranks": size,
        "n_blades": n_b,
        "eos": eos,
        "eo_nd": eo_nd(eos, n_b),
        "n_cases": len(plan),
        "n_computed": len(todo),
        "n_reused": len(plan) - len(todo),
        "worst": worst,
        "best": [{k: v for k, v in b.items() if not k.endswith("_peak_m")} for b in best],
        "failed": [
            {"damper": c["damper"], "eo": c["eo"], "force_n": c["force_n"], "message": c["message"]}
            for c in cases
            if not c["completed"]
        ],
        "at_band_edge": [
            {"damper": c["damper"], "eo": c["eo"], "force_n": c["force_n"], "peak_hz": c["peak_hz"]}
            for c in cases
            if c["peak_at_band_edge"]
        ],
    }
    summary["screen"] = [r for d in spec.dampers for r in post[d]["screen"]]
    summary["worst_peak_field"] = [post[d]["worst"] for d in spec.dampers if post[d]["worst"]]
    if rank == 0:
        timings["total"] = time.perf_counter() - t_start
        summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
        write_outputs(spec, out, cases, worst, best, fans, eos, forces, summary, timings)
    if comm is not None:
        summary = comm.bcast(summary, root=0)
    return summary


def _post(spec, out, recs, cp, plan, keys, cases, worst, models, comm, force) -> dict:
    """Per damper the screen at every ND and the field at its worst peak (the worst EO at
    the largest force): :func:`.post.damper_post`, cached, one task per damper on any rank."""
    import json

    from ....pipeline.sector import build_sector_model
    from .post import damper_post, post_key

    cache = out / "cache" / "bladed_disk"
    zeta = float(spec.damping)
    f_max = max(float(f) for f in spec.forces)
    at = {(d, e, f): i for i, (d, e, f) in enumerate(plan)}
    picks, pkeys = {}, {}
    for d in spec.dampers:
        w = next((w for w in worst if w["damper"] == d and w["force_n"] == f_max), None)
        i = None if w is None else at[(d, w["worst_eo"], f_max)]
        picks[d] = i
        pkeys[d] = post_key(
            keys[i] if i is not None else "", recs[d].digest, cp, spec, zeta, RECORD_VERSION
        )
    todo = [d for d in spec.dampers if force or not (cache / f"post_{pkeys[d]}.json").is_file()]

    def work(k: int) -> dict:
        d = todo[k]
        if d not in models:
            models[d] = build_sector_model(
                recs[d],
                cp,
                None,
                n_modes=int(spec.bladed_disk.sector_modes),
                n_damper_modes=int(spec.bladed_disk.damper_modes),
                zeta=zeta,
            )
        i = picks[d]
        res = damper_post(models[d], recs[d], None if i is None else cases[i], spec, out, zeta)
        write_json(cache / f"post_{pkeys[d]}.json", res)
        log.info("%s: screen and worst-peak field (%.1f s)", d, res["wall_s"])
        return {}

    if todo:
        run_tasks(len(todo), work, comm, desc=f"{spec.name}: screen")
    return {d: json.loads((cache / f"post_{pkeys[d]}.json").read_text()) for d in spec.dampers}
