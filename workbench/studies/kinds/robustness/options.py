"""The robustness study's own options: the solution methods, the hard cases, the checks.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`). The methods and cases are named in
:mod:`workbench.hard_cases`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ....hard_cases import CASES, METHODS
from ....study_options import option

ROBUSTNESS_METHODS = tuple(METHODS)
ROBUSTNESS_CASES = tuple(CASES)


@dataclass(frozen=True)
class RobustnessOptions:
    """The robustness study's own options, one field each (``spec.robustness.<name>``)."""

    methods: list[str] = option(
        "strs",
        list(ROBUSTNESS_METHODS),
        "solution methods of a robustness "
        "study (named solver variants; the first is the reference): "
        + ", ".join(ROBUSTNESS_METHODS),
        "robustness",
        choices=ROBUSTNESS_METHODS,
    )
    hard_cases: list[str] = option(
        "strs",
        list(ROBUSTNESS_CASES),
        "hard cases of a robustness study: " + ", ".join(ROBUSTNESS_CASES),
        "robustness",
        choices=ROBUSTNESS_CASES,
    )
    peak_tolerance: float = option(
        "float",
        1.0,
        "robustness: a method that converges but whose "
        "peak amplitude differs from the first method's by more than this, percent, is a "
        "wrong answer",
        "robustness",
        lo=0.0,
        lo_open=True,
        hi=100.0,
        unit="%",
    )
    time_check: bool = option(
        "bool",
        True,
        "robustness: check the harmonic balance against time "
        "integration at its suspect points (small models)",
        "robustness",
    )
