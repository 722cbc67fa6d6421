"""The uncertainty study: sampled inputs, the peak's distribution and Sobol indices
(``compute.py``; the design in ``samples.py``, seat misalignment in
``imperfection.py``; charts in ``figures.py``, report sections in ``report.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ....study_options import CASES
from .. import StudyKind
from .options import UncertaintyOptions, check


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from .compute import run_uncertainty

    return run_uncertainty(spec, out, force=force)


KIND = StudyKind(
    name="uncertainty",
    description="sampled inputs: distributions of the peak, Sobol indices (MPI)",
    run=_run,
    options=UncertaintyOptions,
    check=check,
    order=5,
    shows=CASES,
)
