"""Planning a fidelity study: knob levels from the study file, the settings to solve.

Parses the ``levels-<knob>`` options, resolves the base setting's 'file
default' values to numbers, lays out the unique settings (the base, one
ladder per varied knob, the reference: every varied knob at its finest
level) and proposes a combination of per-knob levels for a tolerance.
Nothing here solves; ``workbench.studies.kinds.fidelity.compute`` computes the settings.
"""

from __future__ import annotations

import json
from typing import Any

from ....errors import InputError
from ....post.fidelity import Setting, fineness, level_label
from ...engine.spec import StudySpec
from .options import parse_harmonics


def knob_applies(knob: str, damper: str) -> bool:
    """Whether ``knob`` reaches the model of ``damper`` (points per line: not the wedge's
    faces, which have their own grid of points)."""
    from ....geometry.shapes import get as get_shape

    return knob != "points-per-line" or knob in get_shape(damper).study_options


def base_values(spec: StudySpec, dampers: list[str]) -> dict[str, Any]:
    """The base setting's knob values, with 'file default' (None) resolved to numbers.

    The rig's mesh sizes are the same for every damper; the points per line
    are the first damper's that has contact lines (None if none has)."""
    from ....geometry import load_geometry_params
    from ....hbm.core.fourier import default_nt

    v = {
        "mesh-size": spec.mesh_size,
        "contact-mesh-size": spec.contact_mesh_size,
        "modes": int(spec.modes),
        "harmonics": sorted(int(h) for h in spec.harmonics),
        "nt": spec.nt,
        "points-per-line": spec.points_per_line,
        "rigid-damper": bool(spec.rigid_damper),
    }
    for damper in dampers:
        if None not in (v["mesh-size"], v["contact-mesh-size"], v["points-per-line"]):
            break
        gp = load_geometry_params(damper, spec.geometry)
        if v["mesh-size"] is None:
            v["mesh-size"] = float(gp.rig.mesh.size_mm)
        if v["contact-mesh-size"] is None:
            v["contact-mesh-size"] = float(gp.rig.mesh.contact_size_mm)
        if v["points-per-line"] is None:
            v["points-per-line"] = int(getattr(gp.shape, "n_contact_points", 0)) or None
    if v["nt"] is None:
        v["nt"] = default_nt(tuple(v["harmonics"]))
    return v


def knob_levels(spec: StudySpec) -> dict[str, list[Any]]:
    """knob -> its levels (settings values), coarsest first, for the knobs the study varies."""
    raw = {
        "mesh-size": [float(x) for x in spec.fidelity.levels_mesh_size],
        "contact-mesh-size": [float(x) for x in spec.fidelity.levels_contact_mesh_size],
        "modes": [int(x) for x in spec.fidelity.levels_modes],
        "harmonics": [parse_harmonics(x) for x in spec.fidelity.levels_harmonics],
        "nt": [int(x) for x in spec.fidelity.levels_nt],
        "points-per-line": [int(x) for x in spec.fidelity.levels_points_per_line],
        "rigid-damper": [x == "rigid" for x in spec.fidelity.levels_rigid_damper],
    }
    out: dict[str, list[Any]] = {}
    for knob in spec.fidelity.knobs:
        levels = raw[knob]
        if not levels:
            raise InputError(
                f"levels-{knob}", levels, f"at least one level (or drop {knob} from knobs)"
            )
        keys = [json.dumps(x) for x in levels]
        if len(set(keys)) != len(keys):
            raise InputError(
                f"levels-{knob}",
                getattr(spec.fidelity, f"levels_{knob}".replace("-", "_")),
                "distinct levels",
            )
        out[knob] = sorted(levels, key=lambda x, k=knob: fineness(k, x))
    return out


def _settings_dict(base: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    s = dict(base)
    for k, v in values.items():
        s[k] = list(v) if isinstance(v, list) else v
    return s


def plan_settings(
    spec: StudySpec, dampers: list[str]
) -> tuple[list[Setting], dict[str, list[Setting]]]:
    """The unique settings (base, one-knob ladders, reference) and each knob's ladder."""
    base_v = base_values(spec, dampers)
    levels = knob_levels(spec)
    unique: dict[str, Setting] = {}

    def add(values: dict[str, Any], label: str, role: str) -> Setting:
        st = Setting(label, values, role)
        if st.key in unique:
            return unique[st.key]
        unique[st.key] = st
        return st

    base = add(dict(base_v), "base", "base")
    base.members.append(("base", "base"))
    ladders: dict[str, list[Setting]] = {}
    held = held_values(spec, dampers, base_v, levels)
    for knob, lv in levels.items():
        ladders[knob] = []
        for v in lv:
            vals = sampled(base_v, dict(base_v, **held.get(knob, {}), **{knob: v}))
            label = level_label(knob, v) + "".join(
                f", {level_label(k, x)}" for k, x in held.get(knob, {}).items()
            )
            if vals["nt"] != base_v["nt"] and knob == "harmonics":
                label += f", nt {vals['nt']}"
            st = add(vals, label, "knob")
            st.members.append((knob, label))
            ladders[knob].append(st)
    ref_v = dict(base_v)
    for knob, lv in levels.items():
        ref_v[knob] = max(lv + [base_v[knob]], key=lambda x, k=knob: fineness(k, x))
    ref_v = sampled(base_v, ref_v)
    if "nt" in levels and ref_v["nt"] > max(levels["nt"] + [base_v["nt"]]):
        raise InputError(
            "levels-nt",
            levels["nt"],
            f"a level of nt {ref_v['nt']} or more: the reference's harmonics "
            f"{ref_v['harmonics']} are sampled at nt {ref_v['nt']}, and an nt ladder "
            "that stops below it cannot correct the reference",
        )
    ref = add(ref_v, "reference", "reference")
    ref.role, ref.label = "reference", "reference"  # may coincide with a knob's finest level
    ref.members.append(("reference", "reference"))
    for st in unique.values():
        _check_sampling(st.values)
    return list(unique.values()), ladders


def held_values(
    spec: StudySpec, dampers: list[str], base_v: dict[str, Any], levels: dict[str, list[Any]]
) -> dict[str, dict[str, Any]]:
    """knob -> the other knobs' values its ladder holds away from the base (empty: none).

    Only the points per line have one: ``points-contact-mesh-size``, the contact mesh
    size their ladder runs at. The size at the contact points is capped by their spacing
    (``workbench.geometry.layout``), so at the base's size a level with more points also
    refines the mesh at the lines and its step mixes two knobs. The size must therefore be
    at or below the contact spacing of the finest level on every damper the points reach,
    and the levels must include the base's points: that level is the ladder's *pivot*,
    the base's points at the held size (:func:`ladder_pivot`), which the knob's error of the
    base is read from. The knob's correction of the limit (its limit minus its finest level)
    is taken at the held size, the other knobs' at the base: the knobs' errors are assumed
    to add, as everywhere in the all-knob limit."""
    size = spec.fidelity.points_contact_mesh_size
    if size is None or "points-per-line" not in levels:
        return {}
    param = "points-contact-mesh-size"
    lv = levels["points-per-line"]
    if base_v["points-per-line"] not in lv:
        raise InputError(
            "levels-points-per-line",
            lv,
            f"levels that include the base's {base_v['points-per-line']} points per line "
            f"(with {param} = {size:g} mm that level is the ladder's pivot)",
        )
    from ....geometry import load_geometry_params
    from ....geometry.layout import make_layout
    from ....geometry.shapes import get as get_shape

    finest = max(lv)
    for damper in dampers:
        if not knob_applies("points-per-line", damper):
            continue
        name, kind = get_shape(damper).study_options["points-per-line"]
        gp = load_geometry_params(
            damper, spec.geometry, {damper: {name: kind(finest)}}, base_v["mesh-size"]
        )
        spacing = make_layout(gp).contact_spacing
        if size > spacing * (1.0 + 1e-9):
            raise InputError(
                param,
                size,
                f"at most {spacing:.4g} mm, the {damper}'s contact spacing at {finest} points "
                "per line (a larger size is capped by the spacing there, so the ladder would "
                "refine the mesh at the lines as well as the points)",
            )
    return {"points-per-line": {"contact-mesh-size": float(size)}}


def ladder_pivot(knob: str, ladder: list[Setting], base: Setting) -> Setting | None:
    """The level of ``knob``'s ladder at the base's value of it: the base itself, or the
    base's value at the values the ladder holds (:func:`held_values`). None if the
    ladder has no such level."""
    return next((st for st in ladder if st.values[knob] == base.values[knob]), None)


def sampled(base_v: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    """``values`` with nt raised, where its harmonics go beyond the base's, to the solver's
    default for them (``default_nt``: 16 samples per period of the highest harmonic or
    more), never lowered: a user who asks for more harmonics gets that sampling too, and
    a harmonics ladder at a fixed nt would let aliasing into its finest levels (harmonics
    0-7 at nt 64: 9 samples per period of the 7th). The nt knob measures the sampling at
    the base's harmonics."""
    from ....hbm.core.fourier import default_nt

    h, hb = values["harmonics"], base_v["harmonics"]
    if max(h) <= max(hb):
        return values
    return dict(values, nt=max(int(values["nt"]), default_nt(tuple(h))))


def _check_sampling(v: dict[str, Any]) -> None:
    if v["nt"] <= 2 * max(v["harmonics"]):
        raise InputError(
            "levels-nt",
            v["nt"],
            f"nt > 2 * max(harmonics) = "
            f"{2 * max(v['harmonics'])} for every setting (sampling theorem)",
        )


def propose_combination(
    ladders: dict[str, list[Setting]],
    tolerance_pct: float,
    shift: int = 0,
    errors: dict[str, list[float | None]] | None = None,
) -> tuple[dict[str, Any], dict[str, str]] | None:
    """Per knob, the coarsest level whose error meets the tolerance (``shift`` levels finer).

    ``errors``: knob -> the error of each level (percent, coarsest first);
    default: each one-knob setting's error against the reference. Returns
    (knob -> value, knob -> why) or None when a knob has no level meeting
    the tolerance. The caller samples the combination as :func:`sampled` says.
    """
    values: dict[str, Any] = {}
    why: dict[str, str] = {}
    for knob, ladder in ladders.items():
        errs = errors[knob] if errors is not None else [st.error() for st in ladder]
        idx = [i for i, e in enumerate(errs) if e is not None and e <= tolerance_pct]
        if not idx:
            return None
        i = min(idx[0] + shift, len(ladder) - 1)
        values[knob] = ladder[i].values[knob]
        e = errs[i]
        why[knob] = (
            f"{level_label(knob, values[knob])} ({e:.3g} %)"
            if e is not None
            else level_label(knob, values[knob])
        )
    return values, why
