"""The inputs a case was solved with, read from the objects the solve used.

:func:`solve_inputs` is called by the study runner right after a case's
curve is computed, with the prepared model (its contact parameters, built
geometry, assembled model and harmonic-balance system), the case's
settings, the branch and the solver options. It returns one entry per
input::

    key -> {"value": ..., "unit": "N", "source": "geometry/paper_rig.toml [contact]",
            "label": "centrifugal load on the damper", "group": "contact"}

The values are those of the objects themselves (the contact parameters
the assembly received, the preload it computed, the mesh size the
geometry was built with, the harmonics and samples the branch was
solved with), never a second reading of the files, so the report's Inputs
table, results.h5 (``case/inputs``, a ``unit`` attribute on each) and
summary.json cannot disagree with the computation. ``source`` says where a
value came from: "option" (a study option: the report names the study
file or the command line), a parameter file and its table, "computed
from ..." or a default.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..contact.law_params import law_params

ROOT = Path(__file__).resolve().parents[2]

GROUPS = {
    "contact": "Contact",
    "model": "Model",
    "damping": "Damping",
    "solve": "Harmonic balance",
    "code": "Code",
    "run": "Machine during the solve",
}

_CONTACT = (  # ContactParams field, study option, key, label, unit, contact kind
    # the contact laws' parameters (mu, then each law's own), as each law declares them
    *((p.name, p.name, p.name, p.help, p.unit or "1", None) for p in law_params()),
    ("cf_n", "cf", "cf", "centrifugal load on the damper", "N", None),
    (
        "kt_line_n_per_m2",
        "kt-line",
        "kt_line",
        "tangential stiffness per metre of contact line",
        "N/m per m",
        "line",
    ),
    (
        "kn_line_n_per_m2",
        "kn-line",
        "kn_line",
        "normal stiffness per metre of contact line",
        "N/m per m",
        "line",
    ),
    (
        "kt_face_n_per_m3",
        "kt-face",
        "kt_face",
        "tangential stiffness per square metre of contact face",
        "N/m per m^2",
        "face",
    ),
    (
        "kn_face_n_per_m3",
        "kn-face",
        "kn_face",
        "normal stiffness per square metre of contact face",
        "N/m per m^2",
        "face",
    ),
)


def rel(p: Path | str) -> str:
    """A path relative to the repository when it lies inside it, else as given."""
    p = Path(p)
    try:
        return str(p.resolve().relative_to(ROOT))
    except (ValueError, OSError):
        return str(p)


def _e(value: Any, unit: str, source: str, label: str, group: str) -> dict[str, Any]:
    return {"value": value, "unit": unit, "source": source, "label": label, "group": group}


def _rel_source(src: str) -> str:
    """'/abs/geometry/paper_rig.toml [contact]' -> 'geometry/paper_rig.toml [contact]'."""
    if src.endswith("]") and " [" in src:
        path, table = src.rsplit(" [", 1)
        return f"{rel(path)} [{table}"
    return src


def contact_args(settings: Mapping[str, Any]) -> dict[str, Any]:
    """The arguments of ``load_contact_params`` for a case's settings (what the runner's
    ``contact_params_for`` passes)."""
    return {
        "geometry_file": settings.get("geometry"),
        **{field: settings.get(opt) for field, opt, *_ in _CONTACT},
    }


def contact_value(cp: Any, field: str) -> float:
    """A ContactParams value by its field name or contact-law parameter name."""
    return float(cp.law[field] if field in getattr(cp, "law", {}) else getattr(cp, field))


def contact_fields() -> tuple[tuple[str, str], ...]:
    """(ContactParams field or law parameter, study option) of every contact value."""
    return tuple((field, opt) for field, opt, *_ in _CONTACT)


def _contact(cp: Any, settings: Mapping[str, Any], kind: str) -> dict[str, dict]:
    from ..assembly.params import contact_sources, load_contact_params

    args = contact_args(settings)
    src = {k: _rel_source(v) for k, v in contact_sources(**args).items()}
    try:
        same = load_contact_params(**args) == cp
    except Exception:  # noqa: BLE001 - a file removed since: the values stand, the source not
        same = False
    out = {}
    for field, _, key, label, unit, only in _CONTACT:
        if only is not None and only != kind:
            continue
        where = src[field] if same else "as the model was built (its files changed since)"
        out[key] = _e(contact_value(cp, field), unit, where, label, "contact")
    return out


def _file_of(settings: Mapping[str, Any], damper: str, table: tuple[str, ...], key: str) -> str:
    """The geometry file that sets ``[table...] key``: the study's geometry file if it has
    it, else the default file of that table."""
    from ..config import read_toml

    geo = settings.get("geometry")
    if geo:
        try:
            node: Any = read_toml(geo)
            for t in table:
                node = node.get(t, {})
            if key in node:
                return f"{rel(geo)} [{'.'.join(table)}]"
        except Exception:  # noqa: BLE001 - unreadable now: name the default below
            pass
    default = "geometry/rig.toml" if table[0] == "rig" else f"geometry/{damper}.toml"
    return f"{default} [{'.'.join(table)}]"


def _unit_of(key: str) -> str:
    for suffix, unit in (("_mm", "mm"), ("_deg", "deg"), ("_n", "N"), ("_kg", "kg")):
        if key.endswith(suffix):
            return unit
    return "1"


def solve_inputs(prep: Any, settings: Mapping[str, Any], branch: Any, options: Any) -> dict:
    """Every input of one solved case, from the objects the solve used (see the module).

    ``prep``: the runner's prepared model (``contact_params``, ``geometry``,
    ``assembled``, ``system``); ``settings``: the case's study options;
    ``branch``: the computed :class:`~workbench.hbm.forced.branch.Branch`;
    ``options``: the :class:`~workbench.hbm.core.options.SolverOptions` used.
    """
    import dataclasses

    import numpy as np

    geom, model, system, cp = prep.geometry, prep.assembled, prep.system, prep.contact_params
    damper = geom.damper
    kind = model.contact.kind
    beta = float(geom.params["rig"]["platform"]["angle_deg"])
    out: dict[str, dict] = {}
    out.update(_contact(cp, settings, kind))
    side = np.asarray(model.contact.side)
    n0 = np.asarray(model.n0, dtype=float)
    per_side = float(n0[side == 0].sum())
    out["preload_per_side"] = _e(
        per_side,
        "N",
        "computed from cf, mu and the platform angle: cf / (2 (sin beta + mu cos beta))",
        "normal preload on each side of the groove (sum over its pairs)",
        "contact",
    )
    out["slip_limit_per_side"] = _e(
        float(np.mean(model.mu)) * per_side,
        "N",
        "computed: mu times the preload per side",
        "tangential force at which a whole side slips (mu N0)",
        "contact",
    )
    out["kt_total"] = _e(
        float(np.sum(model.kt)),
        "N/m",
        "computed: per-unit stiffness times each pair's length or area, summed",
        "tangential stiffness of all the pairs together",
        "contact",
    )
    out["kn_total"] = _e(
        float(np.sum(model.kn)),
        "N/m",
        "computed: per-unit stiffness times each pair's length or area, summed",
        "normal stiffness of all the pairs together",
        "contact",
    )
    out["n_pairs"] = _e(
        int(model.n_pairs), "1", "the built geometry", f"contact pairs ({kind} contact)", "contact"
    )
    out["contact_law"] = _e(
        str(getattr(system.contacts, "law", "decoupled")),
        "",
        "solver default",
        "friction law of each pair (workbench/contact/laws)",
        "contact",
    )
    out["platform_angle"] = _e(
        beta,
        "deg",
        _file_of(settings, damper, ("rig", "platform"), "angle_deg"),
        "platform angle beta (face from the radial direction)",
        "model",
    )
    # the model
    geo = settings.get("geometry")
    out["geometry_files"] = _e(
        (f"{rel(geo)} over " if geo else "") + f"geometry/rig.toml, geometry/{damper}.toml",
        "",
        "option" if geo else "default",
        "parameter files of the rig and the damper (later files win)",
        "model",
    )
    gm = geom.params["rig"]["mesh"]
    # [rig.mesh] entries: value, unit, the study option that can set it, label
    for name, field, value, unit, option, label in (
        ("mesh_size", "size_mm", float(gm["size_mm"]), "mm", "mesh-size",
         "mesh size (quadratic tetrahedra)"),
        ("contact_mesh_size", "contact_size_mm", float(gm["contact_size_mm"]), "mm",
         "contact-mesh-size",
         "element size at the contact points (capped by their spacing and the mesh size)"),
        ("contact_pads", "pad_mm", float(gm.get("pad_mm", 0.0)), "mm", None,
         "width of the rigid pad tied to each contact point (0: the node alone)"),
        ("mirror_meshes", "mirror", bool(gm.get("mirror", False)), "1", None,
         "half of each body meshed and mirrored (mirror-image meshes of the two sides)"),
    ):  # fmt: skip
        set_by_option = option is not None and settings.get(option) is not None
        source = "option" if set_by_option else _file_of(settings, damper, ("rig", "mesh"), field)
        out[name] = _e(value, unit, source, label, "model")
    for key, value in (geom.params.get(damper) or {}).items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        opt = next(
            (o for o, (f, _) in _shape_options(damper).items() if f == key and settings.get(o)),
            None,
        )
        unit = _unit_of(key)
        name = key[: -len(unit) - 1] if unit != "1" and key.endswith(unit) else key
        out[f"shape/{key}"] = _e(
            value,
            unit,
            "option" if opt else _file_of(settings, damper, (damper,), key),
            f"damper {name.replace('_', ' ')}",
            "model",
        )
    out["modes"] = _e(
        int(settings["modes"]), "1", "option", "fixed-interface modes per body", "model"
    )
    out["rigid_damper"] = _e(
        bool(settings["rigid-damper"]), "1", "option", "damper reduced as a rigid body", "model"
    )
    out["reduced_dofs"] = _e(
        int(model.n),
        "1",
        "the reduced models",
        "coordinates of the reduced rig and damper",
        "model",
    )
    out["geometry_digest"] = _e(
        str(geom.digest), "", "the built geometry", "cache key of the mesh and geometry", "model"
    )
    # damping
    zeta = getattr(system, "zeta", None)
    if zeta is not None:
        z = np.atleast_1d(np.asarray(zeta, dtype=float))
        out["damping"] = _e(
            float(z[0]) if z.size == 1 else z.tolist(),
            "1",
            "option",
            "damping ratio of every mode",
            "damping",
        )
        kind_text = (
            "modal viscous: C = M Phi diag(2 zeta w) Phi^T M over the modes of the reduced "
            "model with every contact stuck and closed"
        )
    elif getattr(system, "C", None) is not None:
        kind_text = "a viscous matrix C given with the model"
    else:
        kind_text = "none (friction only)"
    out["damping_kind"] = _e(
        kind_text, "", "workbench/hbm/core/system.py", "kind of damping", "damping"
    )
    # the harmonic balance
    out["harmonics"] = _e(
        [int(h) for h in branch.harmonics],
        "1",
        "option",
        "harmonics of the balance (0: the mean)",
        "solve",
    )
    out["nt"] = _e(
        int(branch.nt),
        "samples per period",
        "option"
        if settings.get("nt") is not None
        else "solver default (16 x the highest harmonic, at least 32)",
        "time samples per period of the AFT",
        "solve",
    )
    band_given = any(settings.get(k) for k in ("band-in-phase", "band-out-of-phase"))
    out["band"] = _e(
        [float(v) for v in branch.band_hz],
        "Hz",
        "option"
        if band_given
        else "automatic: linear stuck and sliding limits +- band-margin "
        f"({settings.get('band-margin')})",
        "frequency band of the curve",
        "solve",
    )
    out["response"] = _e(
        ", ".join(branch.output_names),
        "",
        "option",
        "response output (blade, direction)",
        "solve",
    )
    opts = dataclasses.asdict(options) if dataclasses.is_dataclass(options) else dict(options)
    out["solver_options"] = _e(
        json.dumps(opts, sort_keys=True, default=str),
        "",
        "option (max-points, stability); the rest SolverOptions defaults",
        "continuation and corrector settings (workbench/hbm/core/options.py)",
        "solve",
    )
    # the code
    from .. import __version__

    out["code_version"] = _e(__version__, "", "workbench/__init__.py", "upd-workbench", "code")
    out["git_commit"] = _e(git_commit(), "", "git", "commit of the sources", "code")
    out["load_average"] = _e(
        round(_load(), 2),
        "1",
        "os.getloadavg() at the end of the solve",
        "load average of the machine (1 min): runnable processes, this run's included",
        "run",
    )
    out["cpus"] = _e(int(os.cpu_count() or 1), "1", "os.cpu_count()", "processor cores", "run")
    out["solver_sources"] = _e(
        solver_sources(),
        "",
        "hash of workbench/contact, hbm, assembly",
        "sources that turn a reduced model into a curve",
        "code",
    )
    return out


def _load() -> float:
    try:
        return float(os.getloadavg()[0])
    except OSError:  # not available on this system
        return float("nan")


def _shape_options(damper: str) -> dict[str, tuple[str, type]]:
    from ..geometry.shapes import get, names

    return get(damper).study_options if damper in names() else {}


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """The short commit of the sources, "+ local changes" when workbench/ differs from it;
    "not a git checkout" outside one."""
    try:
        sha = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short=10", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
        )
        if sha.returncode != 0:
            return "not a git checkout"
        dirty = subprocess.run(
            ["git", "-C", str(ROOT), "diff", "--quiet", "HEAD", "--", "workbench"],
            capture_output=True,
            timeout=10,
        ).returncode
        return sha.stdout.strip() + (" + local changes" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "not a git checkout"


@functools.lru_cache(maxsize=1)
def solver_sources() -> str:
    from ..io import code_version, digest

    pkg = ROOT / "workbench"
    parts = [code_version(pkg / p) for p in ("contact", "hbm", "assembly")]
    parts.append(code_version(pkg / "io", ("record.py",)))  # the branch's HDF5 writer
    return digest(parts, 12)


# ---- storage: case/inputs in a case's HDF5 group -----------------------------------------


def save_inputs(group: Any, inputs: Mapping[str, Mapping[str, Any]]) -> None:
    """One dataset per input under ``group`` (h5py), with ``unit``, ``source``,
    ``description`` and ``group`` attributes; lists as arrays, text as strings."""
    group.attrs["order"] = json.dumps(list(inputs))
    for key, e in inputs.items():
        v = e["value"]
        if isinstance(v, bool):
            v = int(v)
            kind = "bool"
        elif isinstance(v, (int, float)):
            kind = "number"
        elif isinstance(v, list):
            kind = "list"
        else:
            v, kind = str(v), "text"
        d = group.create_dataset(key, data=v)
        d.attrs["unit"] = e.get("unit", "")
        d.attrs["source"] = e.get("source", "")
        d.attrs["description"] = e.get("label", "")
        d.attrs["group"] = e.get("group", "")
        d.attrs["kind"] = kind


def load_inputs(group: Any) -> dict[str, dict[str, Any]]:
    """Read what :func:`save_inputs` wrote (in the order written, nested keys joined by /)."""
    out: dict[str, dict[str, Any]] = {}

    def visit(name: str, obj: Any) -> None:
        if not hasattr(obj, "shape"):
            return
        a = obj.attrs
        raw = obj[()]
        kind = str(a.get("kind", "number"))
        if kind == "text":
            v: Any = raw.decode() if isinstance(raw, bytes) else str(raw)
        elif kind == "bool":
            v = bool(raw)
        elif kind == "list":
            v = [x.item() if hasattr(x, "item") else x for x in raw]
        else:
            v = raw.item() if hasattr(raw, "item") else raw
        out[name] = {
            "value": v,
            "unit": str(a.get("unit", "")),
            "source": str(a.get("source", "")),
            "label": str(a.get("description", "")),
            "group": str(a.get("group", "")),
        }

    group.visititems(visit)
    order = json.loads(group.attrs["order"]) if "order" in group.attrs else list(out)
    return {k: out[k] for k in order if k in out}
