"""The fidelity study: knob ladders against a reference, the Pareto front of time and
error, the cheapest setting within a tolerance (``compute.py``; settings in
``ladders.py``; charts in ``figures.py``, report sections in ``report.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import StudyKind
from .options import FidelityOptions, check


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from .compute import run_fidelity

    return run_fidelity(spec, out, force=force)


KIND = StudyKind(
    name="fidelity",
    description="knob ladders against a reference, Pareto front, cheapest setting "
    "within --tolerance",
    run=_run,
    options=FidelityOptions,
    check=check,
    order=3,
    shows=("dampers", "phases", "forces"),
)
