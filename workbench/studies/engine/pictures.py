"""The report's pictures of each damper's model: the rig with the damper and its stuck modes.

One picture set per damper, of the first model of that damper in plan
order (a sweep prepares several models of one damper: the report shows the
first, so the others need no stuck-mode solve); made also when every case
came from the cache, so a resumed study's report has the pictures an
uninterrupted one has. Under MPI every rank takes part in each damper's
FE modes solve and rank 0 draws.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from ...io import digest, write_json


def study_pictures(cases, prepared: dict, out: Path, comm, cached_costs: dict) -> bool:
    """Draw the pictures of every damper of ``cases`` that are not up to date.

    ``cached_costs`` gets what the reused ones cost when drawn. Returns True
    when any was drawn. Collective under MPI.
    """
    from ...pipeline import contact_params_for, load_geometry

    firsts = [c for i, c in enumerate(cases) if c.damper not in {x.damper for x in cases[:i]}]

    def picture(k: int) -> dict[str, Any]:
        c = firsts[k]
        prep = prepared.get(c.model_digest)
        geom, cparams = (
            (prep.geometry, prep.contact_params)
            if prep is not None
            else (load_geometry(c, out), contact_params_for(c))
        )
        return {"damper": c.damper, "cost": model_pictures(geom, cparams, out, comm=comm)}

    # every rank takes part in each damper's modes (collective FE): a rank solving alone on
    # its own communicator leaves PETSc objects that its exit then cleans up collectively,
    # which the other rank never joins (a hang at exit, seen with PETSc 3.18)
    pics = [picture(k) for k in range(len(firsts))]
    made = False
    for r in pics:
        if r["cost"] is None:
            old = _picture_cost(out, r["damper"])
            if old:
                cached_costs["model pictures"] = cached_costs.get("model pictures", 0.0) + old
        else:
            made = True
    return made


def model_pictures(geometry, contact_params, out: Path, *, comm=None) -> float | None:
    """The rig with the damper, and its stuck first bending modes, for the report.

    ``figures/model_<damper>.png`` and ``figures/modes_<damper>.png``; done
    again only when the geometry or the contact parameters changed (their
    digest is kept beside, in ``figures/.model_<damper>.json``, with what
    drawing them cost). The modes are those of the full FE model with the
    damper stuck (every rank takes part); rank 0 draws. Returns the time
    spent, s, or None when the pictures were up to date.
    """
    import json

    from ...fe.modes import compute_modes

    t0 = time.perf_counter()
    damper = geometry.damper
    figs = out / "figures"
    stamp = figs / f".model_{damper}.json"
    key = digest({"geometry": geometry.digest, "contact": contact_params.key()})
    rank = 0 if comm is None else comm.rank
    fresh = False
    if rank == 0:
        try:
            fresh = json.loads(stamp.read_text()).get("key") == key and all(
                (figs / f"{k}_{damper}.png").is_file() for k in ("model", "modes")
            )
        except (OSError, ValueError, AttributeError):
            fresh = False
    if comm is not None:
        fresh = comm.bcast(fresh, root=0)
    if fresh:
        return None
    res = compute_modes(geometry, contact="stuck", n=4, contact_params=contact_params, comm=comm)
    if rank == 0:
        import shutil
        import tempfile

        from ...render.modes import render_modes
        from ...render.scene import render_scene

        figs.mkdir(parents=True, exist_ok=True)
        render_scene(geometry, figs / f"model_{damper}.png", title=f"rig with the {damper} damper")
        with tempfile.TemporaryDirectory() as tmp:
            made = [p for p in render_modes(res, tmp, modes=[]) if p.name == "first_bending.png"]
            if made:
                shutil.copyfile(made[0], figs / f"modes_{damper}.png")
        write_json(stamp, {"key": key, "cost_s": round(time.perf_counter() - t0, 3)})
    return time.perf_counter() - t0


def _picture_cost(out: Path, damper: str) -> float:
    """What drawing a damper's (cached) model pictures cost, s (0 when unknown)."""
    import json

    try:
        return float(
            json.loads((out / "figures" / f".model_{damper}.json").read_text()).get("cost_s", 0.0)
        )
    except (OSError, ValueError, TypeError, AttributeError):
        return 0.0
