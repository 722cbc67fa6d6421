"""The answer a damper engineer reads first, and the table of every case.

:func:`answer` ranks the dampers of each family at the study's highest
force by their vibration amplitude at resonance (the largest harmonic-1
amplitude of the response, :attr:`CaseResult.h1_mm`), with the ratio to
the least, max |x(t)| and the mean term at the same point, the friction
energy and the stability verdict there; it says at which forces the
ranking holds and how sure the numbers are (stability verdicts, curves
that failed or stopped before their peak, the harmonic-balance accuracy
indicator, the nonlinear-mode cross-check where it ran, what the study did
not vary). :func:`cases_table` is the table of every case.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..hbm.stability.along_path import HOW_CARRIED, HOW_HILL, HOW_LINEAR
from .results import CaseResult, StudyResults, family_name
from .tables import (
    Table,
    _at_peak,
    _peak_extra,
    base_variant,
    energy_floor,
    energy_text,
    families,
    fixed,
    num,
)


@dataclass(frozen=True)
class AnswerRow:
    """One damper of one family at one force, at its harmonic-1 peak."""

    case: CaseResult
    amp_mm: float  # harmonic-1 amplitude at resonance (NaN: no point)
    freq_hz: float
    max_abs_mm: float
    mean_mm: float
    energy_mj: float
    verdict: int  # stability code at the peak
    covered: bool  # the curve went over its peak (else amp_mm is a lower bound)
    ratio: float = math.nan  # amp_mm over the family's least

    @property
    def damper(self) -> str:
        return self.case.damper


def _row(c: CaseResult) -> AnswerRow:
    amp, freq, energy, _ = _at_peak(c)
    code, max_abs, mean, covered = _peak_extra(c)
    return AnswerRow(c, amp, freq, max_abs, mean, energy, code, covered)


def ranked(cases: list[CaseResult]) -> list[AnswerRow]:
    """The cases' answer rows, least amplitude first (curves without a point last), with
    the ratio of each amplitude to the least."""
    rows = sorted((_row(c) for c in cases), key=lambda r: (math.isnan(r.amp_mm), r.amp_mm))
    best = next((r.amp_mm for r in rows if not math.isnan(r.amp_mm) and r.amp_mm > 0), math.nan)
    return [
        AnswerRow(**{**r.__dict__, "ratio": r.amp_mm / best if best == best else math.nan})
        for r in rows
    ]


def answer(results: StudyResults, variant: str | None = None) -> dict[str, Any]:
    """``{"force_n", "rows": {phase: [AnswerRow]}, "sentences": [...], "sure": [...]}``
    for the study's highest force (empty rows when the study has no case)."""
    variant = base_variant(results) if variant is None else variant
    forces = [f for f in results.forces if results.select(force_n=f, variant=variant)]
    if not forces:
        return {"force_n": None, "rows": {}, "sentences": [], "sure": []}
    f_top = forces[-1]
    rows = {
        p: ranked(results.select(phase_deg=p, force_n=f_top, variant=variant))
        for p in families(results)
    }
    rows = {p: r for p, r in rows.items() if r}
    sentences = [_family_sentence(results, p, rs, forces, variant) for p, rs in rows.items()]
    return {
        "force_n": f_top,
        "rows": rows,
        "sentences": sentences,
        "sure": confidence(results, rows),
    }


def _amp(r: AnswerRow) -> str:
    if math.isnan(r.amp_mm):
        return "no point"
    return (">= " if not r.covered else "") + f"{num(r.amp_mm, 3)} mm"


def _family_sentence(
    results: StudyResults, p: float, rows: list[AnswerRow], forces: list[float], variant: str
) -> str:
    fam = family_name(p)
    head = f"{fam[0].upper()}{fam[1:]}, at {rows[0].case.force_n:g} N"
    best = rows[0]
    if len(rows) == 1:
        return f"{head}: the {best.damper} vibrates {_amp(best)} (harmonic-1 amplitude)."
    others = ", ".join(
        f"the {r.damper} {r.ratio:#.3g} times as much ({_amp(r)})"
        if r.ratio == r.ratio
        else f"the {r.damper}: no point computed"
        for r in rows[1:]
    )
    text = f"{head}: the {best.damper} vibrates least, {_amp(best)} (harmonic-1 amplitude); "
    text += others + "."
    # does the ranking hold at every force?
    winners = {}
    for f in forces:
        rs = ranked(results.select(phase_deg=p, force_n=f, variant=variant))
        if rs and not math.isnan(rs[0].amp_mm):
            winners[f] = rs[0].damper
    if len(set(winners.values())) == 1 and len(winners) > 1:
        text += f" It is the least at every force from {forces[0]:g} to {forces[-1]:g} N."
    elif len(winners) > 1:
        parts = [
            f"the {d} at {', '.join(f'{f:g}' for f, w in winners.items() if w == d)} N"
            for d in dict.fromkeys(winners.values())
        ]
        text += " The least changes with the force: " + "; ".join(parts) + "."
    return text


def confidence(results: StudyResults, rows: dict[float, list[AnswerRow]]) -> list[str]:
    """How sure the answer is, one sentence per kind of doubt."""
    from ..render.palette import verdict_counts, verdict_label, verdicts_shown

    out = []
    allc = np.concatenate([c.branch.stability for c in results.cases]) if results.cases else []
    counts = verdict_counts(np.asarray(allc, dtype=int))
    words = ", ".join(f"{counts.get(v.code, 0)} {v.label}" for v in verdicts_shown(counts))
    sentence = f"Stability of the {int(sum(counts.values()))} computed points: {words}"
    hows = (
        np.concatenate([c.branch.stability_how for c in results.cases])
        if results.cases
        else np.zeros(0, int)
    )
    n_hill, n_lin, n_car = (int(np.sum(hows == k)) for k in (HOW_HILL, HOW_LINEAR, HOW_CARRIED))
    if n_lin or n_car:  # how each verdict was obtained (workbench/hbm/stability/along_path.py)
        sentence += (
            f" (Hill's method at {n_hill} points; {n_lin} with every contact stuck take the "
            f"linear system's verdict; {n_car} carry the verdict of the checked points around "
            "them)"
        )
    sentence += "."
    doubtful = [
        f"{r.damper} {r.case.family} ({verdict_label(r.verdict)})"
        for rs in rows.values()
        for r in rs
        if r.verdict != 1 and not math.isnan(r.amp_mm)
    ]
    sentence += (
        " At the peaks of the table: every verdict stable."
        if not doubtful
        else " At the peaks of the table, not stable: " + ", ".join(doubtful) + "."
    )
    out.append(sentence)
    bad = [c for c in results.cases if c.branch.failed]
    early = [c for c in results.cases if not c.branch.failed and not c.branch.completed]
    edge = [c for c in results.cases if c.branch.completed and not c.branch.failed]
    edge = [c for c in edge if not c.h1_peak_covered]
    n = len(results.cases)
    if not (bad or early or edge):
        out.append(f"Curves: all {n} complete, each with its peak inside its band.")
    else:
        parts = []
        for what, cs in (
            ("failed", bad),
            ("stopped early", early),
            ("peak at the band edge", edge),
        ):
            if cs:
                parts.append(f"{len(cs)} {what} ({', '.join(c.case_id for c in cs)})")
        out.append(
            f"Curves: {n - len(bad) - len(early) - len(edge)} of {n} complete with their peak "
            "inside the band; " + "; ".join(parts) + ": their peaks are lower bounds."
        )
    acc = [float(a) for c in results.cases for a in c.branch.accuracy if a == a]
    if acc:
        tol = _accuracy_tol(results.cases)
        out.append(
            "Harmonic truncation and time sampling: the accuracy indicator (loop energy "
            "against the harmonic contact work, a share of the excitation work) is at most "
            f"{num(100 * max(acc), 2)} % over every point"
            + (f" (the solver warns above {num(100 * tol, 2)} %)." if tol else ".")
        )
    nl = results.extras.get("nlmodes") or {}
    errs = [r for r in nl.get("rows", []) if r.get("error_pct") is not None]
    if errs:
        ok = [r for r in errs if r.get("valid")]
        if ok:
            worst = max(abs(r["error_pct"]) for r in ok)
            out.append(
                f"Cross-check by nonlinear modes: the synthesised peaks (max |x(t)|) are within "
                f"{num(worst, 2)} % of the curves' on the {len(ok)} of {len(errs)} peaks where "
                "the synthesis is valid."
            )
        else:
            out.append(
                f"Cross-check by nonlinear modes: the synthesis is flagged not valid at all "
                f"{len(errs)} peaks; the curves are the answer."
            )
    out.append(_not_varied(results.cases))
    return out


def _accuracy_tol(cases: list[CaseResult]) -> float | None:
    for c in cases:
        e = c.inputs.get("solver_options")
        if e:
            try:
                return float(json.loads(e["value"]).get("accuracy_tol"))
            except (ValueError, TypeError, AttributeError):
                return None
    return None


def _not_varied(cases: list[CaseResult]) -> str:
    """What the study did not check: the mesh, the modes and the harmonics it used."""
    c = next((c for c in cases if c.inputs), None)
    if c is None:
        return (
            "Mesh size, modes and harmonics were not varied in this study: "
            "studies/fidelity.toml measures their error."
        )
    inp = c.inputs

    def v(key: str) -> str:
        e = inp.get(key)
        if e is None:
            return "?"
        val = e["value"]
        return ", ".join(str(x) for x in val) if isinstance(val, list) else f"{val:g}"

    return (
        f"Not varied in this study: mesh size ({v('mesh_size')} mm), modes per body "
        f"({v('modes')}), harmonics ({v('harmonics')}); studies/fidelity.toml measures the "
        "error of each."
    )


ANSWER_HEADER = (
    "family",
    "damper (least first)",
    "amplitude, harmonic 1 (mm)",
    "x the least",
    "resonance (Hz)",
    "max |x(t)| (mm)",
    "mean x (mm)",
    "friction energy per cycle (mJ)",
    "stability at the peak",
)


def mean_text(mean_mm: float, amp_mm: float) -> str:
    """The mean term for a table: 3 significant digits, "0" when below 1e-6 of the
    amplitude (round-off of a response without a mean)."""
    if mean_mm != mean_mm:
        return "n/a"
    if abs(mean_mm) <= 1e-6 * abs(amp_mm):
        return "0"
    return num(mean_mm, 3)


def answer_table(rows: dict[float, list[AnswerRow]]) -> Table:
    """The answer rows as a table (cells as the report shows them)."""
    from ..render.palette import verdict_label

    all_e = [r.energy_mj for rs in rows.values() for r in rs]
    floor = energy_floor(all_e)
    out = []
    for p, rs in rows.items():
        for k, r in enumerate(rs):
            none = math.isnan(r.amp_mm)
            amp = "no point" if none else num(r.amp_mm, 4)
            if not none and not r.covered:
                amp = f">= {amp} (peak not reached)"
            if r.case.branch.failed:
                amp += " (failed)"
            out.append(
                (
                    family_name(p) if k == 0 else "",
                    r.damper,
                    amp,
                    "" if none else ("1 (least)" if k == 0 else f"{r.ratio:#.3g}"),
                    "" if none else fixed(r.freq_hz, 5),
                    "" if none else num(r.max_abs_mm, 4),
                    "" if none else mean_text(r.mean_mm, r.amp_mm),
                    "" if none else energy_text(r.energy_mj, floor),
                    "" if none else verdict_label(r.verdict),
                )
            )
    return Table(ANSWER_HEADER, tuple(out))


def verdict_counts(stability: np.ndarray) -> dict[int, int]:
    """Points per stability code (1 stable, 0 unstable, -1 unknown; any other code too)."""
    from ..render.palette import verdict_counts as counts

    return counts(stability)


def cases_table(results: StudyResults) -> Table:
    """One row per case: the harmonic-1 peak with max |x(t)| and the mean term at it, energy,
    the stability verdict at the peak and the points of each verdict, cost, completion."""
    from ..render.palette import VERDICTS, verdict_label

    codes = [v.code for v in VERDICTS]
    for c in results.cases:  # a verdict code that is not in the palette's table
        codes += [k for k in np.unique(c.branch.stability).tolist() if k not in codes]
    variants = any(c.variant for c in results.cases)
    header = (
        "damper",
        "family",
        "force (N)",
        *(("variant",) if variants else ()),
        "resonance (Hz)",
        "vibration amplitude, harmonic 1 (mm)",
        "max |x(t)| at that point (mm)",
        "mean of x at that point (mm)",
        "friction energy per cycle (mJ)",
        "stability at the peak",
        *(f"{verdict_label(k)} points" for k in codes),
        "curve",
        "wall time (s)",
    )
    floor = energy_floor([_at_peak(c)[2] for c in results.cases])
    rows = []
    for c in results.cases:
        i = c.h1_peak_index
        amp, freq, energy, _ = _at_peak(c)
        code, max_abs, mean, covered = _peak_extra(c)
        counts = verdict_counts(c.branch.stability)
        a = num(amp, 4) if covered else (f">= {num(amp, 4)} (peak not reached)" if i >= 0 else "")
        rows.append(
            (
                c.damper,
                c.family,
                f"{c.force_n:g}",
                *((c.variant,) if variants else ()),
                fixed(freq, 5) if i >= 0 else "",
                a,
                num(max_abs, 4) if i >= 0 else "",
                mean_text(mean, max_abs) if i >= 0 else "",
                energy_text(energy, floor) if i >= 0 else "",
                verdict_label(code) if i >= 0 else "",
                *(str(counts.get(k, 0)) for k in codes),
                _curve_cell(c),
                num(float(c.timings.get("hbm", c.branch.timings.get("total", 0.0))), 3),
            )
        )
    return Table(header, tuple(rows))


def _curve_cell(c: CaseResult) -> str:
    b = c.branch
    if b.failed:
        return f"failed after {b.n_points} points: {b.message}"
    if not b.completed:
        return f"stopped early after {b.n_points} points: {b.message or 'no reason recorded'}"
    if not c.h1_peak_covered:
        return f"complete, {b.n_points} points; peak at the band edge"
    return f"complete, {b.n_points} points"
