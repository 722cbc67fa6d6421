"""Robustness study: solution methods crossed with hard cases, a map of success and failure.

A *method* is a named variant of :class:`~workbench.hbm.core.options.SolverOptions`
(:data:`METHODS`, named in :mod:`workbench.study_options`; the first method
of a study is the reference, normally
``default``: the options every other study uses). A *hard case* is one
frequency response of the assembled rig + damper model that stresses the
solver (:data:`CASES`: preload near separation, a high ``kt / (mu N0)``
ratio, a high force, the wedge in phase with separation, a folding branch,
very light damping). Each (method, case) *cell* is one
:func:`~workbench.hbm.forced.response.frequency_response`; its outcome is

* ``ok``: the branch reached the band end and its peak amplitude is within
  ``peak-tolerance`` percent of the reference method's (the peak frequency's
  deviation, relative to the band width, is reported but not judged: on the
  flat, kinked top of a friction peak it moves by a per cent of the band for
  a 0.1 % change of amplitude);
* ``wrong``: it reached the band end but its peak is off by more than that
  (a method that "converges" to another answer);
  A branch with a point whose energy balance is off by more than
  :data:`ENERGY_TOL` (not a periodic solution) is a wrong answer too;
* ``failed``: the solver stopped before the band end (its message and the
  frequency it reached are kept, with the points computed before).

Each cell is cached under a digest of its inputs (the case's digest, which
includes the solver sources, and the method's options) in
``out/cache/robustness/``, so an interrupted study resumes; ``force``
recomputes. Then, where the harmonic balance is suspect (turning points,
separation, Hill-unstable points, the lightest damping), its periodic
solution is compared with a time integration started on it
(:mod:`workbench.hbm.timedomain.timeint`, dense, at most 200 DOFs: so on the small
models of :data:`TIME_MODELS`, not on the rig models of 300-900 DOFs; the
78-DOF synthetic line-damper rig of :mod:`workbench.hbm.io.examples` fits, but
with light damping its time integration does not become periodic within a
few hundred periods, minutes each, so it is not part of the check). That
check lives in :mod:`.robustness_time`, a cell's solve and verdict in
:mod:`.robustness_cells`, the report text in
:mod:`workbench.studies.kinds.robustness.report`.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

from ....errors import InputError, SolveError
from ....hard_cases import CASES, METHODS
from ....io import write_json
from ....io.csv_rows import write_rows_csv
from ...engine.outputs import write_manifest_and_report
from ...engine.spec import StudySpec
from .cells import (
    ENERGY_TOL,
    STATUSES,
    Problem,
    _cell_key,
    classify,
    run_cell,
)
from .time_check import (
    time_checks,
)

log = logging.getLogger(__name__)


# ---- the map of cells (one cell is solved and judged in robustness_cells.py) ----------------


def method_map(
    problems: list[Problem],
    methods: list[str],
    cache_dir: Path | None = None,
    *,
    force: bool = False,
    tol_pct: float = 1.0,
) -> list[dict[str, Any]]:
    """Every (method, problem) cell, cached in ``cache_dir`` when given, classified.

    The first method is the reference. Returns one record per cell, problems
    outer, methods inner.
    """
    from ....log import bars_enabled, progress_bar

    for m in methods:
        if m not in METHODS:
            raise InputError("methods", m, "one of " + ", ".join(METHODS))
    if not methods or not problems:
        raise InputError("methods" if not methods else "hard-cases", [], "at least one")
    cells: list[dict[str, Any]] = []
    n = len(problems) * len(methods)
    n_new = 0
    with progress_bar("robustness: cells", total=n, unit="cell") as bar:
        for p in problems:
            for m in methods:
                bar.set_postfix_str(f"{p.name} / {m}")
                path = None if cache_dir is None else cache_dir / f"{_cell_key(p, m)}.json"
                rec = None
                if path is not None and path.is_file() and not force:
                    try:
                        import json

                        rec = json.loads(path.read_text())
                        rec["cached"] = True
                    except (OSError, ValueError):
                        log.warning("cached cell %s is unreadable; recomputing", path.name)
                if rec is None:
                    rec = run_cell(p, m)
                    rec["cached"] = False
                    n_new += 1
                    if path is not None:
                        write_json(path, rec)
                    if not bars_enabled():
                        log.info(
                            "%s / %s: %s (%d points, %.1f s)",
                            p.name,
                            m,
                            "failed" if rec["failed"] else "done",
                            rec["n_points"],
                            rec["wall_s"],
                        )
                rec.update({k: v for k, v in p.info.items() if k not in rec})
                cells.append(rec)
                bar.update(1)
    log.info("%d of %d cells computed (%d cached)", n_new, n, n - n_new)
    classify(cells, methods[0], tol_pct)
    return cells


# ---- the hard cases of the rig --------------------------------------------------------------


def case_problems(spec: StudySpec, out: Path, force: bool = False) -> list[Problem]:
    """The study's hard cases as problems on the assembled rig + damper models."""
    from ....pipeline import band_for, prepare_model
    from ...engine.plan import make_case

    base = spec.as_dict()
    prepared: dict[str, Any] = {}
    problems = []
    for name in spec.robustness.hard_cases:
        hc = CASES[name]
        settings = {**base, **hc.settings}
        case = make_case(hc.damper, hc.phase_deg, hc.force_n, settings, name)

        def build(case=case):
            if case.model_digest not in prepared:
                log.info("model for %s: geometry, reduction, assembly", case.name)
                prepared[case.model_digest] = prepare_model(case, out, force=force)
            prep = prepared[case.model_digest]
            blade = case.settings["response-blade"]
            return (
                prep.system,
                prep.assembled.excitation(case.phase_deg),
                band_for(prep, case),
                prep.assembled.response_dofs[blade - 1 : blade],
                (f"blade{blade}_x",),
            )

        s = case.settings
        problems.append(
            Problem(
                name=name,
                key=case.digest,
                level=hc.force_n,
                harmonics=tuple(s["harmonics"]),
                nt=s["nt"],
                build=build,
                base_options={"stability": s["stability"], "max_points": s["max-points"]},
                info={
                    "damper": hc.damper,
                    "phase_deg": hc.phase_deg,
                    "force_n": hc.force_n,
                    "changes": ", ".join(f"{k} = {v:g}" for k, v in hc.settings.items()) or "none",
                },
            )
        )
    return problems


# ---- the study ------------------------------------------------------------------------------

_CELL_COLS = (
    "case",
    "method",
    "status",
    "succeeded",
    "n_points",
    "newton_its",
    "wall_s",
    "peak_amplitude",
    "peak_frequency_hz",
    "amp_dev_pct",
    "freq_dev_pct",
    "freq_reached_hz",
    "band_fraction",
    "n_turning_points",
    "n_unstable",
    "n_stability_unknown",
    "max_status",
    "n_unknowns",
    "energy_residual_max",
    "message",
)


def _write_csv(path: Path, rows: list[dict[str, Any]], cols: tuple[str, ...]) -> Path:
    return write_rows_csv(path, rows, cols, digits=6)


def run_robustness(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Run the robustness study ``spec`` into ``out``; returns the JSON summary.

    Other methods' failures are the study's findings; if the reference (first)
    method fails on a hard case, :class:`SolveError` is raised after every
    output is written (the CLI exits with 3).
    """
    from ....log import mpi_size

    if mpi_size() > 1:
        raise InputError(
            "kind",
            "robustness",
            "a robustness study on one process (no mpirun): its timings compare methods",
        )
    out = Path(out)
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    cache = out / "cache" / "robustness"
    cache.mkdir(parents=True, exist_ok=True)
    problems = case_problems(spec, out, force=force)
    t0 = time.perf_counter()
    cells = method_map(
        problems,
        list(spec.robustness.methods),
        cache,
        force=force,
        tol_pct=spec.robustness.peak_tolerance,
    )
    timings["cells (wall)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    checks = time_checks(cache, force=force) if spec.robustness.time_check else []
    timings["time integration"] = time.perf_counter() - t0

    # tables
    tables = out / "tables"
    _write_csv(out / "cells.csv", cells, _CELL_COLS)
    write_json(
        out / "cells.json",
        [
            {k: v for k, v in c.items() if k not in ("freq_hz", "amp", "stable", "stability")}
            for c in cells
        ],
    )
    map_rows = [{**c, "wall_s": round(c["wall_s"], 2)} for c in cells]
    _write_csv(
        tables / "robustness_cells.csv",
        map_rows,
        (
            "case",
            "method",
            "status",
            "n_points",
            "newton_its",
            "wall_s",
            "amp_dev_pct",
            "freq_dev_pct",
            "freq_reached_hz",
            "n_turning_points",
            "n_unstable",
        ),
    )
    fails = [c for c in cells if c["status"] != "ok"]
    _write_csv(
        tables / "robustness_failures.csv",
        fails,
        (
            "case",
            "method",
            "status",
            "n_points",
            "freq_reached_hz",
            "band_fraction",
            "last_freq_hz",
            "amp_dev_pct",
            "freq_dev_pct",
            "message",
        ),
    )
    ref = spec.robustness.methods[0]
    case_rows = []
    for p in problems:
        r = next(c for c in cells if c["case"] == p.name and c["method"] == ref)
        case_rows.append(
            {
                "case": p.name,
                "damper": p.info["damper"],
                "phase_deg": p.info["phase_deg"],
                "force_n": p.info["force_n"],
                "changes": p.info["changes"],
                "band_hz": f"{r['band_hz'][0]:.1f}-{r['band_hz'][1]:.1f}",
                "n_unknowns": r.get("n_unknowns"),
                "turning_points": r["n_turning_points"],
                "turning_points_hz": " ".join(f"{x:.2f}" for x in r["turning_points_hz"]),
                "separated_share": r.get("separated_share"),
                "n_unstable": r["n_unstable"],
                "why": CASES[p.name].why,
            }
        )
    _write_csv(tables / "robustness_cases.csv", case_rows, tuple(case_rows[0]))
    trows = [row for ch in checks for row in ch["points"]]
    if trows:
        _write_csv(
            tables / "hbm_vs_time.csv",
            trows,
            (
                "model",
                "why",
                "freq_hz",
                "hill_stable",
                "hill_verdict",
                "hbm_amplitude",
                "ti_amplitude",
                "diff_pct",
                "n_hbm_solutions",
                "nearest_hbm_amplitude",
                "diff_nearest_pct",
                "hbm_h1",
                "ti_h1",
                "ti_periods",
                "ti_converged",
            ),
        )
    write_json(out / "time_check.json", checks)

    # figures
    from .figures import plot_branches, plot_failure_map, plot_hbm_vs_time

    figs = out / "figures"
    t0 = time.perf_counter()
    plot_failure_map(
        cells,
        list(spec.robustness.methods),
        list(spec.robustness.hard_cases),
        figs / "robustness_map.png",
    )
    plot_branches(cells, list(spec.robustness.hard_cases), figs / "robustness_curves.png")
    if checks:
        plot_hbm_vs_time(checks, figs / "hbm_vs_time.png")
    timings["figures"] = time.perf_counter() - t0

    summary = _summary(spec, cells, checks)
    sections = _sections(spec, cells, checks, summary)
    timings["total"] = time.perf_counter() - t_start
    write_manifest_and_report(
        out,
        spec,
        "robustness study: solution methods x hard cases,",
        summary["headline"],
        timings,
        sections,
    )
    summary.update(
        out=str(out),
        report=str(out / "report.html"),
        timings_s={k: round(v, 2) for k, v in timings.items()},
    )
    write_json(out / "summary.json", summary)
    if summary["reference_failed"]:  # everything is written; the CLI exits with 3
        raise SolveError(
            f"the reference method '{spec.robustness.methods[0]}' failed on "
            + ", ".join(summary["reference_failed"])
            + f" (see {out}/report.html)",
            partial=summary,
        )
    return summary


def _sections(spec: StudySpec, cells: list[dict], checks: list[dict], summary: dict) -> list[dict]:
    """The report's sections (written by :mod:`workbench.studies.kinds.robustness.report`)."""
    from .report import robustness_sections

    return robustness_sections(
        spec.robustness.peak_tolerance,
        {m: METHODS[m][1] for m in spec.robustness.methods},
        ENERGY_TOL,
        cells,
        checks,
    )


def _summary(spec: StudySpec, cells: list[dict], checks: list[dict]) -> dict[str, Any]:
    opts = spec.robustness
    ref = opts.methods[0]
    counts = {m: {s: 0 for s in STATUSES} for m in opts.methods}
    for c in cells:
        counts[c["method"]][c["status"]] += 1
    ref_failed = [c["case"] for c in cells if c["method"] == ref and c["status"] == "failed"]
    head = [
        f"{len(opts.methods)} methods x {len(opts.hard_cases)} hard cases = {len(cells)} "
        f"solves; reference method '{ref}'."
    ]
    head.append(
        f"The reference method failed on: {', '.join(ref_failed)}."
        if ref_failed
        else f"The reference method '{ref}' reached the band end on every hard case."
    )
    for m in spec.robustness.methods:
        k = counts[m]
        head.append(
            f"{m}: {k['ok']} ok, {k['wrong']} wrong answer, {k['failed']} failed; "
            f"{sum(c['newton_its'] for c in cells if c['method'] == m)} Newton "
            f"iterations, {sum(c['wall_s'] for c in cells if c['method'] == m):.1f} s"
        )
    rows = [r for ch in checks for r in ch["points"] if r["hill_stable"] and r["ti_converged"]]
    if rows:
        head.append(
            f"HBM vs time integration at {len(rows)} Hill-stable suspect points: largest "
            f"amplitude difference {max(abs(r['diff_pct']) for r in rows):.3g} % to the "
            f"starting HBM orbit, {max(abs(r['diff_nearest_pct']) for r in rows):.3g} % to the "
            "nearest HBM solution at the same frequency."
        )
    for verdict, what in (
        ("unknown", "Hill's verdict is unknown"),
        ("unstable", "Hill's verdict is unstable"),
    ):
        pts = [r for ch in checks for r in ch["points"] if r["hill_verdict"] == verdict]
        if pts:
            head.append(
                f"At {len(pts)} suspect point(s) {what}; the time integration started on the "
                "orbit ends: "
                + "; ".join(
                    f"{r['model']} at {r['freq_hz']:.4g} Hz: {r['diff_pct']:+.3g} %"
                    + ("" if r["ti_converged"] else " (not periodic)")
                    for r in pts
                )
                + "."
            )
    return {
        "study": spec.name,
        "kind": "robustness",
        "reference": ref,
        "counts": counts,
        "reference_failed": ref_failed,
        "headline": head,
        "cells": [{k: c.get(k) for k in _CELL_COLS} for c in cells],
        "time_check": [{k: v for k, v in r.items()} for ch in checks for r in ch["points"]],
    }


__all__ = [
    "run_robustness",
    "method_map",
]
