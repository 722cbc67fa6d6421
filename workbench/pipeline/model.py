"""The model pipeline: a case's options -> geometry -> reduction -> assembled system -> curve.

Every study kind, the API and the CLI get their models here: :func:`prepare_model`
meshes, reduces and assembles the model of a case (each stage cached on disk
under ``out/cache``), :func:`band_for` picks its frequency band and
:func:`solve_case` computes its frequency response. A *case* is any object
with the attributes of :class:`workbench.studies.engine.plan.Case` (``damper``,
``phase_deg``, ``force_n``, ``variant``, ``name``, ``digest`` and the option
values in ``settings``); this package never imports the studies.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..io import digest
from ..post.results import CaseResult

Case = Any  # a workbench.studies.engine.plan.Case (see the module docstring)


@dataclass
class PreparedModel:
    """Everything the cases of one model share."""

    geometry: Any  # BuiltGeometry
    geometry_dir: Path
    assembled: Any  # AssembledModel
    system: Any  # hbm System
    bands: dict[float, tuple[float, float, dict[str, float]]]
    timings: dict[str, float]
    contact_params: Any = None
    # stage -> what it cost when it was computed, for the stages reused from the cache
    cached: dict[str, float] = field(default_factory=dict)
    # the reduced models ("rig", "damper"), for full-mesh fields (studies/engine/fields.py)
    reduced: dict[str, Any] = field(default_factory=dict)


def geometry_request(case: Case) -> dict[str, Any]:
    """build_geometry arguments for a case (overrides from the study options)."""
    from ..geometry.shapes import get as get_shape

    s = case.settings
    overrides: dict[str, Any] = {}
    # the study options that reach this shape's parameters (points-per-line, cone-angle, ...)
    for option, (name, kind) in get_shape(case.damper).study_options.items():
        if s.get(option) is not None:
            overrides.setdefault(case.damper, {})[name] = kind(s[option])
    if s.get("contact-mesh-size") is not None:  # the element size at the contact points
        overrides["rig"] = {"mesh": {"contact_size_mm": float(s["contact-mesh-size"])}}
    return {
        "damper": case.damper,
        "geometry_file": s.get("geometry"),
        "size_mm": s.get("mesh-size"),
        "overrides": overrides or None,
    }


def contact_params_for(case: Case):
    from ..assembly.params import load_contact_params
    from ..post.provenance import contact_args  # the layers the report names, one mapping

    return load_contact_params(**contact_args(case.settings))


def prepare_model(case: Case, out: Path, *, force: bool = False, comm=None) -> PreparedModel:
    """Mesh, reduce and assemble the model of ``case`` (each stage cached on disk)."""
    from ..assembly.model import assemble
    from ..fe.reduce import model_path, reduce_body
    from ..hbm.core.system import System
    from ..log import stage

    timings: dict[str, float] = {}
    cached: dict[str, float] = {}
    gdir = geometry_dir(case, out)
    t0 = time.time()
    with stage(timings, "geometry"):
        geom = load_geometry(case, out)
    if _older(gdir / "geometry.h5", t0):  # reused: its cost is the one of its first build
        cached["geometry"] = float(sum((geom.stats.get("timings_s") or {}).values()))
    s = case.settings
    fe_dir = out / "cache" / "fe"
    reduced = {}
    for body in ("rig", "damper"):
        t0 = time.time()
        with stage(timings, f"reduction {body}"):
            reduced[body] = reduce_body(
                geom,
                body,
                n_modes=s["modes"],
                rigid=s["rigid-damper"] and body == "damper",
                cache_dir=fe_dir,
                comm=comm,
                force=force,
            )
        rm = reduced[body]
        if _older(model_path(fe_dir, rm.inputs, rm.digest), t0):
            cached[f"reduction {body}"] = float(rm.timings.get("total", 0.0))
    rig, damper = reduced["rig"], reduced["damper"]
    with stage(timings, "assembly"):
        beta = float(geom.params["rig"]["platform"]["angle_deg"])
        cparams = contact_params_for(case)
        model = assemble(
            rig,
            damper,
            geom.contact,
            cparams,
            beta_deg=beta,
            excitation_direction=tuple(geom.excitation_direction),
            response_direction=tuple(geom.response_direction),
        )
        system = System(M=model.M, K=model.K, zeta=s["damping"], contacts=model.contact_elements())
    return PreparedModel(geom, gdir, model, system, {}, timings, cparams, cached, reduced)


def _older(path: Path, t0: float) -> bool:
    """True when ``path`` exists and was written before ``t0`` (time.time()): a reused file."""
    try:
        return path.stat().st_mtime < t0
    except OSError:
        return False


def geometry_dir(case: Case, out: Path) -> Path:
    """The cached geometry folder of a case's model."""
    return out / "cache" / "geometry" / f"{case.damper}-{digest(geometry_request(case), 10)}"


def load_geometry(case: Case, out: Path, comm=None):
    """The case's BuiltGeometry (built once, then read from its cache folder)."""
    from ..geometry import build_geometry

    req = geometry_request(case)
    return build_geometry(
        req["damper"],
        geometry_dir(case, out),
        geometry_file=req["geometry_file"],
        size_mm=req["size_mm"],
        overrides=req["overrides"],
        comm=comm,
    )


def band_for(prep: PreparedModel, case: Case) -> tuple[float, float]:
    """The case's frequency band: given in the study, or automatic for its family."""
    s = case.settings
    fam = case.phase_deg % 360.0
    given = (
        s["band-in-phase"]
        if abs(fam) < 1e-9
        else s["band-out-of-phase"]
        if abs(fam - 180.0) < 1e-9
        else []
    )
    if given:
        return float(given[0]), float(given[1])
    if case.phase_deg not in prep.bands:
        from ..assembly.linear import auto_band

        prep.bands[case.phase_deg] = auto_band(
            prep.assembled, case.phase_deg, s["band-margin"], s["response-blade"]
        )
    lo, hi, _ = prep.bands[case.phase_deg]
    return lo, hi


def solve_case(prep: PreparedModel, case: Case) -> CaseResult:
    """The frequency response of one case (never raises for a failed solve)."""
    from ..hbm.core.options import SolverOptions
    from ..hbm.forced.response import frequency_response
    from ..post.provenance import solve_inputs  # the inputs, read from the objects used

    s = case.settings
    t0 = time.perf_counter()
    band = band_for(prep, case)
    model = prep.assembled
    opts = SolverOptions(stability=s["stability"], max_points=s["max-points"])
    blade = s["response-blade"]
    branch = frequency_response(
        prep.system,
        model.excitation(case.phase_deg),
        case.force_n,
        band,
        outputs=model.response_dofs[blade - 1 : blade],
        harmonics=tuple(s["harmonics"]),
        nt=s["nt"],
        options=opts,
        output_names=(f"blade{blade}_x",),
        label=case.name,
    )
    timings = {**prep.timings, "hbm": time.perf_counter() - t0}
    return CaseResult(
        damper=case.damper,
        phase_deg=case.phase_deg,
        force_n=case.force_n,
        branch=branch,
        points=model.contact.points,
        side=model.contact.side,
        variant=case.variant,
        params={**case.settings, "band_hz": list(band)},
        digest=case.digest,
        timings=timings,
        inputs=solve_inputs(prep, s, branch, opts),
    )
