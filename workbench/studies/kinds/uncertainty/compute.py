"""The uncertainty study: which damper is robust when the inputs are not what the drawing says.

Per damper and family (inter-blade phase) at one excitation level, the
peak amplitude, resonance frequency and friction energy per cycle of the
frequency response are computed for a Saltelli design of the uncertain
inputs (``uq-inputs``; distributions named in the study file):

========== ===================================================== ==========
input      what varies                                           kind
========== ===================================================== ==========
mu         friction coefficient                                  absolute
cf         centrifugal force on the damper                       factor
kt         tangential contact stiffness (line and face values)   factor
kn         normal contact stiffness (line and face values)       factor
damping    modal damping ratio of the assembly                   absolute
seat-tilt  misalignment of one side's seat, deg                  absolute
========== ===================================================== ==========

A distribution is ``uniform LO HI``, ``normal MEAN SD [LO HI]`` or
``lognormal MEDIAN SIGMA_LN [LO HI]`` (bounds truncate). ``factor`` inputs
multiply the nominal value (study option or ``geometry/contact.toml``).

Design: SALib's Saltelli extension of a scrambled Sobol sequence
(``SALib.sample.sobol``, which draws from ``scipy.stats.qmc.Sobol``) on the
unit cube, mapped through each input's inverse CDF. Its ``N (D + 2)`` rows
feed SALib's Sobol first- and total-order indices; its ``A`` and ``B`` rows
(``2 N`` quasi-random draws of the joint distribution) give the
distributions, percentiles and exceedance probabilities. The design of
``N`` is the first ``N`` base points of the design of ``2 N``, row for row,
so a larger study reuses every case of a smaller one.

Cases: each design row is one case of the runner (``plan.make_case`` on
the study's settings with the row's absolute values), cached under its
digest plus the seat tilt and the imperfection model's source: a killed
study resumes, ``--force`` recomputes. The FE reduction and the coupling
matrix are built once per damper (``pipeline.prepare_model`` on the nominal
inputs); a sample only re-makes the contact parameters, the preload vector
(the seat tilt, :mod:`workbench.studies.kinds.uncertainty.imperfection`) and the modal
damping: nothing is re-meshed or re-reduced.

MPI: models are prepared on every rank together, then the samples are
handed out by a shared counter (an MPI one-sided ``Fetch_and_op`` on a
window of rank 0): a rank takes the next sample when it is free, so a
separating sample 10 times dearer than a stuck one does not hold up the
others (``uq-schedule = "static"`` is round-robin, for comparison). The
numbers do not depend on the rank count: each sample is solved alone from
its own inputs.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ....io import write_json
from ....log import bars_enabled
from ....post.results import CaseResult, family_name
from ....post.uncertainty import (
    INPUT_LABELS,
    QUANTITIES,
    Design,
    Distribution,
    analysis_summary,
    answer_rows,
    driver,
    driver_verdict,
    headline,
    index_rows,
    make_design,
    ranking_confidence,
    sobol_indices,
    statistics,
    stats_rows,
)
from ...engine.plan import make_case
from ...engine.schedule import (
    run_tasks,
    schedule_efficiency,
    study_comm,
)
from ...engine.spec import StudySpec
from .samples import (
    Sample,
    base_settings,
    nominal_contact,
    plan_samples,
    prepare_sample,
    sample_settings,
    study_distributions,
)

log = logging.getLogger(__name__)


# ---- the study --------------------------------------------------------------------------


def run_uncertainty(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Compute every sample (resuming from ``out``), then statistics, indices and report."""
    from ....pipeline import prepare_model, solve_case
    from ...engine.runner import case_done

    out = Path(out)
    comm = study_comm()
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    dists = study_distributions(spec)
    design = make_design(dists, spec.uncertainty.uq_samples, spec.uncertainty.uq_seed)
    samples = plan_samples(spec, design)
    case_dir = out / "cache" / "cases"
    case_dir.mkdir(parents=True, exist_ok=True)
    todo_ids = None
    if rank == 0:
        todo_ids = [s.case.digest for s in samples if force or not case_done(case_dir, s.case)]
    if comm is not None:
        todo_ids = comm.bcast(todo_ids, root=0)
    want = set(todo_ids)
    todo = [s for s in samples if s.case.digest in want]
    todo = list({s.case.digest: s for s in todo}.values())  # equal rows solve once
    log.info(
        "%d samples (%d dampers x %d families x %d design rows): %d to compute, %d cached",
        len(samples),
        len(spec.dampers),
        len(spec.phases),
        design.n_rows,
        len(todo),
        len(samples) - len(todo),
    )

    # 1. one base model per damper (nominal inputs): geometry, reduction, assembly
    t0 = time.perf_counter()
    bases: dict[str, Any] = {}
    nominal = sample_settings(base_settings(spec), nominal_contact(spec), {})
    for damper in dict.fromkeys(s.case.damper for s in todo):
        c = make_case(damper, spec.phases[0], spec.forces[0], nominal)
        bases[damper] = prepare_model(c, out, force=force, comm=comm)
    timings["models (geometry, reduction, assembly)"] = time.perf_counter() - t0

    # 2. samples: interleave dampers and families so that a rank count's share mixes them
    order = sorted(todo, key=lambda s: (s.row, s.case.damper, s.case.phase_deg))

    def work(k: int) -> dict[str, Any]:
        s = order[k]
        c0 = time.process_time()
        prep = prepare_sample(bases[s.case.damper], s.case, s.tilt_deg)
        res = solve_case(prep, s.case)
        res.timings["hbm_cpu"] = time.process_time() - c0  # this rank's CPU: the projection's
        res.save(case_dir / f"{s.case.digest}.h5")
        if res.branch.failed:
            log.warning("sample %s stopped early: %s", s.case.name, res.branch.message)
        if not bars_enabled():
            log.info(
                "sample %d/%d on rank %d: %s (%.1f s)",
                k + 1,
                len(order),
                rank,
                s.case.name,
                res.timings.get("hbm", 0.0),
            )
        return {
            "digest": s.case.digest,
            "hbm_s": float(res.timings.get("hbm", 0.0)),
            "cpu_s": float(res.timings["hbm_cpu"]),
            "failed": bool(res.branch.failed),
        }

    t0 = time.perf_counter()
    records = (
        run_tasks(
            len(order),
            work,
            comm,
            static=spec.uncertainty.uq_schedule == "static",
            desc=f"{spec.name}: samples",
        )
        if order
        else []
    )
    timings["samples (wall)"] = time.perf_counter() - t0
    sched = schedule_efficiency(records, size)
    sched["schedule"] = spec.uncertainty.uq_schedule
    sched["n_computed"] = len(records)

    summary: dict[str, Any] = {
        "study": spec.name,
        "kind": "uncertainty",
        "out": str(out),
        "report": str(out / "report.html"),
        "ranks": size,
        "n_samples": len(samples),
        "n_computed": len(order),
        "n_reused": len(samples) - len(order),
        "schedule": sched,
    }
    t0 = time.perf_counter()
    results = collect(samples, design, case_dir, comm)  # collective: a share per rank
    if rank == 0:
        if records:
            write_json(out / "tables" / "schedule_records.json", records)
        else:  # nothing computed: the report keeps the last computing run's schedule
            sched = _previous_schedule(out) or sched
        analysis = analyse(spec, design, dists, results)
        summary.update(analysis_summary(analysis))
        timings["post and report"] = time.perf_counter() - t0  # before the report is written
        timings["total"] = time.perf_counter() - t_start
        summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
        write_uncertainty_outputs(spec, out, design, dists, results, analysis, sched, timings)
    if comm is not None:
        summary = comm.bcast(summary, root=0)
    return summary


# ---- post-processing --------------------------------------------------------------------


def _previous_schedule(out: Path) -> dict[str, Any] | None:
    import json

    try:
        prev = json.loads((out / "uncertainty.json").read_text()).get("schedule")
    except (OSError, ValueError):
        return None
    return prev if prev and prev.get("n_computed") else None


def sample_output(case_dir: Path, s: Sample) -> dict[str, Any]:
    """The scalar outputs of one finished sample (read from its case file)."""
    res = CaseResult.load(case_dir / f"{s.case.digest}.h5")
    summ = res.summary()
    out = {q: (np.nan if summ.get(q) is None else float(summ[q])) for q, _, _ in QUANTITIES}
    out.update(
        hbm_s=float(res.timings.get("hbm", np.nan)),
        cpu_s=float(res.timings.get("hbm_cpu", np.nan)),
        failed=bool(res.branch.failed),
    )
    return out


def collect(
    samples: list[Sample], design: Design, case_dir: Path, comm=None
) -> dict[tuple, dict] | None:
    """(damper, phase) -> the design-ordered outputs of its samples (NaN where no peak).

    Under MPI each rank reads a share of the case files (rank r: samples r,
    r + P, ...) and rank 0 assembles them (the other ranks get None): the
    serial part of the post-processing does not grow with the sample count.
    """
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    mine = [(k, sample_output(case_dir, samples[k])) for k in range(rank, len(samples), size)]
    if comm is not None:
        parts = comm.gather(mine, root=0)
        if rank != 0:
            return None
        mine = [x for part in parts for x in part]
    outputs = dict(mine)
    groups: dict[tuple, dict] = {}
    for k, s in enumerate(samples):
        g = groups.setdefault(
            (s.case.damper, s.case.phase_deg),
            {q: np.full(design.n_rows, np.nan) for q, _, _ in QUANTITIES},
        )
        g.setdefault("hbm_s", np.full(design.n_rows, np.nan))
        g.setdefault("cpu_s", np.full(design.n_rows, np.nan))
        g.setdefault("failed", np.zeros(design.n_rows, bool))
        g.setdefault("digests", [""] * design.n_rows)
        o = outputs[k]
        for q in (*(q for q, _, _ in QUANTITIES), "hbm_s", "cpu_s", "failed"):
            g[q][s.row] = o[q]
        g["digests"][s.row] = s.case.digest
    return groups


def analyse(
    spec: StudySpec, design: Design, dists: dict[str, Distribution], results: dict[tuple, dict]
) -> dict[str, Any]:
    """Statistics of each quantity and Sobol indices per damper and family.

    A sample whose solve stopped early (``failed``) has no trustworthy peak
    (the branch may stop on its way up): its outputs count as missing, in
    the statistics (``n_missing``) and in the indices (its base point is
    dropped). The dampers of a family are compared on the SAME samples: the
    A and B rows every damper of the family solved (``p95_common``), which
    decides the robust damper; ``p95`` over each damper's own solved rows is
    reported beside. The threshold (``uq-threshold``, else 1.2 x the
    family's median peak over every damper) is per family.
    """
    ab = design.ab_rows
    clean = {}
    for key, g in results.items():
        bad = np.asarray(g["failed"], bool)
        clean[key] = {q: np.where(bad, np.nan, g[q]) for q, _, _ in QUANTITIES}
    fams = list(dict.fromkeys(ph for _, ph in results))
    thresholds: dict[str, float | None] = {}
    common: dict[float, np.ndarray] = {}
    for ph in fams:
        keys = [k for k in results if k[1] == ph]
        ok = np.all([np.isfinite(clean[k]["peak_amplitude_mm"][ab]) for k in keys], axis=0)
        common[ph] = ab[ok]
        if spec.uncertainty.uq_threshold is not None:
            thresholds[family_name(ph)] = float(spec.uncertainty.uq_threshold)
        else:
            pk = np.concatenate([clean[k]["peak_amplitude_mm"][ab] for k in keys])
            pk = pk[np.isfinite(pk)]
            thresholds[family_name(ph)] = 1.2 * float(np.median(pk)) if pk.size else None
    groups = []
    for (damper, phase), g in results.items():
        fam = family_name(phase)
        thr = thresholds[fam]
        c = clean[(damper, phase)]
        row: dict[str, Any] = {
            "damper": damper,
            "phase_deg": phase,
            "family": fam,
            "threshold_mm": thr,
            "stats": {},
            "indices": {},
        }
        for q, _, _ in QUANTITIES:
            row["stats"][q] = statistics(c[q][ab], thr if q == "peak_amplitude_mm" else None)
            row["indices"][q] = sobol_indices(design, c[q], seed=spec.uncertainty.uq_seed)
        pc = c["peak_amplitude_mm"][common[phase]]
        row["stats"]["peak_amplitude_mm"]["n_common"] = int(pc.size)
        if pc.size:
            row["stats"]["peak_amplitude_mm"]["p95_common"] = float(np.quantile(pc, 0.95))
        row["driver"] = driver(row["indices"]["peak_amplitude_mm"])
        row["n_failed"] = int(np.asarray(g["failed"]).sum())
        row["n_failed_ab"] = int(np.asarray(g["failed"])[ab].sum())
        row["case_time_s"] = statistics(g.get("cpu_s", g["hbm_s"]))
        groups.append(row)
    robust, ranking = {}, {}
    for phase in fams:
        keys = [k for k in results if k[1] == phase]
        P = np.column_stack([clean[k]["peak_amplitude_mm"][common[phase]] for k in keys])
        rc = ranking_confidence(P, [k[0] for k in keys], seed=spec.uncertainty.uq_seed)
        if rc:
            ranking[family_name(phase)] = rc
        cand = [
            r
            for r in groups
            if r["phase_deg"] == phase and "p95_common" in r["stats"]["peak_amplitude_mm"]
        ]
        if cand:
            best = min(cand, key=lambda r: r["stats"]["peak_amplitude_mm"]["p95_common"])
            robust[family_name(phase)] = best["damper"]
    return {
        "thresholds_mm": thresholds,
        "groups": groups,
        "robust": robust,
        "ranking": ranking,
        "inputs": {k: d.describe() for k, d in dists.items()},
    }


def write_h5(
    path: Path,
    design: Design,
    dists: dict[str, Distribution],
    results: dict[tuple, dict],
    a: dict[str, Any],
) -> Path:
    """``uncertainty.h5``: the design, every sample's outputs, the statistics and indices."""
    import json

    import h5py

    from ....io import atomic_path

    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
        d = h.create_group("design")
        d["unit"] = design.unit
        d["values"] = design.values
        d.attrs["names"] = json.dumps(list(design.names))
        d.attrs["n_base"], d.attrs["seed"] = design.n_base, design.seed
        d.attrs["distributions"] = json.dumps({k: v.describe() for k, v in dists.items()})
        d["ab_rows"] = design.ab_rows
        for (damper, phase), g in results.items():
            grp = h.create_group(f"samples/{damper}/{family_name(phase)}")
            for q, _, unit in QUANTITIES:
                grp[q] = g[q]
                grp[q].attrs["unit"] = unit
            grp["hbm_s"] = g["hbm_s"]  # wall time of the solve, s
            # CPU time of the sample (its model and solve), s
            grp["cpu_s"] = g.get("cpu_s", np.full_like(g["hbm_s"], np.nan))
            grp["failed"] = g["failed"]
            grp.attrs["digests"] = json.dumps(g["digests"])
        for r in a["groups"]:
            grp = h.create_group(f"analysis/{r['damper']}/{r['family']}")
            for q, _, _ in QUANTITIES:
                sq = grp.create_group(q)
                for k, v in r["stats"][q].items():
                    sq.attrs[k] = v
                for k in ("S1", "S1_conf", "ST", "ST_conf"):
                    sq[k] = np.asarray(r["indices"][q][k], dtype=float)
            grp.attrs["driver"] = r["driver"] or ""
            ver = driver_verdict(r["indices"]["peak_amplitude_mm"])
            grp.attrs["driver_resolved"] = ver["resolved"]
            grp.attrs["driver_contenders"] = json.dumps(ver["contenders"])
            grp.attrs["threshold_mm"] = np.nan if r["threshold_mm"] is None else r["threshold_mm"]
        h.attrs["thresholds_mm"] = json.dumps(a["thresholds_mm"])
        h.attrs["ranking"] = json.dumps(a.get("ranking", {}))
    return path


def write_uncertainty_outputs(
    spec: StudySpec,
    out: Path,
    design: Design,
    dists: dict[str, Distribution],
    results: dict[tuple, dict],
    a: dict[str, Any],
    sched: dict[str, Any],
    timings: dict[str, float],
) -> None:
    """Tables, HDF5, figures, ``uncertainty.json``, manifest and report."""
    from ....io.csv_rows import write_rows_csv
    from ...engine.outputs import write_manifest_and_report

    tables = out / "tables"
    write_rows_csv(tables / "uncertainty_answer.csv", answer_rows(a))
    write_rows_csv(tables / "uncertainty_stats.csv", stats_rows(a))
    write_rows_csv(tables / "uncertainty_indices.csv", index_rows(a))
    write_rows_csv(
        tables / "uncertainty_inputs.csv",
        [
            {"input": k, "meaning": INPUT_LABELS[k], "distribution": d.describe()}
            for k, d in dists.items()
        ],
    )
    samp = []
    for (damper, phase), g in results.items():
        for r in range(design.n_rows):
            samp.append(
                {
                    "damper": damper,
                    "family": family_name(phase),
                    "row": r,
                    "role": design.role(r),
                    **{k: float(design.values[r, j]) for j, k in enumerate(design.names)},
                    **{q: g[q][r] for q, _, _ in QUANTITIES},
                    "hbm_s": g["hbm_s"][r],
                    "failed": bool(g["failed"][r]),
                }
            )
    write_rows_csv(tables / "uncertainty_samples.csv", samp)
    write_h5(out / "uncertainty.h5", design, dists, results, a)
    write_json(out / "uncertainty.json", {"analysis": a, "schedule": sched, "timings": timings})
    figures: list[dict[str, str]] = []
    try:
        from .figures import uncertainty_figures

        figures = uncertainty_figures(out / "figures", design, results, a)
    except ImportError:  # the figure module is optional only while it is being built
        pass
    from .report import uncertainty_sections

    sections = uncertainty_sections(spec.forces[0], design, a, sched, figures)
    write_manifest_and_report(out, spec, "uncertainty study,", headline(a), timings, sections)


# moved to post/uncertainty.py and studies/engine/schedule.py; kept importable from here
__all__ = [
    "analyse",
    "run_uncertainty",
    "write_h5",
]
