"""The coupling screen of a study's models: ``upd screen`` and the report's screen table.

For every model of a study (damper x swept value) and every inter-blade
phase, :func:`workbench.assembly.screen.screen` on the assembled stuck
model, with the rig bound from the same rig and a rigid damper. The FE
reductions are those of the study (same cache folder), so a screen before
``upd study`` costs nothing afterwards, and a study computes its screen
from models it has anyway.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

from ...assembly.screen import ScreenResult, linear_pair, screen
from .plan import Case, plan
from .spec import StudySpec

log = logging.getLogger(__name__)


def rigid_bound_model(prep, case: Case, out: Path, comm=None):
    """The case's rig with a rigid 6-DOF damper (same contact layout and parameters)."""
    from ...assembly.model import assemble
    from ...fe.reduce import reduce_body

    geom = prep.geometry
    s = case.settings
    rig = reduce_body(geom, "rig", n_modes=s["modes"], cache_dir=out / "cache" / "fe", comm=comm)
    dmp = reduce_body(
        geom, "damper", n_modes=0, rigid=True, cache_dir=out / "cache" / "fe", comm=comm
    )
    beta = float(geom.params["rig"]["platform"]["angle_deg"])
    return assemble(
        rig,
        dmp,
        geom.contact,
        prep.contact_params,
        beta_deg=beta,
        excitation_direction=tuple(geom.excitation_direction),
        response_direction=tuple(geom.response_direction),
    )


def screen_prepared(
    prep, case: Case, phases, out: Path, *, comm=None, f_max_n: float | None = None
) -> list[ScreenResult]:
    """The screen of one prepared model (``pipeline.PreparedModel``) for each phase."""
    s = case.settings
    bound = rigid_bound_model(prep, case, out, comm)
    blade = s["response-blade"]
    return [
        screen(
            linear_pair(prep.assembled, ph, blade),
            s["damping"],
            phase_deg=ph,
            bound=linear_pair(bound, ph, blade),
            f_max_n=f_max_n,
        )
        for ph in phases
    ]


def screen_row(case: Case, res: ScreenResult) -> dict[str, Any]:
    """One flat, JSON-able row: the damper, the variant and the screen's numbers."""
    return {"damper": case.damper, "variant": case.variant, **res.as_dict()}


def screen_key(case: Case, phases, f_max_n: float) -> str:
    """Cache key of a model's screen: the model, the phases, the force range, the code."""
    from ...io import code_version, digest

    root = Path(__file__).resolve().parents[2]  # workbench/
    return digest(
        {
            "model": case.model_digest,
            "phases": [float(p) for p in phases],
            "f_max": float(f_max_n),
            "blade": case.settings["response-blade"],
            "code": [
                code_version(root / "assembly"),
                code_version(root / "studies" / "engine", ("screening.py",)),
            ],
        },
        16,
    )


def study_screens(
    cases: list[Case], prepared: dict, out: Path, phases, f_max_n: float, *, comm=None
) -> list[dict[str, Any]]:
    """Screen rows of every model of a study, cached in ``out/cache/screen/``.

    Models already prepared for the study's cases are used as they are; the
    others are loaded from the FE cache (a resumed study has no prepared
    model but must show the same table). Collective under MPI.
    """
    from ...io import write_json
    from ...pipeline import prepare_model

    models: dict[str, Case] = {}
    for c in cases:
        models.setdefault(c.model_digest, c)
    sdir = out / "cache" / "screen"
    keys = {md: screen_key(c, phases, f_max_n) for md, c in models.items()}
    rank = 0 if comm is None else comm.rank
    missing = None
    if rank == 0:
        missing = [md for md in models if not (sdir / f"{keys[md]}.json").is_file()]
    if comm is not None:
        missing = comm.bcast(missing, root=0)
    for md in missing:
        c = models[md]
        prep = prepared.get(md) or prepare_model(c, out, comm=comm)
        rows = [
            screen_row(c, r)
            for r in screen_prepared(prep, c, phases, out, comm=comm, f_max_n=f_max_n)
        ]
        if rank == 0:
            write_json(sdir / f"{keys[md]}.json", rows)
    if comm is not None:
        comm.Barrier()
    import json

    rows: list[dict[str, Any]] = []
    for md in models:
        rows.extend(json.loads((sdir / f"{keys[md]}.json").read_text()))
    return rows


def run_screen(spec: StudySpec, out: str | Path, *, comm=None) -> dict[str, Any]:
    """Screen every model of ``spec``: rows (one per model and phase) and timings.

    The meshes and reductions of all models are first computed concurrently
    (:mod:`.prefetch`: local workers, or under mpirun whole models per rank);
    ``timings`` then holds what each model cost afterwards and ``pool`` the
    pool's figures (workers, wall seconds, seconds per task).
    """
    from ...log import progress_bar
    from ...pipeline import prepare_model

    out = Path(out)
    cases = plan(spec)
    models: dict[str, Case] = {}
    for c in cases:
        models.setdefault(c.model_digest, c)
    f_max = max(spec.forces)
    rows: list[dict[str, Any]] = []
    timings: dict[str, float] = {}
    # meshes and reductions of every model at once: local workers, or one model per rank
    from .prefetch import prefetch_models

    pool = prefetch_models(list(models.values()), out, comm, rigid_bound=True)
    with progress_bar("screen: models", total=len(models), unit="model") as bar:
        for c in models.values():
            t0 = time.perf_counter()
            bar.set_postfix_str(c.damper + (f" {c.variant}" if c.variant else ""))
            prep = prepare_model(c, out, comm=comm)
            for res in screen_prepared(prep, c, spec.phases, out, comm=comm, f_max_n=f_max):
                row = screen_row(c, res)
                row["seconds"] = time.perf_counter() - t0
                rows.append(row)
            key = c.damper + (f" {c.variant}" if c.variant else "")
            timings[key] = time.perf_counter() - t0
            bar.update(1)
    return {"rows": rows, "timings": timings, "f_max_n": f_max, "pool": pool}


# the table's formatting lives in post/screen_table.py; kept importable from here
__all__ = [
    "rigid_bound_model",
    "run_screen",
    "screen_key",
    "screen_prepared",
    "screen_row",
    "study_screens",
]
