"""What a finished study writes: results.h5, CSV, VTK, summary, manifest.json and report.html.

:func:`write_outputs` writes a comparison or sweep study's files,
:func:`write_manifest_and_report` the manifest and HTML report of any
study kind (the sections come from ``workbench.render``), :func:`headline`
its summary lines and :func:`check_failures` turns failed or short cases
into a :class:`~workbench.errors.SolveError` once everything is written.
The computing side is :mod:`.runner`.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

from ...errors import SolveError
from ...io import write_json
from ...post.results import StudyResults
from ..kinds import inputs_table
from .plan import plan
from .spec import StudySpec

if TYPE_CHECKING:
    from ...pipeline import PreparedModel


def write_outputs(
    results: StudyResults, spec: StudySpec, out: Path, prepared: dict[str, PreparedModel]
) -> None:
    """results.h5, CSV files, summary, figures, tables, manifest and report."""
    from ...io.csv_rows import write_rows_csv

    results.save(out / "results.h5")
    for c in results.cases:
        c.branch.to_csv(out / "cases" / f"{c.case_id}.csv", unit_scale=1e3, unit="mm")
    from ...io.vtk_out import write_study_peaks

    write_study_peaks(results, out, prepared, {c.digest: c.model_digest for c in plan(spec)})
    rows = results.summaries()
    # summary.json: each case's row and the inputs its solve used, each with unit and source
    write_json(
        out / "summary.json",
        [{**r, "inputs": c.inputs} for r, c in zip(rows, results.cases, strict=True)],
    )
    if results.extras.get("screen"):
        write_rows_csv(out / "screen.csv", results.extras["screen"])
    if rows:
        write_rows_csv(out / "summary.csv", rows)
    timings = dict(results.timings)
    for k, v in (results.extras.get("cached_costs") or {}).items():
        timings[f"{k}, reused from the cache (its cost when computed)"] = v
    sections = _sections(results, out)
    if results.extras.get("nlmodes"):  # backbones and synthesis (engine/nlmodes.py)
        from .nlmodes import nlmode_sections

        sections += nlmode_sections(results.extras["nlmodes"], out)
    write_manifest_and_report(
        out, spec, f"{spec.kind} study,", headline(results), timings, sections, results=results
    )


def write_manifest_and_report(
    out: Path,
    spec: StudySpec,
    subtitle: str,
    summary: list[str],
    timings: dict[str, float],
    sections: list[dict],
    *,
    results: StudyResults | None = None,
) -> None:
    """``manifest.json`` (see render/report.py for its layout) and ``report.html``.

    With ``results`` the Inputs table is what the solve of its cases recorded
    (:func:`workbench.post.inputs.study_inputs`) and the manifest carries the
    machine's load during the cases; without, the study's options resolved
    from the files (:func:`workbench.post.inputs.used_inputs`).
    """
    import os

    from ...post.inputs import study_inputs, used_inputs
    from ...render.report import write_report
    from ...versions import software_versions

    table = inputs_table(spec.kind)  # the kind's rows, from its registry entry
    inputs = (
        study_inputs(results.cases, spec.as_dict(), spec.source, table)
        if results is not None
        else used_inputs(spec.as_dict(), spec.source, table=table)
    )
    loads = [
        c.inputs["load_average"]["value"]
        for c in (results.cases if results is not None else [])
        if "load_average" in c.inputs
    ]
    try:
        loads.append(round(os.getloadavg()[0], 2))  # and now, writing the report
    except OSError:
        pass
    manifest = {
        "title": f"Study '{spec.name}'",
        "subtitle": subtitle,
        "created": time.strftime("%Y-%m-%d %H:%M:%S"),
        "summary": summary,
        "inputs": spec.as_dict(),
        "sources": spec.source,
        "inputs_used": inputs,
        "versions": software_versions(),
        "timings": timings,
        "machine": {"cpus": os.cpu_count() or 1, "load": loads},
        "sections": sections,
    }
    write_json(out / "manifest.json", manifest)
    write_report(out)


def _sections(results: StudyResults, out: Path) -> list[dict]:
    try:
        from ...render.sections import build_sections
    except ImportError:  # the figure module is optional only while it is being built
        return []
    return build_sections(results, out, geometry_dirs=_geometry_dirs(out))


def _geometry_dirs(out: Path) -> dict[str, Path]:
    dirs: dict[str, Path] = {}
    for d in sorted((out / "cache" / "geometry").glob("*-*")):
        dirs.setdefault(d.name.split("-")[0], d)
    return dirs


def headline(results: StudyResults) -> list[str]:
    """One line per damper and family: the vibration at the highest force.

    The harmonic-1 amplitude at resonance, with max |x(t)| and the mean term
    at that point. A case whose curve did not reach its resonance is named
    with its lower bound, never given as a peak.
    """
    from ...post.answer import mean_text
    from ...post.tables import energy_floor, energy_text, num

    floor = energy_floor([c.summary()["h1_friction_energy_mj"] or 0.0 for c in results.cases])
    lines = []
    for d in results.dampers:
        for ph in results.phases:
            cs = results.select(damper=d, phase_deg=ph)
            ok = [c for c in cs if c.h1_peak_index >= 0]
            if not ok:
                continue
            top = max(ok, key=lambda c: (c.force_n, -float(c.h1_mm[c.h1_peak_index])))
            s = top.summary()
            # a sweep has several cases per damper and force: name the one quoted
            which = f" ({top.variant.replace('=', ' = ')})" if top.variant else ""
            if not top.h1_peak_covered:
                lines.append(
                    f"{d}, {top.family}{which}: at {top.force_n:g} N the resonance was NOT "
                    f"reached; the vibration amplitude (harmonic 1) is at least "
                    f"{num(s['h1_lower_bound_mm'], 4)} mm (lower bound: {top.peak_note()})"
                )
                continue
            energy = energy_text(s["h1_friction_energy_mj"], floor)
            lines.append(
                f"{d}, {top.family}{which}: at {top.force_n:g} N the vibration amplitude "
                f"(harmonic 1) is {num(s['h1_amplitude_mm'], 4)} mm at "
                f"{s['h1_peak_frequency_hz']:.1f} Hz (max |x(t)| {num(s['h1_max_abs_mm'], 4)} mm, "
                f"mean {mean_text(s['h1_mean_mm'], s['h1_max_abs_mm'])} mm), friction energy per "
                "cycle " + (energy if energy[0].isalpha() else f"{energy} mJ")
            )
    short = results.uncovered()
    if short:
        lines.append(
            f"{len(short)} of {len(results.cases)} case(s) did not cover their "
            "resonance (peak only a lower bound): " + ", ".join(c.case_id for c in short)
        )
    return lines


def check_failures(results: StudyResults, summary: dict | None = None) -> None:
    """Raise SolveError (exit 3) after writing everything if a case failed or fell short.

    Every case of the study counts (also those reused from the cache): a
    failed solve, or a curve that stopped before its resonance peak (its
    peak is then only a lower bound). ``summary`` is the command's JSON
    summary, still printed by the CLI.
    """
    failed = [c for c in results.cases if c.branch.failed]
    short = [c for c in results.uncovered() if not c.branch.failed]
    if not failed and not short:
        return
    parts = []
    if failed:
        parts.append(
            f"{len(failed)} case(s) failed: "
            + "; ".join(f"{c.case_id} ({c.branch.message})" for c in failed[:3])
            + ("; ..." if len(failed) > 3 else "")
        )
    if short:
        parts.append(
            f"{len(short)} case(s) did not reach their resonance peak, which is only a "
            "lower bound: "
            + "; ".join(
                f"{c.case_id} ({c.branch.message or 'peak at the band edge'})" for c in short[:3]
            )
            + ("; ..." if len(short) > 3 else "")
        )
    raise SolveError(
        " and ".join(parts) + " (all computed points are kept in the results and the report)",
        partial=results,
        summary=summary,
    )
