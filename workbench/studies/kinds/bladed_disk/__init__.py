"""The bladed-disk study: dampers x engine orders x forces on one cyclic sector
(``compute.py``; charts in ``figures.py``, report sections in ``report.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import StudyKind
from .options import BladedDiskOptions


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from .compute import run_bladed_disk

    return run_bladed_disk(spec, out, force=force)


KIND = StudyKind(
    name="bladed_disk",
    description="dampers x engine orders x forces on a bladed disk's sector: the worst EO",
    run=_run,
    options=BladedDiskOptions,
    order=6,
    shows=("dampers", "forces"),
    # the sector has its own reduction (sector-modes, contact-points) and flexible damper;
    # Hill's stability runs on the worst peaks only (bladed disk) or not at all (mistuning)
    ignores=("modes", "rigid-damper", "points-per-line", "stability"),
)
