"""The mistuning study's own options: the scatter of the blade frequencies and its sampling.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`). The disk (``n-blades``, the
sector's mesh sizes and contact points, ``sector-modes``, ``damper-modes``)
and the engine orders (``eos``) are the bladed-disk study's options, the
dampers and forces the shared ``dampers`` and ``forces``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ....study_options import option

SAMPLINGS = ("sobol", "lhs")


@dataclass(frozen=True)
class MistuningOptions:
    """The mistuning study's own options, one field each (``spec.mistuning.<name>``)."""

    mistuning_std: float = option(
        "percent",
        2.0,
        "mistuning: standard deviation of the blade frequencies, percent of the tuned "
        "blade's ('2' or '2%%'); a blade whose frequency deviates by df has its stiffness "
        "scaled by (1 + df)^2",
        "mistuning",
        lo=0.0,
        hi=50.0,
        unit="%",
        role="case",
    )
    mistuning_patterns: int = option(
        "int",
        50,
        "mistuning: number of sampled mistuning patterns (one frequency deviation per blade "
        "each) per damper",
        "mistuning",
        lo=2,
        hi=100000,
        role="case",
    )
    mistuning_sampling: str = option(
        "str",
        "sobol",
        "mistuning: design of the patterns on the unit cube (scipy.stats.qmc), mapped to "
        "normal deviates by the inverse CDF: sobol (scrambled; a larger count keeps the "
        "patterns of a smaller one) or lhs (Latin hypercube)",
        "mistuning",
        choices=SAMPLINGS,
        role="case",
    )
    mistuning_seed: int = option(
        "int",
        2026,
        "mistuning: seed of the pattern design",
        "mistuning",
        lo=0,
        hi=2**31 - 1,
        role="case",
    )


def check(spec: Any) -> None:
    """A mistuning study's sampled patterns keep every blade's frequency and stiffness
    positive (only a study of kind ``mistuning`` samples them)."""
    if spec.kind != "mistuning":
        return
    from .patterns import study_patterns

    study_patterns(spec)
