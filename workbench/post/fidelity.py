"""The fidelity study's records and measures: settings, their labels and their errors.

A :class:`Setting` is one combination of the six modelling knobs with its
measured cases, charged stage times and relative errors against the
reference. This module holds the knob vocabulary (names, labels, which
level is finer), the error measures (``relative_errors``, ``worst``,
``ladder_self_errors``) and one table row per setting (``setting_row``).
It is plain data on computed :class:`~workbench.post.results.CaseResult`
records: the study (``workbench.studies.fidelity``) fills it, the report
(``workbench.render.fidelity_report``) draws it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..io import digest
from .results import CaseResult

KNOBS = ("mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper")


QUANTITIES = (
    ("peak_amplitude_mm", "peak amplitude", "mm"),
    ("peak_frequency_hz", "resonance frequency", "Hz"),
    ("friction_energy_mj", "friction energy per cycle", "mJ"),
)


STAGES = ("geometry", "reduction", "assembly", "hbm")


def harmonics_label(hs: list[int]) -> str:
    hs = sorted(hs)
    if len(hs) > 1 and hs == list(range(hs[0], hs[-1] + 1)):
        return f"{hs[0]}-{hs[-1]}"
    return "+".join(map(str, hs))


def level_label(knob: str, v: Any) -> str:
    """A short label of one knob value (used on the charts and in the tables)."""
    if knob == "mesh-size":
        return f"mesh {v:g} mm"
    if knob == "modes":
        return f"{v} modes"
    if knob == "harmonics":
        return f"H {harmonics_label(v)}"
    if knob == "nt":
        return f"nt {v}"
    if knob == "points-per-line":
        return f"{v} pts/line"
    if knob == "rigid-damper":
        return "rigid damper" if v else "flexible damper"
    raise AssertionError(knob)


def fineness(knob: str, v: Any) -> tuple:
    """Sort key: larger is finer (more accurate, more expensive)."""
    if knob == "mesh-size":
        return (-float(v),)
    if knob == "harmonics":
        return (max(v), len(v))
    if knob == "rigid-damper":
        return (0 if v else 1,)
    return (int(v),)


@dataclass
class Setting:
    """One combination of knob values, its measured cases, times and errors."""

    label: str
    values: dict[str, Any]  # knob -> value (all six knobs)
    role: str = "knob"  # "base", "knob", "reference", "combined"
    members: list[tuple[str, str]] = field(default_factory=list)  # (knob, level label)
    results: dict[str, CaseResult] = field(default_factory=dict)  # condition -> case
    times: dict[str, float] = field(default_factory=dict)  # stage -> s (charged)
    errors: dict[str, dict[str, float | None]] = field(default_factory=dict)  # cond -> q -> %

    @property
    def key(self) -> str:
        return digest(self.values, 16)

    @property
    def time_s(self) -> float:
        return float(sum(self.times.get(s, 0.0) for s in STAGES))

    @property
    def failed(self) -> list[str]:
        return [
            f"{c}: {r.branch.message or 'no resonance peak'}"
            for c, r in self.results.items()
            if r.branch.failed or r.peak_index < 0
        ]

    def error(self, q: str | None = None) -> float | None:
        """Largest error (percent) over the conditions, of quantity ``q`` or of all three."""
        return worst(self.errors, q)


def worst(errors: dict[str, dict[str, float | None]], q: str | None = None) -> float | None:
    """Largest of ``errors[condition][quantity]`` (percent); None if any is missing."""
    qs = [q] if q else [k for k, _, _ in QUANTITIES]
    vals = [errors.get(c, {}).get(k) for c in errors for k in qs]
    if not errors or any(v is None or not math.isfinite(v) for v in vals):
        return None
    return max(vals)


def condition_name(phase: float, force: float) -> str:
    return f"{phase:g} deg {force:g} N"


def relative_errors(st: Setting, ref: Setting) -> dict[str, dict[str, float | None]]:
    """condition -> quantity -> |q - q_ref| / |q_ref| in percent (None: no value to compare)."""
    out: dict[str, dict[str, float | None]] = {}
    for cond, r in st.results.items():
        rr = ref.results.get(cond)
        s = r.summary() if not r.branch.failed else {}
        sr = rr.summary() if rr is not None and not rr.branch.failed else {}
        out[cond] = {}
        for q, _, _ in QUANTITIES:
            a, b = s.get(q), sr.get(q)
            out[cond][q] = (
                abs(a - b) / abs(b) * 100.0 if a is not None and b is not None and b != 0 else None
            )
    return out


def ladder_self_errors(ladders: dict[str, list[Setting]]) -> dict[str, list[float | None]]:
    """knob -> worst error (percent) of each level against the knob's OWN finest level.

    The other knobs stay at the base in both, so this is the error that knob
    alone makes (its convergence), free of the other knobs' errors that every
    one-knob setting carries against the reference.
    """
    return {
        knob: [worst(relative_errors(st, lad[-1])) for st in lad] for knob, lad in ladders.items()
    }


def setting_row(st: Setting) -> dict[str, Any]:
    row: dict[str, Any] = {
        "label": st.label,
        "role": st.role,
        "knobs": "; ".join(f"{k}={m}" for k, m in st.members),
    }
    for k in KNOBS:
        row[k] = level_label(k, st.values[k])
    for s in STAGES:
        row[f"{s}_s"] = round(st.times.get(s, 0.0), 3)
    row["time_s"] = round(st.time_s, 3)
    for q, _, _ in QUANTITIES:
        e = st.error(q)
        row[f"err_{q}_pct"] = e
    row["max_error_pct"] = st.error()
    row["failed"] = "; ".join(st.failed)
    return row
