"""Parameters of the rig and the dampers, read from ``geometry/*.toml``.

Every dimension is a named field with its unit in the key (``_mm``, ``_deg``).
The rig's records below mirror ``geometry/rig.toml``; each damper shape's
record lives in its module (``workbench/geometry/shapes/<name>.py``) and
mirrors ``geometry/<name>.toml`` (a test keeps each pair in step); the
files are what a user edits and they explain the choices.

Layering (later wins), all through :func:`workbench.config.load_record`, so
an unknown key is refused with a hint and a value out of range names itself::

    defaults (geometry/rig.toml + geometry/<damper>.toml)
    <- the user's geometry file (any of the tables [rig...] and [<damper>])
    <- ``overrides`` (a nested dict with the same keys, used by studies)
    <- ``size_mm`` (the global mesh size, ``upd mesh --size``)
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..config import load_record, param, read_toml, record_to_dict
from ..errors import InputError, check_range, did_you_mean
from .shapes import all_shapes
from .shapes import get as get_shape
from .shapes import names as shape_names

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "geometry"


# --- rig -------------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    """Linear elastic material (rig and damper): stainless steel by default."""

    e_gpa: float = param(197.0, "Young's modulus, GPa", lo=0.0, lo_open=True)
    nu: float = param(0.3, "Poisson's ratio", lo=0.0, hi=0.5, hi_open=True)
    rho_kg_m3: float = param(7800.0, "density, kg/m^3", lo=0.0, lo_open=True)

    def as_si(self) -> dict[str, float]:
        """``{"E_pa", "nu", "rho_kg_m3"}`` as stored in BuiltGeometry.material."""
        return {"E_pa": self.e_gpa * 1e9, "nu": self.nu, "rho_kg_m3": self.rho_kg_m3}


@dataclass(frozen=True)
class Base:
    """The base block (the 'disc'), clamped on its bottom face z = 0."""

    length_mm: float = param(180.0, "extent along x (tangential), mm", lo=0.0, lo_open=True)
    width_mm: float = param(140.0, "extent along y (axial), mm", lo=0.0, lo_open=True)
    height_mm: float = param(50.0, "extent along z (radial), mm", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class Blade:
    """The two beam-like blades, standing on the base, mirror images about x = 0."""

    thickness_mm: float = param(
        40.0, "extent along x, the bending direction of the first mode, mm", lo=0.0, lo_open=True
    )
    width_mm: float = param(100.0, "extent along y (axial), mm", lo=0.0, lo_open=True)
    height_mm: float = param(
        313.0, "span along z from the base top to the blade tip, mm", lo=0.0, lo_open=True
    )
    gap_mm: float = param(
        40.0, "clear distance between the inner faces of the two blades, mm", lo=0.0, lo_open=True
    )


@dataclass(frozen=True)
class Platform:
    """A platform on each blade; its inclined underside faces the other blade."""

    angle_deg: float = param(
        45.0,
        "platform angle beta between each inclined contact face and the radial z axis, deg",
        lo=15.0,
        hi=75.0,
    )
    overhang_mm: float = param(
        16.0,
        "extent from the blade's inner face toward the other blade, along x, mm",
        lo=0.0,
        lo_open=True,
    )
    tip_thickness_mm: float = param(
        6.0,
        "height of the platform's vertical tip face (above the inclined face), mm",
        lo=0.0,
        lo_open=True,
    )
    top_below_tip_mm: float = param(
        221.0, "distance from the blade tip down to the platform's top face, mm", lo=0.0
    )
    width_mm: float = param(100.0, "extent along y, centred on the blade, mm", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class Excitation:
    """Where the excitation force acts: a point on the outer face of each blade.

    The outer face is the one away from the groove; the force is along x
    (the bending direction of the first mode).
    """

    height_mm: float = param(273.0, "height above the base top, mm", lo=0.0, lo_open=True)
    y_mm: float = param(0.0, "axial position (0 = blade centre), mm")


@dataclass(frozen=True)
class Response:
    """Where the response is read: a point on the outer face of each blade, along x."""

    height_mm: float = param(303.0, "height above the base top, mm", lo=0.0, lo_open=True)
    y_mm: float = param(0.0, "axial position (0 = blade centre), mm")


MAX_SIZE_MM = 1000.0  # a mesh size beyond the rig's own size (~300 mm) means nothing


@dataclass(frozen=True)
class MeshSizes:
    """Target element sizes (gmsh) of the second-order tetrahedral meshes."""

    size_mm: float = param(
        9.0, "global element size of the rig, mm", lo=0.0, lo_open=True, hi=MAX_SIZE_MM
    )
    contact_size_mm: float = param(
        1.5, "element size at the contact points (rig and damper), mm", lo=0.0, lo_open=True
    )
    pad_mm: float = param(
        0.0,
        "width of the pad tied to each contact point (workbench/fe/pads.py); 0: the node alone, mm",
        lo=0.0,
    )
    mirror: bool = param(
        False,
        "mesh the half x >= 0 of the rig and of the damper and mirror it about the plane "
        "between the blades, so the two platforms and contact lines have mirror-image meshes "
        "(workbench/geometry/mirror.py; not on the bladed disk's sector)",
    )
    refine_distance_mm: float = param(
        12.0,
        "distance from the contact points over which the size grows back, mm",
        lo=0.0,
        lo_open=True,
    )
    damper_size_mm: float = param(
        3.0, "global element size of the damper, mm", lo=0.0, lo_open=True
    )


@dataclass(frozen=True)
class Fit:
    """Geometric margins used to decide whether a damper fits the groove.

    The lower bounds (0.1 mm) keep gmsh away from features it would need
    elements that small for.
    """

    edge_margin_mm: float = param(
        1.0,
        "smallest distance from a contact line or face to the edge of a platform face, mm",
        lo=0.1,
    )
    clearance_mm: float = param(
        1.0,
        "smallest gap between the damper and any rig part it must not touch, "
        "and between the two platform tips, mm",
        lo=0.1,
    )
    min_feature_mm: float = param(
        0.5, "smallest step between faces (a step is either absent or at least this), mm", lo=0.1
    )


@dataclass(frozen=True)
class RigParams:
    """Everything in ``[rig...]`` of rig.toml."""

    material: Material = field(default_factory=Material)
    base: Base = field(default_factory=Base)
    blade: Blade = field(default_factory=Blade)
    platform: Platform = field(default_factory=Platform)
    excitation: Excitation = field(default_factory=Excitation)
    response: Response = field(default_factory=Response)
    mesh: MeshSizes = field(default_factory=MeshSizes)
    fit: Fit = field(default_factory=Fit)


# --- dampers: each shape's record lives in its module (workbench/geometry/shapes/) ---------


def __getattr__(name: str) -> Any:
    """``DAMPERS``, ``DAMPER_RECORDS`` and the shapes' records (``ConeParams``, ...), from the
    registry of shapes (looked up on use, so a new shape module is found without edits)."""
    from .shapes import all_shapes

    if name == "DAMPERS":
        return tuple(s.name for s in all_shapes())
    if name == "DAMPER_RECORDS":
        return {s.name: s.params for s in all_shapes()}
    for s in all_shapes():
        if s.params.__name__ == name:
            return s.params
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class GeometryParams:
    """The resolved inputs of one build: the rig and the chosen damper."""

    damper: str
    rig: RigParams
    shape: Any  # the damper shape's params record (workbench.geometry.shapes)

    def as_dict(self) -> dict[str, Any]:
        """Nested plain dict in file units: ``{"rig": {...}, "<damper>": {...}}``."""
        return {"rig": record_to_dict(self.rig), self.damper: record_to_dict(self.shape)}


# --- loading ---------------------------------------------------------------


def _merge(base: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge ``top`` into a copy of ``base`` (tables merge, values replace)."""
    out = copy.deepcopy(base)
    for k, v in top.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = _merge(dict(out[k]), v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def _check_tables(data: Mapping[str, Any], source: str) -> None:
    # [contact] of a rig file holds the contact parameters calibrated with that rig; it is
    # read by workbench.assembly.params.load_contact_params, not by the geometry
    allowed = ("rig", *shape_names(), "contact")
    for key, value in data.items():
        if key not in allowed:
            raise InputError(
                f"[{key}] in {source}",
                "a table",
                "the tables " + ", ".join(f"[{a}]" for a in allowed),
                ("unknown table; " + did_you_mean(key, allowed)).rstrip("; "),
            )
        if not isinstance(value, Mapping):
            raise InputError(f"{source}: {key}", value, f"a table [{key}]")


def default_files(damper: str) -> list[Path]:
    """The repository's default parameter files for ``damper`` (those that exist)."""
    return [p for p in (DEFAULT_DIR / "rig.toml", DEFAULT_DIR / f"{damper}.toml") if p.is_file()]


def load_geometry_params(
    damper: str,
    geometry_file: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    size_mm: float | None = None,
) -> GeometryParams:
    """Resolve the parameters of a build (see the module docstring for the layering).

    Raises InputError for an unknown damper, table or key and for values out
    of range; the geometric checks (does the damper fit?) are done later by
    :func:`workbench.geometry.layout.make_layout`.
    """
    shape_type = get_shape(damper)
    damper = shape_type.name
    data: dict[str, Any] = {}
    for path in default_files(damper):
        raw = read_toml(path)
        _check_tables(raw, str(path))
        data = _merge(data, raw)
    if geometry_file is not None:
        raw = read_toml(geometry_file)
        _check_tables(raw, str(geometry_file))
        data = _merge(data, {k: v for k, v in raw.items() if k != "contact"})
    if overrides:
        if not isinstance(overrides, Mapping):
            raise InputError("overrides", overrides, "a nested mapping like {'cone': {...}}")
        _check_tables(overrides, "overrides")
        data = _merge(data, overrides)
    if size_mm is not None:
        size = check_range("size_mm", size_mm, 0.0, MAX_SIZE_MM, lo_open=True, unit="mm")
        data = _merge(data, {"rig": {"mesh": {"size_mm": size}}})
    rig = load_record(RigParams, data.get("rig", {}), "rig.")
    # the other dampers' tables are checked too, so a typo there is not silently kept
    for other in all_shapes():
        if other.name != damper and other.name in data:
            load_record(other.params, data[other.name], f"{other.name}.")
    shape = load_record(shape_type.params, data.get(damper, {}), f"{damper}.")
    return GeometryParams(damper=damper, rig=rig, shape=shape)


def defaults_as_dict(record_type: type) -> dict[str, Any]:
    """The dataclass defaults of a record as a nested dict (for the file/record test)."""
    return dataclasses.asdict(record_type())
