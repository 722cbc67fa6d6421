"""The numbers behind the study figures and tables: peaks, energies, status shares, sweeps.

Plain numpy on :class:`~workbench.post.results.StudyResults` and lists of
:class:`~workbench.post.results.CaseResult`; :mod:`workbench.render` draws
what these return. Report units: amplitude mm, energy per cycle mJ,
frequency Hz, force N.

Grouping: a *family* is one inter-blade phase angle (0 deg in-phase, 180 deg
out-of-phase, any other angle); a *curve set* is every force of one damper
and one family (the cases of one receptance figure). Tables follow the
paper's Tables 1-2: one row per damper, one column per force, one table per
family.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io import write_text
from .results import STATUS_KEYS, STATUS_NAMES, CaseResult, StudyResults, family_name

__all__ = [
    "PeakCurve",
    "SweepCurve",
    "Table",
    "base_variant",
    "case_label",
    "curve_set",
    "energy_split_table",
    "energy_table",
    "families",
    "pick_forces",
    "peak_amplitude_table",
    "peak_curve",
    "peak_frequency_table",
    "sci",
    "slug",
    "stability_runs",
    "status_share_curves",
    "status_shares_table",
    "sweep_curve",
    "sweep_curves",
    "sweep_table",
    "sweep_value",
]


# ---- formatting -------------------------------------------------------------------------


def sci(value: float, digits: int = 2) -> str:
    """Scientific notation the way the paper writes it: ``1.1e-2``, ``2.3e-22``.

    ``digits`` significant digits; ``0`` for zero, ``n/a`` for NaN.
    """
    v = float(value)
    if math.isnan(v):
        return "n/a"
    if v == 0.0:
        return "0"
    mant, exp = f"{v:.{max(digits - 1, 0)}e}".split("e")
    return f"{mant}e{int(exp)}"


ENERGY_FLOOR_REL = 1e-6
"""Energies below this fraction of the largest one in a table or figure are round-off of a
contact that does not slip (stuck, rolling or open): they are written as words
(:data:`STUCK_TEXT`), never as numbers."""
STUCK_TEXT = "zero (no slip)"


def energy_floor(values: Sequence[float] | np.ndarray, rel: float = ENERGY_FLOOR_REL) -> float:
    """The energy floor of a set of values: ``rel`` times the largest finite one (0 if none)."""
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    top = float(np.max(np.abs(v))) if v.size else 0.0
    return rel * top


def fixed(value: float, digits: int = 4) -> str:
    """A number with ``digits`` significant digits (``n/a`` for NaN, never ``-0``)."""
    v = float(value)
    if math.isnan(v):
        return "n/a"
    out = f"{v:.{digits}g}"
    return out[1:] if out.startswith("-") and float(out) == 0.0 else out


def num(value: Any, digits: int = 4) -> str:
    """A number for a report table: ``digits`` significant digits in plain notation from
    1e-3 to 1e5 (``0.1843``, ``383.9``, ``13600``), the paper's ``4e10`` notation outside
    (trailing zeros dropped), ``0`` for zero (never ``-0``), ``n/a`` for None or NaN."""
    if value is None:
        return "n/a"
    v = float(value)
    if math.isnan(v):
        return "n/a"
    if v == 0.0 or abs(v) < 1e-300:
        return "0"
    if 1e-3 <= abs(v) < 1e5:
        out = f"{v:.{digits}g}"
        if "e" in out:  # 4 digits of a number >= 1e4: write it out
            out = f"{v:.0f}"
        return out
    mant, exp = f"{v:.{max(digits - 1, 0)}e}".split("e")
    mant = mant.rstrip("0").rstrip(".") if "." in mant else mant
    return f"{mant}e{int(exp)}"


def slug(text: str) -> str:
    """A file-name-safe form of a label: ``"phase 90 deg" -> "phase-90deg"``."""
    out = "".join(ch if ch.isalnum() or ch in "-." else "-" for ch in text.replace(" deg", "deg"))
    while "--" in out:
        out = out.replace("--", "-")
    return out.strip("-").lower()


# ---- grouping ---------------------------------------------------------------------------


def families(results: StudyResults) -> list[float]:
    """The phase angles of the study, in-phase first, then out-of-phase, then the others."""

    def key(p: float) -> tuple[int, float]:
        name = family_name(p)
        return ({"in-phase": 0, "out-of-phase": 1}.get(name, 2), float(p) % 360.0)

    return sorted(results.phases, key=key)


def base_variant(results: StudyResults) -> str:
    """The variant the comparison figures show: ``""`` when present, else the first one."""
    variants = list(dict.fromkeys(c.variant for c in results.cases))
    return "" if "" in variants or not variants else variants[0]


def curve_set(
    results: StudyResults, damper: str, phase_deg: float, variant: str | None = None
) -> list[CaseResult]:
    """Every force of one damper and one family (one variant), sorted by force."""
    cases = results.select(damper=damper, phase_deg=phase_deg, variant=variant)
    return sorted(cases, key=lambda c: c.force_n)


def pick_forces(forces: Sequence[float], preferred: Sequence[float] = (9.6, 30.0)) -> list[float]:
    """The forces of the status maps: ``preferred`` if all present, else lowest and highest."""
    fs = sorted(set(float(f) for f in forces))
    if not fs:
        return []
    if all(any(abs(f - p) <= 1e-9 * max(1.0, p) for f in fs) for p in preferred):
        return [f for f in fs if any(abs(f - p) <= 1e-9 * max(1.0, p) for p in preferred)]
    return sorted({fs[0], fs[-1]})


def case_label(case: CaseResult) -> str:
    """``"cone, in-phase, F = 9.6 N"`` (plus the variant if any)."""
    v = f", {case.variant}" if case.variant else ""
    return f"{case.damper}, {case.family}, F = {case.force_n:g} N{v}"


# ---- curves -----------------------------------------------------------------------------


def stability_runs(stable: np.ndarray) -> list[tuple[slice, bool]]:
    """Split a branch into runs of equal stability for drawing (solid/dashed).

    Consecutive runs share their boundary point, so the drawn pieces join
    into one unbroken line. Returns ``[(slice, is_stable), ...]``.
    """
    s = np.asarray(stable, dtype=bool)
    n = s.size
    if n == 0:
        return []
    if n == 1:
        return [(slice(0, 1), bool(s[0]))]
    # a segment between points i and i+1 is stable when both ends are
    seg = s[:-1] & s[1:]
    runs, start = [], 0
    for i in range(1, seg.size + 1):
        if i == seg.size or seg[i] != seg[start]:
            runs.append((slice(start, i + 1), bool(seg[start])))
            start = i
    return runs


@dataclass(frozen=True)
class PeakCurve:
    """Resonance values of one curve set vs force (NaN where a branch has no point).

    The resonance of a curve is its largest harmonic-1 amplitude (the
    vibration); the other values are taken at that same point.
    """

    damper: str
    phase_deg: float
    force_n: np.ndarray
    amp_mm: np.ndarray  # largest harmonic-1 amplitude of each branch
    freq_hz: np.ndarray  # its frequency
    energy_mj: np.ndarray  # friction energy per cycle, all pairs, at that point
    stable: np.ndarray  # bool, that point is stable
    failed: np.ndarray  # bool, the branch stopped on a failure
    verdict: np.ndarray | None = None  # stability code at that point (1, 0, -1, ...)
    max_abs_mm: np.ndarray | None = None  # max |x(t)| at that point
    mean_mm: np.ndarray | None = None  # mean term at that point
    covered: np.ndarray | None = None  # bool, the curve went over that peak

    @property
    def family(self) -> str:
        return family_name(self.phase_deg)


def _at_peak(case: CaseResult) -> tuple[float, float, float, bool]:
    """(harmonic-1 amplitude mm, frequency Hz, friction energy mJ, stable) at the
    harmonic-1 peak."""
    i = case.h1_peak_index
    if i < 0:
        return (math.nan,) * 3 + (False,)
    return (
        float(case.h1_mm[i]),
        float(case.freq_hz[i]),
        float(case.energy_mj[i].sum()),
        bool(case.stable[i]),
    )


def _peak_extra(case: CaseResult) -> tuple[int, float, float, bool]:
    """(stability code, max |x(t)| mm, mean mm, covered) at the harmonic-1 peak."""
    i = case.h1_peak_index
    if i < 0:
        return (-1, math.nan, math.nan, False)
    return (
        int(case.branch.stability[i]),
        float(case.amp_mm[i]),
        float(case.mean_mm[i]),
        case.h1_peak_covered,
    )


def peak_curve(cases: Sequence[CaseResult]) -> PeakCurve:
    """Harmonic-1 peak amplitude, frequency and friction energy vs force, one curve set."""
    if not cases:
        raise InputError("cases", "[]", "at least one case of one damper and one family")
    cases = sorted(cases, key=lambda c: c.force_n)
    _check_one_set(cases)
    vals = [_at_peak(c) for c in cases]
    extra = [_peak_extra(c) for c in cases]
    return PeakCurve(
        damper=cases[0].damper,
        phase_deg=cases[0].phase_deg,
        force_n=np.array([c.force_n for c in cases]),
        amp_mm=np.array([v[0] for v in vals]),
        freq_hz=np.array([v[1] for v in vals]),
        energy_mj=np.array([v[2] for v in vals]),
        stable=np.array([v[3] for v in vals]),
        failed=np.array([bool(c.branch.failed) for c in cases]),
        verdict=np.array([e[0] for e in extra], dtype=int),
        max_abs_mm=np.array([e[1] for e in extra]),
        mean_mm=np.array([e[2] for e in extra]),
        covered=np.array([e[3] for e in extra], dtype=bool),
    )


def _check_one_set(cases: Sequence[CaseResult]) -> None:
    d = {(c.damper, round(c.phase_deg, 9)) for c in cases}
    if len(d) != 1:
        raise InputError("cases", sorted(d), "cases of a single damper and a single family")


def status_share_curves(cases: Sequence[CaseResult]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Forces and the share (0..1) of pairs in each status at resonance, one curve set."""
    cases = sorted(cases, key=lambda c: c.force_n)
    _check_one_set(cases)
    forces = np.array([c.force_n for c in cases])
    shares = [c.status_shares(c.h1_peak_index) for c in cases]
    return forces, {k: np.array([s[k] for s in shares]) for k in STATUS_KEYS}


# ---- sweeps -----------------------------------------------------------------------------


def sweep_value(case: CaseResult, option: str) -> float:
    """The swept option's value of a case (``params[option]``; dashes or underscores)."""
    for key in (option, option.replace("-", "_"), option.replace("_", "-")):
        if key in case.params and case.params[key] is not None:
            return float(case.params[key])
    raise InputError(
        f"params[{option!r}] of case {case.case_id}",
        sorted(case.params),
        f"the swept option {option!r} in every case's parameters",
    )


@dataclass(frozen=True)
class SweepCurve:
    """Resonance values of one damper, family and force vs the swept option."""

    damper: str
    phase_deg: float
    force_n: float
    option: str
    value: np.ndarray
    amp_mm: np.ndarray
    freq_hz: np.ndarray
    energy_mj: np.ndarray
    stable: np.ndarray
    failed: np.ndarray
    verdict: np.ndarray | None = None  # stability code at each peak (1, 0, -1, ...)

    @property
    def family(self) -> str:
        return family_name(self.phase_deg)


def sweep_curve(cases: Iterable[CaseResult], option: str) -> SweepCurve:
    """Peak values vs the swept ``option`` for cases of one damper, family and force."""
    cases = sorted(cases, key=lambda c: sweep_value(c, option))
    if not cases:
        raise InputError("cases", "[]", "at least one case")
    keys = {(c.damper, round(c.phase_deg, 9), round(c.force_n, 12)) for c in cases}
    if len(keys) != 1:
        raise InputError("cases", sorted(keys), "cases of one damper, family and force")
    vals = [_at_peak(c) for c in cases]
    return SweepCurve(
        damper=cases[0].damper,
        phase_deg=cases[0].phase_deg,
        force_n=cases[0].force_n,
        option=option,
        value=np.array([sweep_value(c, option) for c in cases]),
        amp_mm=np.array([v[0] for v in vals]),
        freq_hz=np.array([v[1] for v in vals]),
        energy_mj=np.array([v[2] for v in vals]),
        stable=np.array([v[3] for v in vals]),
        failed=np.array([bool(c.branch.failed) for c in cases]),
        verdict=np.array([_peak_extra(c)[0] for c in cases], dtype=int),
    )


def sweep_curves(results: StudyResults, option: str) -> list[SweepCurve]:
    """One :class:`SweepCurve` per damper, family and force of a sweep study."""
    out = []
    for d in results.dampers:
        for p in families(results):
            for f in results.forces:
                cases = results.select(damper=d, phase_deg=p, force_n=f)
                if cases:
                    out.append(sweep_curve(cases, option))
    return out


# ---- tables -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Table:
    """A small table of text cells: written as CSV and as markdown with the same cells."""

    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]

    def __post_init__(self) -> None:
        for r in self.rows:
            if len(r) != len(self.header):
                raise InputError("table row", list(r), f"{len(self.header)} cells")

    def csv_text(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.header)
        w.writerows(self.rows)
        return buf.getvalue()

    def markdown_text(self) -> str:
        def line(cells: Sequence[str]) -> str:
            return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"

        sep = "|" + "|".join(["---"] + ["---:"] * (len(self.header) - 1)) + "|"
        return "\n".join([line(self.header), sep, *(line(r) for r in self.rows)]) + "\n"

    def write(self, stem: str | Path) -> tuple[Path, Path]:
        """Write ``<stem>.csv`` and ``<stem>.md`` atomically; return both paths."""
        stem = Path(stem)
        csv_path = write_text(stem.with_suffix(".csv"), self.csv_text())
        md_path = write_text(stem.with_suffix(".md"), self.markdown_text())
        return csv_path, md_path

    def column(self, name: str) -> list[str]:
        return [r[self.header.index(name)] for r in self.rows]


def _force_table(
    results: StudyResults, phase_deg: float, corner: str, value: Any, fmt: Any, variant: str | None
) -> Table:
    forces = [
        f for f in results.forces if results.select(phase_deg=phase_deg, force_n=f, variant=variant)
    ]
    rows = []
    for d in results.dampers:
        cases = curve_set(results, d, phase_deg, variant)
        if not cases:
            continue
        by_force = {round(c.force_n, 12): c for c in cases}
        row = [d]
        for f in forces:
            c = by_force.get(round(f, 12))
            cell = fmt(value(c)) if c is not None else ""
            if c is not None and c.branch.failed:
                cell += " (failed)"  # the value of a branch that stopped early
            elif c is not None and not c.h1_peak_covered and c.h1_peak_index >= 0:
                cell += " (peak not reached)"
            row.append(cell)
        rows.append(tuple(row))
    return Table((corner, *(f"{f:g} N" for f in forces)), tuple(rows))


def energy_table(results: StudyResults, phase_deg: float, variant: str | None = None) -> Table:
    """Friction energy per cycle at resonance, mJ: dampers x forces (paper Tables 1-2).

    At the harmonic-1 peak. Energies below :data:`ENERGY_FLOOR_REL` times the
    table's largest are written :data:`STUCK_TEXT` (round-off of a contact
    that does not slip).
    """
    cases = [c for c in results.select(phase_deg=phase_deg, variant=variant)]
    floor = energy_floor([_at_peak(c)[2] for c in cases])
    return _force_table(
        results,
        phase_deg,
        "damper: friction energy per cycle (mJ) at force",
        lambda c: _at_peak(c)[2],
        lambda v: energy_text(v, floor),
        variant,
    )


def energy_split_table(
    results: StudyResults, phase_deg: float, variant: str | None = None
) -> Table:
    """The friction energy's split between the two platforms' lines at resonance:
    dampers x forces, platform 1's minus platform 2's in percent of the two
    (:meth:`CaseResult.energy_split_pct`); :data:`STUCK_TEXT` where the contact does not
    slip (at or below the energy table's floor)."""
    cases = [c for c in results.select(phase_deg=phase_deg, variant=variant)]
    floor = energy_floor([_at_peak(c)[2] for c in cases])

    def split(c: CaseResult) -> float | None:
        return None if _at_peak(c)[2] <= floor else c.energy_split_pct()

    return _force_table(
        results,
        phase_deg,
        "damper: energy on platform 1's line minus platform 2's (% of both) at force",
        split,
        lambda v: STUCK_TEXT if v is None else f"{v:+.1f}",
        variant,
    )


def energy_text(value: float, floor: float, digits: int = 3) -> str:
    """An energy for a table: ``digits`` significant digits above the floor,
    :data:`STUCK_TEXT` at or below it (or negative)."""
    v = float(value)
    if math.isnan(v):
        return "n/a"
    if v <= floor or v <= 0.0:
        return STUCK_TEXT
    return num(v, digits)


def peak_amplitude_table(
    results: StudyResults, phase_deg: float, variant: str | None = None
) -> Table:
    """Harmonic-1 peak amplitude, mm: dampers x forces."""
    return _force_table(
        results,
        phase_deg,
        "damper: vibration amplitude, harmonic 1 (mm) at force",
        lambda c: _at_peak(c)[0],
        lambda v: num(v, 4),
        variant,
    )


def peak_frequency_table(
    results: StudyResults, phase_deg: float, variant: str | None = None
) -> Table:
    """Frequency of the harmonic-1 peak, Hz: dampers x forces."""
    return _force_table(
        results,
        phase_deg,
        "damper: resonance frequency (Hz) at force",
        lambda c: _at_peak(c)[1],
        lambda v: fixed(v, 5),
        variant,
    )


def status_shares_table(
    results: StudyResults, phase_deg: float, variant: str | None = None
) -> Table:
    """Share of the pairs in each status at resonance (the harmonic-1 peak), percent: one
    row per damper and force."""
    rows = []
    for d in results.dampers:
        for c in curve_set(results, d, phase_deg, variant):
            s = c.status_shares(c.h1_peak_index)
            rows.append((d, f"{c.force_n:g}", *(_share(100.0 * s[k]) for k in STATUS_KEYS)))
    return Table(("damper", "force (N)", *(f"{n} (%)" for n in STATUS_NAMES)), tuple(rows))


def _share(pct: float) -> str:
    if math.isnan(pct):
        return "n/a"
    return "none" if pct == 0.0 else ("all" if pct == 100.0 else num(pct, 3))


def sweep_table(curves: Sequence[SweepCurve]) -> Table:
    """Long table of a sweep: damper, family, force, value, resonance, harmonic-1 amplitude,
    energy, stability at the peak."""
    if not curves:
        return Table(("damper",), ())
    opt = curves[0].option
    rows = []
    floor = energy_floor(np.concatenate([sc.energy_mj for sc in curves]))
    for sc in curves:
        for k in range(sc.value.size):
            rows.append(
                (
                    sc.damper,
                    sc.family,
                    f"{sc.force_n:g}",
                    f"{sc.value[k]:g}",
                    fixed(sc.freq_hz[k], 5),
                    num(sc.amp_mm[k], 4),
                    energy_text(sc.energy_mj[k], floor),
                    "failed" if sc.failed[k] else _verdict_word(sc, k),
                )
            )
    return Table(
        (
            "damper",
            "family",
            "force (N)",
            opt,
            "resonance (Hz)",
            "vibration amplitude, harmonic 1 (mm)",
            "friction energy per cycle (mJ)",
            "stability at the peak",
        ),
        tuple(rows),
    )


def _verdict_word(sc: SweepCurve, k: int) -> str:
    from ..render.palette import verdict_label

    if sc.verdict is None:
        return "stable" if sc.stable[k] else "not stable"
    return verdict_label(int(sc.verdict[k]))


def _nan(v: Any) -> float:
    return math.nan if v is None else float(v)
