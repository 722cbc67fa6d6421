"""The sweep study: the comparison's cases once per value of one swept scalar option
(``sweep``, ``sweep-values``; the engine's plan and runner, report sections in
``workbench.render.sweep_sections``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ....study_options import SHOWN
from .. import StudyKind


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from ...engine.runner import run_forced_responses

    return run_forced_responses(spec, out, force=force)


KIND = StudyKind(
    name="sweep",
    description="the comparison once per value of one option (--sweep, --sweep-values)",
    run=_run,
    order=2,
    shows=("sweep", "sweep-values", *SHOWN),
)
