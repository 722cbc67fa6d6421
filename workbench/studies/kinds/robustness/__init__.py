"""The robustness study: solution methods x hard cases, the map of success and failure
(``compute.py``; one cell in ``cells.py``, the time-integration checks in
``time_check.py``; charts in ``figures.py``, report sections in ``report.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import StudyKind
from .options import RobustnessOptions


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from .compute import run_robustness

    return run_robustness(spec, out, force=force)


KIND = StudyKind(
    name="robustness",
    description="solution methods x hard cases: the map of success and failure",
    run=_run,
    options=RobustnessOptions,
    order=4,
    shows=("response-blade", "band-margin"),
)
