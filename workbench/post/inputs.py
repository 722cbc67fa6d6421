"""The inputs a study actually used: value, unit and where it came from, per study kind.

A study option left at ``None`` means "the value of the geometry or contact
file". :func:`used_inputs` resolves those to the numbers the models were
built with (the same loaders the runner calls), so the report's Inputs
table never shows "None", and lists only the options that apply to the
study's kind and dampers.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..geometry.shapes import all_shapes
from ..geometry.shapes import get as get_shape
from ..geometry.shapes import names as shape_names

ROOT = Path(__file__).resolve().parents[2]

UNITS: dict[str, str] = {
    "phases": "deg",
    "forces": "N",
    "response-blade": "",
    "band-in-phase": "Hz",
    "band-out-of-phase": "Hz",
    "band-margin": "fraction",
    "mu": "",
    "cf": "N",
    "kt-line": "N/m per m",
    "kn-line": "N/m per m",
    "kt-face": "N/m per m^2",
    "kn-face": "N/m per m^2",
    "damping": "ratio",
    "mesh-size": "mm",
    "modes": "per body",
    "points-per-line": "per line",
    "harmonics": "",
    "nt": "samples per period",
    "cone-angle": "deg",
    "max-points": "points per curve",
    "tolerance": "%",
    "levels-mesh-size": "mm",
    "levels-nt": "samples per period",
    "levels-points-per-line": "per line",
    "levels-modes": "per body",
    "peak-tolerance": "%",
}

_MODEL = (
    "mu",
    "cf",
    "kt-line",
    "kn-line",
    "kt-face",
    "kn-face",
    "damping",
    "mesh-size",
    "modes",
    "rigid-damper",
    "points-per-line",
    "cone-angle",
    "geometry",
)
_SOLVE = ("harmonics", "nt", "max-points", "stability")
_CASES = (
    "dampers",
    "phases",
    "forces",
    "response-blade",
    "band-in-phase",
    "band-out-of-phase",
    "band-margin",
)
KIND_OPTIONS: dict[str, tuple[str, ...]] = {
    "comparison": ("name", "kind", *_CASES, *_MODEL, *_SOLVE, "field-shapes"),
    "sweep": ("name", "kind", "sweep", "sweep-values", *_CASES, *_MODEL, *_SOLVE, "field-shapes"),
    "fidelity": (
        "name",
        "kind",
        "dampers",
        "phases",
        "forces",
        "tolerance",
        "knobs",
        "levels-mesh-size",
        "levels-modes",
        "levels-harmonics",
        "levels-nt",
        "levels-points-per-line",
        "levels-rigid-damper",
        *_MODEL,
        *_SOLVE,
    ),
    "robustness": (
        "name",
        "kind",
        "methods",
        "hard-cases",
        "peak-tolerance",
        "time-check",
        "response-blade",
        "band-margin",
        *_MODEL,
        *_SOLVE,
    ),
}


def _rel(p: Path | str) -> str:
    p = Path(p)
    try:
        return str(p.resolve().relative_to(ROOT))
    except ValueError:
        return str(p)


def _origin(source: str) -> str:
    """'default', 'command line', 'python API' or a study file (shown relative)."""
    if source in ("default", "command line", "python API", ""):
        return source or "default"
    return _rel(source)


def used_inputs(
    values: dict[str, Any], sources: dict[str, str] | None = None, kind: str | None = None
) -> list[dict[str, Any]]:
    """Rows ``{option, value, unit, source}`` for the options of this study kind.

    ``values`` are the spec's options (``StudySpec.as_dict()``), ``sources``
    where each came from (``StudySpec.source``).
    """
    from ..assembly.params import DEFAULT_FILE, ContactParams, load_contact_params

    sources = sources or {}
    kind = kind or values.get("kind", "comparison")
    names = KIND_OPTIONS.get(kind, KIND_OPTIONS["comparison"])
    dampers = list(values.get("dampers") or [])
    if kind == "robustness":
        from ..study_options import CASES

        dampers = sorted({CASES[n].damper for n in values.get("hard-cases") or [] if n in CASES})
    shapes = [get_shape(d) for d in dampers if d in shape_names()]
    skip = set()
    if not any(sh.contact == "line" for sh in shapes):
        skip |= {"kt-line", "kn-line"}
    if not any(sh.contact == "face" for sh in shapes):
        skip |= {"kt-face", "kn-face"}
    # a study option that reaches a shape's parameters (points-per-line, cone-angle, ...)
    # is shown when one of the dampers has it
    for option in {o for sh in all_shapes() for o in sh.study_options}:
        if not any(option in sh.study_options for sh in shapes):
            skip |= {option, f"levels-{option}"}

    contact_file = _rel(DEFAULT_FILE) if DEFAULT_FILE.is_file() else "ContactParams defaults"
    cp: ContactParams = load_contact_params()
    contact_default = {
        "mu": cp.mu,
        "cf": cp.cf_n,
        "kt-line": cp.kt_line_n_per_m2,
        "kn-line": cp.kn_line_n_per_m2,
        "kt-face": cp.kt_face_n_per_m3,
        "kn-face": cp.kn_face_n_per_m3,
    }
    geo_file = values.get("geometry")
    sweep = values.get("sweep") if kind == "sweep" else None

    shape_options = {o for sh in all_shapes() for o in sh.study_options}
    rows = []
    for name in names:
        if name in skip:
            continue
        v = values.get(name)
        src = _origin(sources.get(name, "default"))
        if name == sweep:
            v = values.get("sweep-values")
            src = f"swept ({_origin(sources.get('sweep-values', 'default'))})"
        elif v is None and name in contact_default:
            v, src = contact_default[name], f"default: {contact_file}"
        elif v is None and (name == "mesh-size" or name in shape_options):
            v, src = _geometry_default(name, dampers, geo_file)
        elif v is None and name == "nt":
            from ..hbm.fourier import default_nt

            v = default_nt(tuple(values.get("harmonics") or (1,)))
            src = "solver default (16 x the highest harmonic, at least 32)"
        elif name == "geometry":
            v = _rel(v) if v else "geometry/rig.toml + geometry/<damper>.toml"
        elif v is None and name == "tolerance":
            v = "none (no pick)"
        elif name in ("band-in-phase", "band-out-of-phase") and not v:
            v = "automatic"
            src = f"{src}: linear stuck and sliding limits +- band-margin"
        rows.append({"option": name, "value": v, "unit": UNITS.get(name, ""), "source": src})
    return rows


def _geometry_default(name: str, dampers: list[str], geo_file: Any) -> tuple[Any, str]:
    from ..geometry.params import load_geometry_params

    vals = {}
    for d in dampers:
        own = get_shape(d).study_options if d in shape_names() else {}
        if name != "mesh-size" and name not in own:
            continue
        gp = load_geometry_params(d, geo_file)
        vals[d] = gp.rig.mesh.size_mm if name == "mesh-size" else getattr(gp.shape, own[name][0])
    files = ["geometry/rig.toml"] if name == "mesh-size" else [f"geometry/{d}.toml" for d in vals]
    src = "default: " + (f"{_rel(geo_file)} over " if geo_file else "") + ", ".join(files)
    if not vals:
        return None, src
    uniq = set(vals.values())
    if len(uniq) == 1:
        return uniq.pop(), src
    return ", ".join(f"{d} {v:g}" for d, v in vals.items()), src
