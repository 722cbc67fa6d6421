"""The mistuning study: sampled blade frequency deviations on a bladed disk, per damper the
amplification of the worst blade without damper, with the damper stuck and in friction
(``compute.py``; the patterns in ``patterns.py``, the tables and files in ``write.py``,
charts in ``figures.py``, report sections in ``report.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import StudyKind
from .options import MistuningOptions, check


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from .compute import run_mistuning

    return run_mistuning(spec, out, force=force)


KIND = StudyKind(
    name="mistuning",
    description="sampled blade mistuning on a bladed disk: the worst blade's amplification "
    "without damper, stuck, in friction (MPI)",
    run=_run,
    options=MistuningOptions,
    check=check,
    order=7,
    # the disk and its engine orders are the bladed-disk study's options
    shows=(
        "dampers",
        "forces",
        "n-blades",
        "eos",
        "sector-modes",
        "damper-modes",
        "contact-mesh-size",
        "damper-mesh-size",
        "contact-points",
    ),
    # the sector has its own reduction (sector-modes, contact-points) and flexible damper;
    # Hill's stability runs on the worst peaks only (bladed disk) or not at all (mistuning)
    ignores=("modes", "rigid-damper", "points-per-line", "stability"),
)
