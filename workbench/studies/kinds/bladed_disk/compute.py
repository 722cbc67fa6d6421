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
solver sources (:func:`workbench.studies.engine.plan.solver_code_version`), so a
study killed part way resumes where it stopped and a second run reuses every
case; ``force`` recomputes. The cases are handed to whichever MPI rank is free
(:func:`workbench.studies.engine.schedule.run_tasks`).

The answer: per damper and force its worst EO (the largest peak) and, per
EO and force, the damper with the smallest peak.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ....errors import InputError
from ....io import digest, write_json
from ....io.csv_rows import write_rows_csv
from ...engine.outputs import write_manifest_and_report
from ...engine.plan import solver_code_version
from ...engine.schedule import run_tasks, study_comm
from ...engine.spec import StudySpec

log = logging.getLogger(__name__)

ZETA = 0.005  # modal damping ratio of the bladed sector's reduced modes (sector.py's default)


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


def nd_and_direction(eo: int, n_blades: int) -> tuple[int, str]:
    """The ND the harmonic-1 excitation of ``eo`` lives at and its wave's direction:
    "standing" (ND 0 or N/2), "forward" (``eo mod N <= N/2``) or "backward"."""
    k = eo % n_blades
    nd = min(k, n_blades - k)
    if nd == 0 or 2 * nd == n_blades:
        return nd, "standing"
    return nd, "forward" if k <= n_blades // 2 else "backward"


def disk_sectors(spec: StudySpec, out: Path, comm) -> dict[str, Any]:
    """Every damper's disk sector, built on rank 0 (gmsh is serial), loaded by the others."""
    import dolfinx  # noqa: F401 - collective PETSc initialisation before rank 0 builds

    from ....errors import run_on_root
    from ....geometry.disk_build import DiskSector, build_disk_sector

    o = spec.bladed_disk
    mesh = {
        k: float(v)
        for k, v in (
            ("contact_size_mm", o.contact_mesh_size),
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
            "zeta": ZETA,
            "harmonics": [int(h) for h in spec.harmonics],
            "eo": int(eo),
            "force_n": float(force_n),
            "code": solver_code_version(),
        }
    )


def solve_case(model, eo: int, force_n: float, harmonics: tuple[int, ...]) -> dict[str, Any]:
    """One case's record: the sector's forced response at ``eo`` and ``force_n`` and its peak."""
    from ....pipeline.sector import sector_forced_response

    t0 = time.perf_counter()
    br, info = sector_forced_response(model, eo, force_n, None, harmonics)
    amp = np.asarray(br.out_amp[:, 0], dtype=float)
    i = int(amp.argmax()) if len(amp) else -1
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
                zeta=ZETA,
            )
        rec = {"damper": d, **solve_case(models[d], e, f, harmonics)}
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
    summary: dict[str, Any] = {
        "study": spec.name,
        "kind": "bladed_disk",
        "out": str(out),
        "report": str(out / "report.html"),
        "ranks": size,
        "n_blades": n_b,
        "eos": eos,
        "eo_nd": {
            str(e): dict(zip(("nd", "direction"), nd_and_direction(e, n_b), strict=True))
            for e in eos
        },
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
    if rank == 0:
        timings["total"] = time.perf_counter() - t_start
        summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
        write_outputs(spec, out, cases, worst, best, fans, eos, forces, summary, timings)
    if comm is not None:
        summary = comm.bcast(summary, root=0)
    return summary


def write_outputs(spec, out, cases, worst, best, fans, eos, forces, summary, timings) -> None:
    """Tables (CSV), results (HDF5 with units), figures, summary JSON and report (rank 0)."""
    import h5py

    from .figures import plot_energy_vs_eo, plot_fan_eo, plot_peaks_vs_eo
    from .report import bladed_disk_sections

    n_b = int(spec.bladed_disk.n_blades)
    dampers = list(spec.dampers)
    tables, figs = out / "tables", out / "figures"
    tables.mkdir(parents=True, exist_ok=True)
    figs.mkdir(parents=True, exist_ok=True)
    cols = [
        "damper",
        "eo",
        "nd",
        "direction",
        "force_n",
        "peak_m",
        "peak_hz",
        "friction_energy_j",
        "stuck_hz",
        "peak_at_band_edge",
        "completed",
        "cached",
        "n_points",
        "wall_s",
        "message",
    ]
    write_rows_csv(tables / "bladed_disk_cases.csv", cases, cols)
    write_rows_csv(tables / "bladed_disk_worst.csv", worst)
    write_rows_csv(tables / "bladed_disk_best.csv", best)
    fan_rows = [
        {
            "nodal_diameter": k,
            **{
                f"{d}_family_{j + 1}_hz": float(fans[d][k, j])
                for d in dampers
                for j in range(fans[d].shape[1])
            },
        }
        for k in range(n_b // 2 + 1)
    ]
    write_rows_csv(tables / "bladed_disk_fan.csv", fan_rows)

    shape = (len(dampers), len(forces), len(eos))
    grid = {q: np.full(shape, np.nan) for q in ("peak_m", "peak_hz", "friction_energy_j")}
    lower = np.zeros(shape, dtype=bool)
    for c in cases:
        i, j, k = dampers.index(c["damper"]), forces.index(c["force_n"]), eos.index(c["eo"])
        for q in grid:
            grid[q][i, j, k] = np.nan if c[q] is None else c[q]
        # a curve that stopped early or peaks on its band edge: its peak is a lower bound
        lower[i, j, k] = not c["completed"] or c["peak_at_band_edge"]
    units = {
        "peak_m": (
            "m",
            "peak amplitude of the response point along the excitation [damper, force, eo]",
        ),
        "peak_hz": ("Hz", "frequency of the peak [damper, force, eo]"),
        "friction_energy_j": (
            "J",
            "friction energy per sector and cycle at the peak [damper, force, eo]",
        ),
        "forces_n": ("N", "harmonic-1 force on each blade"),
        "eos": ("1", "engine orders"),
        "nd": ("1", "nodal diameter of the harmonic-1 excitation of each EO"),
        "nodal_diameters": ("1", "nodal diameters of the fan diagram"),
    }
    with h5py.File(out / "bladed_disk.h5", "w") as h:
        for q, a in grid.items():
            h[q] = a
        h["forces_n"] = np.array(forces)
        h["eos"] = np.array(eos)
        h["nd"] = np.array([nd_and_direction(e, n_b)[0] for e in eos])
        h["nodal_diameters"] = np.arange(n_b // 2 + 1)
        h.attrs["dampers"] = json_list(dampers)
        h.attrs["direction"] = json_list([nd_and_direction(e, n_b)[1] for e in eos])
        h.attrs["n_blades"] = n_b
        for d in dampers:
            name = f"fan_stuck_hz/{d}"
            h[name] = fans[d]
            h[name].attrs["unit"] = "Hz"
            h[name].attrs["description"] = (
                "stuck-damper cyclic frequencies [nodal diameter, family]"
            )
        for q, (u, text) in units.items():
            h[q].attrs["unit"] = u
            h[q].attrs["description"] = text

    curves = {(c["damper"], c["force_n"], c["eo"]): c for c in cases}
    paths = {
        "peaks": plot_peaks_vs_eo(
            dampers, forces, eos, grid["peak_m"], n_b, figs / "bladed_disk_peaks.png", lower
        ),
        "energy": plot_energy_vs_eo(
            dampers, forces, eos, grid["friction_energy_j"], figs / "bladed_disk_energy.png", lower
        ),
        "fan": plot_fan_eo(
            fans,
            n_b,
            worst,
            [c for c in curves.values() if c["peak_hz"]],
            figs / "bladed_disk_fan.png",
        ),
    }
    summary["files"] = {
        "h5": str(out / "bladed_disk.h5"),
        "cases_csv": str(tables / "bladed_disk_cases.csv"),
        "worst_csv": str(tables / "bladed_disk_worst.csv"),
        "best_csv": str(tables / "bladed_disk_best.csv"),
        **{f"{k}_png": str(p) for k, p in paths.items()},
    }
    head = [
        f"{w['damper']} at {w['force_n']:g} N: worst EO {w['worst_eo']} (ND {w['nd']}, "
        f"{w['direction']}), peak {w['worst_peak_m']:.4g} m at {w['peak_hz']:.1f} Hz"
        + (f" (branch stopped early at EO {w['stopped_eos']})" if w["stopped_eos"] else "")
        for w in worst
    ]
    summary["headline"] = head
    sections = bladed_disk_sections(
        n_b, eos, summary["eo_nd"], worst, best, summary["failed"], summary["at_band_edge"]
    )
    write_manifest_and_report(
        out,
        spec,
        f"bladed disk of {n_b} blades: dampers x engine orders x forces,",
        head,
        timings,
        sections,
    )
    write_json(out / "bladed_disk.json", summary)


def json_list(v: list) -> str:
    import json

    return json.dumps(v)
