"""The machinery of a study report's sections: sections, figure jobs, tables, stale files.

A :class:`_Builder` collects the report's sections, queues the figures to
draw (run together with one progress bar; an optional figure that fails
drops out with a note) and writes the tables; it also removes the figures
and tables of our own names left by an earlier run. Plus the small caption
helpers the section writers share. The sections themselves are written by
:mod:`.sections` (comparison) and :mod:`.sweep_sections` (sweeps).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import WorkbenchError
from ..log import progress
from ..post.results import CaseResult, StudyResults, family_name
from ..post.tables import Table, peak_curve, slug
from . import study_figures as sf

log = logging.getLogger(__name__)

FIGURES, TABLES = "figures", "tables"
# figure file names the sections write (anything else in figures/ is shown as found)
OWN_PREFIXES = (
    "answer_",
    "receptance_",
    "peak_amplitude_",
    "friction_energy_",
    "status_map_",
    "status_shares_",
    "contact_",
    "sweep_",
    "screen_",
)
OWN_TABLE_PREFIXES = (
    "answer.",
    "peak_amplitude_",
    "peak_frequency_",
    "friction_energy_",
    "status_shares_",
    "sweep_",
    "cases.",
    "screen.",
)


@dataclass
class _Section:
    id: str
    title: str
    text: list[str] = field(default_factory=list)
    figures: list[dict[str, str]] = field(default_factory=list)
    tables: list[dict[str, str]] = field(default_factory=list)
    kind: str = ""  # "answer": the report's first screen (render/report.py)
    notes: list[str] = field(default_factory=list)  # the answer's "how sure" lines

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "id": self.id,
            "title": self.title,
            "text": self.text,
            "figures": self.figures,
            "tables": self.tables,
        }
        if self.kind:
            out["kind"] = self.kind
            out["notes"] = self.notes
        return out


@dataclass
class _Job:
    """One figure to draw: ``run()`` writes the PNG(s) the section entries point to."""

    run: Callable[[], Any]
    section: _Section
    entries: list[dict[str, str]]
    optional: bool = False  # a WorkbenchError drops the entries instead of failing


class _Builder:
    def __init__(self, results: StudyResults, study_dir: Path):
        self.results = results
        self.root = Path(study_dir)
        self.fig_dir = self.root / FIGURES
        self.tab_dir = self.root / TABLES
        self.sections: list[_Section] = []
        self.jobs: list[_Job] = []
        self.written: set[str] = set()  # table file names written by this run

    def section(self, id_: str, title: str, text: Sequence[str] = ()) -> _Section:
        s = _Section(id_, title, list(text))
        self.sections.append(s)
        return s

    def figure(self, sec: _Section, name: str, caption: str, draw: Callable[[Path], Any]) -> None:
        path = self.fig_dir / f"{name}.png"
        entry = {"path": f"{FIGURES}/{name}.png", "caption": caption}
        sec.figures.append(entry)
        self.jobs.append(_Job(lambda: draw(path), sec, [entry]))

    def table(
        self, sec: _Section, name: str, table: Table, caption: str, *, name_files: bool = True
    ) -> None:
        """Write the table as CSV and markdown; the caption names the markdown file unless
        ``name_files`` is False (the answer, where every line of the first screen counts)."""
        for path in table.write(self.tab_dir / name):
            self.written.add(path.name)
        note = f" (also as markdown: {TABLES}/{name}.md)" if name_files else ""
        sec.tables.append({"path": f"{TABLES}/{name}.csv", "caption": caption + note})

    def run(self) -> None:
        for job in progress(self.jobs, desc="study figures", total=len(self.jobs), unit="fig"):
            try:
                job.run()
            except WorkbenchError as e:
                if not job.optional:
                    raise
                for entry in job.entries:
                    job.section.figures.remove(entry)
                job.section.text.append(f"A picture could not be drawn: {e}")
                log.warning("figure skipped: %s", e)

    def remove_stale(self) -> None:
        """Delete figures and tables of ours left by an earlier run and not made by this one,
        so the folder holds exactly what the report shows."""
        shown = {Path(f["path"]).name for s in self.sections for f in s.figures}
        for p in self.fig_dir.glob("*.png"):
            if p.name.startswith(OWN_PREFIXES) and p.name not in shown:
                log.debug("removing stale %s", p)
                p.unlink()
        for p in [*self.tab_dir.glob("*.csv"), *self.tab_dir.glob("*.md")]:
            if p.name.startswith(OWN_TABLE_PREFIXES) and p.name not in self.written:
                log.debug("removing stale %s", p)
                p.unlink()


def _fam_slug(phase_deg: float) -> str:
    return slug(family_name(phase_deg))


def _failures(cases: Sequence[CaseResult]) -> str:
    notes = sf.failure_notes(cases)
    return (" " + " ".join(notes)) if notes else ""


def _forces_text(forces: Sequence[float]) -> str:
    return ", ".join(f"{f:g}" for f in sorted(forces)) + " N"


def _peak_sentence(cases: Sequence[CaseResult]) -> str:
    """'cone: 0.0135 mm at 392.1 Hz (0.096 N) to 0.156 mm at 358.2 Hz (30 N); ...' (the
    harmonic-1 peaks)."""
    from ..post.tables import num

    pc = peak_curve(cases)
    ok = [k for k in range(pc.force_n.size) if pc.amp_mm[k] == pc.amp_mm[k]]
    if not ok:
        return f"{pc.damper}: no point computed"
    a, b = ok[0], ok[-1]
    first = f"{num(pc.amp_mm[a], 3)} mm at {pc.freq_hz[a]:.1f} Hz ({pc.force_n[a]:g} N)"
    if a == b:
        return f"{pc.damper}: peak {first}"
    last = f"{num(pc.amp_mm[b], 3)} mm at {pc.freq_hz[b]:.1f} Hz ({pc.force_n[b]:g} N)"
    ratio = (pc.amp_mm[b] / pc.force_n[b]) / (pc.amp_mm[a] / pc.force_n[a])
    return (
        f"{pc.damper}: peak {first} to {last}; peak receptance at the highest force over "
        f"that at the lowest {num(ratio, 3)} (1 for a linear response)"
    )
