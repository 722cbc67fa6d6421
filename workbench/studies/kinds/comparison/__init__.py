"""The comparison study: every damper x inter-blade phase x excitation level as a
frequency response, compared in one report (the engine's forced-response runner,
``workbench.studies.engine.runner``; its report sections are ``workbench.render.sections``,
shared with the sweep)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .. import StudyKind


def _run(spec: Any, out: Path, force: bool = False) -> dict[str, Any]:
    from ...engine.runner import run_forced_responses

    return run_forced_responses(spec, out, force=force)


KIND = StudyKind(
    name="comparison",
    description="dampers x phases x forces: frequency responses compared (the default)",
    run=_run,
    order=1,
)
