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

from ..errors import SolveError
from ..io import write_json
from ..post.results import StudyResults
from .plan import plan
from .spec import StudySpec

if TYPE_CHECKING:
    from .runner import PreparedModel


def write_outputs(
    results: StudyResults, spec: StudySpec, out: Path, prepared: dict[str, PreparedModel]
) -> None:
    """results.h5, CSV files, summary, figures, tables, manifest and report."""
    from ..post.tables import write_rows_csv

    results.save(out / "results.h5")
    for c in results.cases:
        c.branch.to_csv(out / "cases" / f"{c.case_id}.csv", unit_scale=1e3, unit="mm")
    from ..post.vtk_out import write_study_peaks

    write_study_peaks(results, out, prepared, {c.digest: c.model_digest for c in plan(spec)})
    rows = results.summaries()
    write_json(out / "summary.json", rows)
    if results.extras.get("screen"):
        write_rows_csv(out / "screen.csv", results.extras["screen"])
    if rows:
        write_rows_csv(out / "summary.csv", rows)
    timings = dict(results.timings)
    for k, v in (results.extras.get("cached_costs") or {}).items():
        timings[f"{k}, reused from the cache (its cost when computed)"] = v
    sections = _sections(results, out)
    if results.extras.get("nlmodes"):  # backbones and synthesis (workbench/studies/nlmodes.py)
        from .nlmodes import nlmode_sections

        sections += nlmode_sections(results.extras["nlmodes"], out)
    write_manifest_and_report(
        out, spec, f"{spec.kind} study,", headline(results), timings, sections
    )


def write_manifest_and_report(
    out: Path,
    spec: StudySpec,
    subtitle: str,
    summary: list[str],
    timings: dict[str, float],
    sections: list[dict],
) -> None:
    """``manifest.json`` (see render/report.py for its layout) and ``report.html``."""
    from ..post.inputs import used_inputs
    from ..render.report import write_report
    from ..versions import software_versions

    manifest = {
        "title": f"Study '{spec.name}'",
        "subtitle": subtitle,
        "created": time.strftime("%Y-%m-%d %H:%M:%S"),
        "summary": summary,
        "inputs": spec.as_dict(),
        "sources": spec.source,
        "inputs_used": used_inputs(spec.as_dict(), spec.source),
        "versions": software_versions(),
        "timings": timings,
        "sections": sections,
    }
    write_json(out / "manifest.json", manifest)
    write_report(out)


def _sections(results: StudyResults, out: Path) -> list[dict]:
    try:
        from ..render.sections import build_sections
    except ImportError:  # the figure module is optional only while it is being built
        return []
    return build_sections(results, out, geometry_dirs=_geometry_dirs(out))


def _geometry_dirs(out: Path) -> dict[str, Path]:
    dirs: dict[str, Path] = {}
    for d in sorted((out / "cache" / "geometry").glob("*-*")):
        dirs.setdefault(d.name.split("-")[0], d)
    return dirs


def headline(results: StudyResults) -> list[str]:
    """One line per damper and family: the peak response over the forces.

    A case whose curve did not reach its resonance is named with its lower
    bound, never given as a peak.
    """
    lines = []
    for d in results.dampers:
        for ph in results.phases:
            cs = results.select(damper=d, phase_deg=ph)
            ok = [c for c in cs if c.peak_index >= 0]
            if not ok:
                continue
            top = max(ok, key=lambda c: (c.force_n, -float(c.amp_mm[c.peak_index])))
            s = top.summary()
            # a sweep has several cases per damper and force: name the one quoted
            which = f" ({top.variant.replace('=', ' = ')})" if top.variant else ""
            if not top.peak_covered:
                lines.append(
                    f"{d}, {top.family}{which}: at {top.force_n:g} N the resonance was NOT "
                    "reached; "
                    f"the peak is at least {s['peak_lower_bound_mm']:.4g} mm (lower bound: "
                    f"{top.peak_note()})"
                )
                continue
            lines.append(
                f"{d}, {top.family}{which}: at {top.force_n:g} N the peak is "
                f"{s['peak_amplitude_mm']:.4g} mm at {s['peak_frequency_hz']:.2f} Hz, "
                f"friction energy {s['friction_energy_mj']:.3g} mJ per cycle"
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
