"""The inputs a study actually used: value, unit and where it came from, per study kind.

A study option left at ``None`` means "the value of the geometry or contact
file". :func:`used_inputs` resolves those to the numbers the models were
built with (the same loaders the runner calls), so the report's Inputs
table never shows "None", and lists only the options that apply to the
study's kind and dampers.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..geometry.shapes import all_shapes
from ..geometry.shapes import get as get_shape
from ..geometry.shapes import names as shape_names
from ..study_options import input_table
from .provenance import _rel_source, contact_fields, contact_value, rel

ROOT = Path(__file__).resolve().parents[2]

_rel = rel


def _origin(source: str) -> str:
    """'default', 'command line', 'python API' or a study file (shown relative)."""
    if source in ("default", "command line", "python API", ""):
        return source or "default"
    return _rel(source)


def used_inputs(
    values: dict[str, Any],
    sources: dict[str, str] | None = None,
    kind: str | None = None,
    table: Sequence[tuple[str, str]] | None = None,
) -> list[dict[str, Any]]:
    """Rows ``{option, value, unit, source}`` for the options of this study kind.

    ``values`` are the spec's options (``StudySpec.as_dict()``), ``sources``
    where each came from (``StudySpec.source``), ``table`` the rows
    ``(option, unit)`` to list (the study engine gives the kind's, read from
    its registry entry; None: the comparison's,
    :func:`workbench.study_options.input_table`).
    """
    from ..assembly.params import ContactParams, contact_sources, load_contact_params

    sources = sources or {}
    kind = kind or values.get("kind", "comparison")
    table = tuple(table) if table is not None else input_table()
    dampers = list(values.get("dampers") or [])
    if kind == "robustness":
        from ..hard_cases import CASES

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

    geo_file = values.get("geometry")
    # the layers the runner loads (geometry/contact.toml < the geometry file's [contact])
    cp: ContactParams = load_contact_params(geometry_file=geo_file)
    csrc = contact_sources(geometry_file=geo_file)
    contact_default = {
        opt: (contact_value(cp, f), f"default: {_rel_source(csrc[f])}")
        for f, opt in contact_fields()
    }
    sweep = values.get("sweep") if kind == "sweep" else None

    shape_options = {o for sh in all_shapes() for o in sh.study_options}
    rows = []
    for name, unit in table:
        if name in skip:
            continue
        v = values.get(name)
        src = _origin(sources.get(name, "default"))
        if name == sweep:
            v = values.get("sweep-values")
            src = f"swept ({_origin(sources.get('sweep-values', 'default'))})"
        elif v is None and name in contact_default:
            v, src = contact_default[name]
        elif v is None and (name == "mesh-size" or name in shape_options):
            v, src = _geometry_default(name, dampers, geo_file)
        elif v is None and name == "nt":
            from ..hbm.core.fourier import default_nt

            v = default_nt(tuple(values.get("harmonics") or (1,)))
            src = "solver default (16 x the highest harmonic, at least 32)"
        elif name == "geometry":
            v = _rel(v) if v else "geometry/rig.toml + geometry/<damper>.toml"
        elif v is None and name == "tolerance":
            v = "none (no pick)"
        elif v is None:  # an optional kind option left unset: its help says what then
            v = "not set"
        elif name in ("band-in-phase", "band-out-of-phase") and not v:
            v = "automatic"
            src = f"{src}: linear stuck and sliding limits +- band-margin"
        rows.append({"option": name, "value": v, "unit": unit, "source": src})
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


# ---- the report's table: the study's options and what the solve recorded ----------------

# a recorded input -> the study option that sets it (its "option" source is named by the spec)
OPTION_OF = {
    "mu": "mu",
    "cf": "cf",
    "kt_line": "kt-line",
    "kn_line": "kn-line",
    "kt_face": "kt-face",
    "kn_face": "kn-face",
    "mesh_size": "mesh-size",
    "modes": "modes",
    "rigid_damper": "rigid-damper",
    "damping": "damping",
    "harmonics": "harmonics",
    "nt": "nt",
    "band": "band-in-phase",
    "response": "response-blade",
    "geometry_files": "geometry",
    "solver_options": "max-points",
}
# study options whose values the solve records (they leave the study part of the table)
RECORDED_OPTIONS = set(OPTION_OF.values()) | {
    "band-out-of-phase",
    "points-per-line",
    "cone-angle",
}
MAX_LISTED = 4  # more distinct values than this: the range, and where to find each


def _option_of(key: str, damper: str) -> str | None:
    if key.startswith("shape/") and damper in shape_names():
        field = key.split("/", 1)[1]
        return next(
            (o for o, (f, _) in get_shape(damper).study_options.items() if f == field), None
        )
    return OPTION_OF.get(key)


def study_inputs(
    cases: list[Any],
    values: dict[str, Any],
    sources: dict[str, str] | None = None,
    table: Sequence[tuple[str, str]] | None = None,
) -> list[dict[str, Any]]:
    """The report's Inputs rows: the study's own options, then every input the solve of
    its cases recorded (``CaseResult.inputs``), grouped (``group``: Study, Contact, Model,
    Damping, Harmonic balance, Code).

    An input that differs between cases (a sweep, the dampers' own stiffnesses) is
    listed per case label (``damper [variant]``). Cases solved before the inputs were
    recorded fall back to :func:`used_inputs` (resolved again from the files).
    """
    from .provenance import GROUPS

    sources = sources or {}
    recorded = [c for c in cases if getattr(c, "inputs", None)]
    base = used_inputs(values, sources, table=table)
    if not recorded:
        return [dict(r, group="Study and model (resolved again from the files)") for r in base]
    rows = [dict(r, group="Study") for r in base if r["option"] not in RECORDED_OPTIONS]
    keys = list(dict.fromkeys(k for c in recorded for k in c.inputs))
    dampers = list(dict.fromkeys(c.damper for c in recorded))
    for group in GROUPS:
        if group == "run":  # the machine's load: the report's cost section says it
            continue
        for key in keys:
            per = [(c, c.inputs[key]) for c in recorded if key in c.inputs]
            if not per or per[0][1].get("group") != group:
                continue
            rows.append(_merged_row(key, per, sources, GROUPS[group], dampers))
    missing = [c.case_id for c in cases if not getattr(c, "inputs", None)]
    if missing:
        rows.append(
            {
                "option": "cases without a record",
                "value": ", ".join(missing),
                "unit": "",
                "source": "solved by an earlier version; their inputs are not in this table",
                "group": "Study",
            }
        )
    return rows


def _label(c: Any, family: bool = False) -> str:
    return c.damper + (f" [{c.variant}]" if c.variant else "") + (f", {c.family}" if family else "")


def _merged_row(
    key: str, per: list, sources: dict[str, str], group: str, dampers: list[str]
) -> dict[str, Any]:
    first = per[0][1]

    def src(c: Any, e: dict) -> str:
        s = e.get("source", "")
        if s == "option":
            opt = _option_of(key, c.damper)
            return _origin(sources.get(opt, "default")) if opt else "study option"
        return s

    by_value: dict[str, list] = {}
    for c, e in per:
        by_value.setdefault(json.dumps(e["value"], sort_keys=True, default=str), []).append((c, e))
    label = f"{first.get('label', key)} ({key})"
    if key == "solver_options":  # JSON in the files; "name = value" for a reader
        per = [(c, {**e, "value": _options_text(e["value"])}) for c, e in per]
        first = per[0][1]
    if len(by_value) == 1:
        value = first["value"]
        srcs = list(dict.fromkeys(src(c, e) for c, e in per))
        names = list(dict.fromkeys(c.damper for c, _ in per))
        who = "" if names == dampers else " (" + ", ".join(names) + ")"
        return {
            "option": label + who,
            "value": value,
            "unit": first.get("unit", ""),
            "source": "; ".join(srcs),
            "group": group,
        }
    groups = list(by_value.values())
    if len(groups) > MAX_LISTED and all(isinstance(g[0][1]["value"], (int, float)) for g in groups):
        vs = sorted(float(g[0][1]["value"]) for g in groups)
        value: Any = f"{len(groups)} values, {vs[0]:.4g} to {vs[-1]:.4g}"
    else:
        parts = []
        # a value of each case (the band): name the family too
        per_case = len({_label(c) for c, _ in per}) < len(per)
        for g in groups:
            who = ", ".join(dict.fromkeys(_label(c, per_case) for c, _ in g))
            parts.append(f"{who}: {_short(g[0][1]['value'])}")
        value = "; ".join(parts)
    srcs = list(dict.fromkeys(src(c, e) for c, e in per))
    return {
        "option": label,
        "value": value,
        "unit": first.get("unit", ""),
        "source": "; ".join(srcs),
        "group": group,
    }


def _options_text(text: str) -> str:
    try:
        opts = json.loads(text)
    except (TypeError, ValueError):
        return str(text)
    return "; ".join(f"{k} = {_short(v)}" for k, v in opts.items())


def _short(v: Any) -> str:
    from .tables import num

    if isinstance(v, float):
        return num(v, 4)
    if isinstance(v, list):
        return ", ".join(_short(x) for x in v)
    return str(v)
