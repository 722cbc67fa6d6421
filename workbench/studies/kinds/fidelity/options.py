"""The fidelity study's own options: the knobs it varies, their levels and the tolerance.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ....errors import InputError
from ....post.knobs import KNOBS
from ....study_options import option


@dataclass(frozen=True)
class FidelityOptions:
    """The fidelity study's own options, one field each (``spec.fidelity.<name>``)."""

    tolerance: float | None = option(
        "percent",
        None,
        "accepted error, percent ('1' or '1%%'): pick the "
        "cheapest settings meeting it (fidelity studies)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        hi=100.0,
        optional=True,
        unit="%",
    )
    knobs: list[str] = option(
        "strs",
        ["mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper"],
        "knobs a fidelity study varies, one at a time about the base setting (the study's "
        "own mesh-size, modes, ...)",
        "fidelity",
        choices=KNOBS,
    )
    damper_phases: list[str] = option(
        "strs",
        [],
        "fidelity: the (damper, phase) pairs to solve, each 'damper phase' ('cone 0', "
        "'wedge 0', 'cone 180'), every pair at every force (empty: every damper at every phase)",
        "fidelity",
    )
    production_geometry: str | None = option(
        "path",
        None,
        "fidelity: the geometry file of a production job whose model differs from the "
        "study's (for instance point contacts against this study's contact pads): its "
        "cases are solved at the base setting and judged against this study's limit",
        "fidelity",
        optional=True,
    )
    levels_mesh_size: list[float] = option(
        "floats",
        [14.0, 11.0, 9.0, 7.0],
        "fidelity: global mesh sizes to try, mm (finest = smallest)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        unit="mm",
    )
    levels_contact_mesh_size: list[float] = option(
        "floats",
        [3.0, 1.5, 1.0],
        "fidelity: element sizes at the contact points to try, mm (finest = smallest)",
        "fidelity",
        lo=0.2,
        hi=50.0,
        unit="mm",
    )
    levels_modes: list[int] = option(
        "ints",
        [4, 8, 12, 24, 40],
        "fidelity: fixed-interface modes per body to try",
        "fidelity",
        lo=0,
        hi=400,
        unit="per body",
    )
    levels_harmonics: list[str] = option(
        "strs",
        ["1", "0-1", "0-3", "0-5", "0-7"],
        "fidelity: harmonic sets to try, each 'a-b' (a range) or 'h+h+...' (a list)",
        "fidelity",
    )
    levels_nt: list[int] = option(
        "ints",
        [16, 32, 64, 128, 256, 512],
        "fidelity: AFT time samples per period to try",
        "fidelity",
        lo=4,
        hi=8192,
        unit="samples per period",
    )
    levels_points_per_line: list[int] = option(
        "ints",
        [5, 11, 23, 33, 45],
        "fidelity: contact points per line to try",
        "fidelity",
        lo=2,
        hi=400,
        unit="per line",
    )
    points_contact_mesh_size: float | None = option(
        "float",
        None,
        "fidelity: the contact mesh size the points-per-line ladder runs at, mm (none: the "
        "base's). The size at the points is capped by their spacing, so at the base's size "
        "the finer levels also refine the mesh at the lines; at or below the finest level's "
        "spacing every level has the same size there and the ladder measures the points "
        "alone (its levels must then include the base's points)",
        "fidelity",
        lo=0.2,
        hi=50.0,
        optional=True,
        unit="mm",
    )
    levels_rigid_damper: list[str] = option(
        "strs",
        ["rigid", "flexible"],
        "fidelity: damper models to try (finest = flexible)",
        "fidelity",
        choices=("rigid", "flexible"),
    )


def parse_harmonics(text: Any, param: str = "levels-harmonics") -> list[int]:
    """'1' -> [1]; '0-3' -> [0, 1, 2, 3]; '1+3+5' -> [1, 3, 5]. Must contain 1."""
    allowed = "'a-b' (a range) or 'h+h+...' (a list) of harmonics >= 0 containing 1"
    s = str(text).strip()
    try:
        if "-" in s:
            a, b = (int(x) for x in s.split("-"))
            hs = list(range(a, b + 1))
        else:
            hs = [int(x) for x in s.split("+")]
    except ValueError:
        raise InputError(param, text, allowed) from None
    if not hs or 1 not in hs or min(hs) < 0 or len(set(hs)) != len(hs) or max(hs) > 64:
        raise InputError(param, text, allowed)
    return sorted(hs)


def damper_phases(spec: Any) -> list[tuple[str, float]]:
    """The study's (damper, phase) pairs: ``damper-phases`` parsed, or every damper at every
    phase. Each pair's damper must be one of ``dampers``, its phase one of ``phases``."""
    if not spec.fidelity.damper_phases:
        return [(d, float(p)) for d in spec.dampers for p in spec.phases]
    out: list[tuple[str, float]] = []
    for i, text in enumerate(spec.fidelity.damper_phases):
        param = f"damper-phases[{i}]"
        parts = str(text).split()
        allowed = (
            f"'damper phase' with a damper of dampers ({', '.join(spec.dampers)}) and a "
            f"phase of phases ({', '.join(f'{p:g}' for p in spec.phases)}), e.g. 'cone 0'"
        )
        if len(parts) != 2 or parts[0] not in spec.dampers:
            raise InputError(param, text, allowed)
        try:
            phase = float(parts[1])
        except ValueError:
            raise InputError(param, text, allowed) from None
        if phase not in [float(p) for p in spec.phases]:
            raise InputError(param, text, allowed)
        if (parts[0], phase) in out:
            raise InputError(param, text, "pairs that are not repeated")
        out.append((parts[0], phase))
    return out


def check(spec: Any) -> None:
    """Every harmonic set of ``levels-harmonics`` and every ``damper-phases`` pair parses."""
    for i, text in enumerate(spec.fidelity.levels_harmonics):
        parse_harmonics(text, f"levels-harmonics[{i}]")
    damper_phases(spec)
