"""The fidelity study's own options: the knobs it varies, their levels and the tolerance.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`).
"""

from __future__ import annotations

from typing import Any

from ....errors import InputError
from ....study_options import Option

OPTIONS: tuple[Option, ...] = (
    Option(
        "tolerance",
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
    ),
    Option(
        "knobs",
        "strs",
        ["mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper"],
        "knobs a fidelity study varies, one at a time about the base setting (the study's "
        "own mesh-size, modes, ...)",
        "fidelity",
        choices=("mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper"),
    ),
    Option(
        "levels-mesh-size",
        "floats",
        [14.0, 11.0, 9.0, 7.0],
        "fidelity: global mesh sizes to try, mm (finest = smallest)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        unit="mm",
    ),
    Option(
        "levels-modes",
        "ints",
        [4, 8, 12, 24, 40],
        "fidelity: fixed-interface modes per body to try",
        "fidelity",
        lo=0,
        hi=400,
        unit="per body",
    ),
    Option(
        "levels-harmonics",
        "strs",
        ["1", "0-1", "0-3", "0-5", "0-7"],
        "fidelity: harmonic sets to try, each 'a-b' (a range) or 'h+h+...' (a list)",
        "fidelity",
    ),
    Option(
        "levels-nt",
        "ints",
        [16, 32, 64, 128, 256, 512],
        "fidelity: AFT time samples per period to try",
        "fidelity",
        lo=4,
        hi=8192,
        unit="samples per period",
    ),
    Option(
        "levels-points-per-line",
        "ints",
        [5, 11, 23, 33, 45],
        "fidelity: contact points per line to try",
        "fidelity",
        lo=2,
        hi=400,
        unit="per line",
    ),
    Option(
        "levels-rigid-damper",
        "strs",
        ["rigid", "flexible"],
        "fidelity: damper models to try (finest = flexible)",
        "fidelity",
        choices=("rigid", "flexible"),
    ),
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


def check(spec: Any) -> None:
    """Every harmonic set of ``levels-harmonics`` parses."""
    for i, text in enumerate(spec.levels_harmonics):
        parse_harmonics(text, f"levels-harmonics[{i}]")
