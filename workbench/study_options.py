"""The study options every kind shares (plain data), and the :class:`Option` record.

Every option of ``upd study`` is declared once, with its name, type, default,
help, allowed values, unit, role (what it shapes: the model, a case's solve,
the cases themselves or only the study) and the physical range of a real rig
with its reason. The options every study kind reads are the fields of
:class:`SharedOptions` here (each ``name: type = option(...)``); a kind's own
options are the fields of its record in its folder
(``workbench/studies/kinds/<kind>/options.py``, reached through the kind
registry); a contact law's parameters are declared by the law
(``workbench/contact/laws/``) and become :data:`LAW_OPTIONS`.
:mod:`workbench.studies.engine.spec` turns them into a
:class:`~workbench.studies.engine.spec.StudySpec` (a subclass of
:class:`SharedOptions`) from a TOML file and the command line; the parser,
its help, the cache keys (``role``), the report's Inputs table
(:func:`input_table`, ``unit``) and the figures' axis labels (:func:`find`)
read these declarations. Nothing here computes: it imports no study.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from .contact.law_params import law_params
from .geometry.params import DAMPERS
from .limits import (
    BAND_MAX_HZ,
    BAND_WHY,
    CF_MAX_N,
    CF_WHY,
    FORCE_MAX_N,
    FORCE_WHY,
    K_FACE_N_PER_M3,
    K_FACE_WHY,
    K_LINE_N_PER_M2,
    K_LINE_WHY,
)

__all__ = [
    "BY_NAME",
    "CASES",
    "OPTIONS",
    "SHOWN",
    "Option",
    "declare",
    "find",
    "input_table",
]


@dataclass(frozen=True)
class Option:
    """One study option: its name, type, default, help and allowed values."""

    name: str  # dashed, e.g. "mesh-size"
    kind: str  # "float", "int", "bool", "str", "floats", "ints", "strs", "path"
    default: Any
    help: str
    group: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    choices: tuple[str, ...] | None = None
    optional: bool = False  # None allowed ("use the geometry/contact file's value")
    unit: str = ""
    # the range a real rig cannot leave (allow-extreme passes it) and its reason
    soft_lo: float | None = None
    soft_hi: float | None = None
    why: str = ""
    power_of_2: bool = False  # an int that must be a power of 2
    # what the option shapes: "model" (mesh, reduction, contact: the model's cache key),
    # "solve" (a case's curve on that model: the solve's cache key), "case" (each case takes
    # one of its values: damper, phase, force) or "study" (what is computed and shown)
    role: str = "study"

    @property
    def attr(self) -> str:
        return self.name.replace("-", "_")


def option(kind: str, default: Any, help: str, group: str, **more: Any) -> Any:
    """Declare a study option as a field of an options record (:class:`SharedOptions`, a
    kind's own record): its :class:`Option` (name: the field's, dashes for underscores)
    without its name, and its default (a list default is copied for each record)."""
    meta = {"option": dict(kind=kind, default=default, help=help, group=group, **more)}
    if isinstance(default, list):
        return field(default_factory=lambda d=default: list(d), metadata=meta)
    return field(default=default, metadata=meta)


def options_of(record: type) -> tuple[Option, ...]:
    """The study options declared by the fields of ``record`` (see :func:`option`), in
    field order."""
    return tuple(
        Option(f.name.replace("_", "-"), **f.metadata["option"])
        for f in fields(record)
        if "option" in f.metadata
    )


# a contact law's parameter: None is "the contact files' value" (geometry/contact.toml)
LAW_OPTIONS: tuple[Option, ...] = tuple(
    Option(
        p.name,
        "float",
        None,
        p.help,
        "contact",
        lo=p.lo,
        hi=p.hi,
        lo_open=p.lo_open,
        optional=True,
        unit=p.unit,
        role="model",
    )
    for p in law_params()
)


@dataclass(frozen=True)
class SharedOptions:
    """The options every study kind shares, one field each (``spec.<name>``)."""

    # what to compute
    name: str = option("str", "study", "a name for the study (report title, file names)", "study")
    allow_extreme: bool = option(
        "bool",
        False,
        "accept values beyond the physical ranges of a real rig (forces, cf, contact "
        "stiffness, bands, uq-threshold) for a numerical experiment; the numerical limits stay",
        "study",
    )
    # its choices and help come from the kind registry (workbench/studies/kinds/)
    kind: str = option("str", "comparison", "what the study computes", "study")
    dampers: list[str] = option(
        "strs", list(DAMPERS), "dampers to compare", "cases", choices=DAMPERS, role="case"
    )
    phases: list[float] = option(
        "floats",
        [0.0, 180.0],
        "inter-blade phase angles, deg (0 in-phase, 180 out-of-phase)",
        "cases",
        lo=-360.0,
        hi=360.0,
        unit="deg",
        role="case",
    )
    forces: list[float] = option(
        "floats",
        [0.096, 3.84, 9.6, 15.0, 20.0, 25.0, 30.0],
        "excitation force amplitudes on each blade, N",
        "cases",
        lo=0.0,
        lo_open=True,
        unit="N",
        soft_hi=FORCE_MAX_N,
        why=FORCE_WHY,
        role="case",
    )
    response_blade: int = option(
        "int", 1, "blade whose response is reported (1 or 2)", "cases", lo=1, hi=2, role="solve"
    )
    # frequency band
    band_in_phase: list[float] = option(
        "floats",
        [],
        "band of the in-phase family [lo, hi], Hz "
        "(empty: automatic from the linear stuck and sliding limits)",
        "band",
        lo=0.0,
        lo_open=True,
        unit="Hz",
        soft_hi=BAND_MAX_HZ,
        why=BAND_WHY,
        role="solve",
    )
    band_out_of_phase: list[float] = option(
        "floats",
        [],
        "band of the out-of-phase family [lo, hi], Hz (empty: automatic)",
        "band",
        lo=0.0,
        lo_open=True,
        unit="Hz",
        soft_hi=BAND_MAX_HZ,
        why=BAND_WHY,
        role="solve",
    )
    band_margin: float = option(
        "float",
        0.04,
        "automatic band: relative margin beyond the linear limits",
        "band",
        lo=0.0,
        lo_open=True,
        hi=0.5,
        unit="fraction",
        role="solve",
    )
    # contact and loads (None: geometry/contact.toml)
    # (each contact law's parameters, declared in workbench/contact/laws/: spec.law[name])
    cf: float | None = option(
        "float",
        None,
        "centrifugal force on the damper, N",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N",
        soft_hi=CF_MAX_N,
        why=CF_WHY,
        role="model",
    )
    kt_line: float | None = option(
        "float",
        None,
        "tangential stiffness per metre of line (cone, cylinder), N/m per m",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m",
        soft_lo=K_LINE_N_PER_M2[0],
        soft_hi=K_LINE_N_PER_M2[1],
        why=K_LINE_WHY,
        role="model",
    )
    kn_line: float | None = option(
        "float",
        None,
        "normal stiffness per metre of line, N/m per m",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m",
        soft_lo=K_LINE_N_PER_M2[0],
        soft_hi=K_LINE_N_PER_M2[1],
        why=K_LINE_WHY,
        role="model",
    )
    kt_face: float | None = option(
        "float",
        None,
        "tangential stiffness per m^2 of face (wedge), N/m per m^2",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m^2",
        soft_lo=K_FACE_N_PER_M3[0],
        soft_hi=K_FACE_N_PER_M3[1],
        why=K_FACE_WHY,
        role="model",
    )
    kn_face: float | None = option(
        "float",
        None,
        "normal stiffness per m^2 of face (wedge), N/m per m^2",
        "contact",
        lo=0.0,
        lo_open=True,
        optional=True,
        unit="N/m per m^2",
        soft_lo=K_FACE_N_PER_M3[0],
        soft_hi=K_FACE_N_PER_M3[1],
        why=K_FACE_WHY,
        role="model",
    )
    damping: float = option(
        "float",
        0.002,
        "modal damping ratio of the assembly (stuck contacts)",
        "contact",
        lo=0.0,
        hi=0.5,
        unit="ratio",
        role="model",
    )
    # modelling knobs (fidelity)
    mesh_size: float | None = option(
        "float",
        None,
        "global mesh size, mm (None: the geometry file's)",
        "fidelity",
        lo=0.0,
        lo_open=True,
        hi=1000.0,
        optional=True,
        unit="mm",
        role="model",
    )
    contact_mesh_size: float | None = option(
        "float",
        None,
        "element size at the contact points (rig and damper), mm; capped by the contact "
        "spacing and the global mesh size (None: the geometry file's rig.mesh.contact_size_mm)",
        "fidelity",
        lo=0.2,
        hi=50.0,
        optional=True,
        unit="mm",
        role="model",
    )
    modes: int = option(
        "int",
        12,
        "fixed-interface modes per body (Craig-Bampton)",
        "fidelity",
        lo=0,
        hi=400,
        unit="per body",
        role="model",
    )
    rigid_damper: bool = option(
        "bool", False, "rigid 6-DOF damper instead of Craig-Bampton", "fidelity", role="model"
    )
    points_per_line: int | None = option(
        "int",
        None,
        "contact points per line (cone, cylinder)",
        "fidelity",
        lo=2,
        hi=400,
        optional=True,
        unit="per line",
        role="model",
    )
    harmonics: list[int] = option(
        "ints", [0, 1, 2, 3], "harmonics of the balance", "fidelity", lo=0, hi=64, role="solve"
    )
    nt: int | None = option(
        "int",
        None,
        "AFT time samples per period (None: solver default)",
        "fidelity",
        lo=4,
        hi=8192,
        optional=True,
        unit="samples per period",
        role="solve",
    )
    # geometry
    geometry: Path | None = option(
        "path",
        None,
        "TOML overriding geometry tables (rig, cone, ...)",
        "geometry",
        optional=True,
        role="model",
    )
    cone_angle: float | None = option(
        "float",
        None,
        "cone semi-angle, deg (None: cone.toml's)",
        "geometry",
        lo=0.0,
        lo_open=True,
        hi=89.0,
        optional=True,
        unit="deg",
        role="model",
    )
    # solver
    max_points: int = option(
        "int",
        400,
        "largest number of continuation points per curve",
        "solver",
        lo=5,
        hi=100000,
        unit="points per curve",
        role="solve",
    )
    stability: bool = option("bool", True, "Hill stability of every point", "solver", role="solve")
    nonlinear_modes: bool = option(
        "bool",
        False,
        "comparison study: also one nonlinear mode "
        "(backbone) per damper and family, the forced responses synthesised from it and "
        "their check against the curves (workbench/studies/engine/nlmodes.py)",
        "solver",
    )
    field_shapes: bool = option(
        "bool",
        False,
        "also write cases/<case>_peak_field.vtu: the displacement at each curve's peak on "
        "the full rig and damper meshes (ParaView; about one reduction's eigen solve per "
        "damper, workbench/studies/engine/fields.py)",
        "solver",
    )
    # sweeps and the fidelity/robustness studies
    sweep: str | None = option(
        "str",
        None,
        "name of a scalar option to sweep (e.g. cf, cone-angle, mu)",
        "sweep",
        optional=True,
    )
    sweep_values: list[float] = option("floats", [], "values of the swept option", "sweep")


def _shared() -> tuple[Option, ...]:
    """The shared options in --help order: the contact laws' parameters first in the
    contact group."""
    own = options_of(SharedOptions)
    at = next(i for i, o in enumerate(own) if o.group == "contact")
    return (*own[:at], *LAW_OPTIONS, *own[at:])


OPTIONS: tuple[Option, ...] = _shared()

BY_NAME = {o.name: o for o in OPTIONS}
# options declared elsewhere (each study kind's own, by the kind registry when it finds them)
_DECLARED: dict[str, Option] = {}


def declare(options: tuple[Option, ...]) -> None:
    """Make options declared outside this module (a study kind's own) known to
    :func:`find` (figure labels and units read them there)."""
    _DECLARED.update((o.name, o) for o in options)


def find(name: str) -> Option | None:
    """The declaration of study option ``name`` (dashes or underscores): a shared option or
    a registered kind's own; None for an unknown name."""
    key = name.replace("_", "-")
    return BY_NAME.get(key) or _DECLARED.get(key)


# the shared options a report's Inputs table lists by default besides the name, the kind and
# the model and solver options (a kind names its own list: ``StudyKind.shows``)
CASES = tuple(o.name for o in OPTIONS if o.group in ("cases", "band"))
SHOWN = (*CASES, "field-shapes")


def input_table(
    shows: tuple[str, ...] = SHOWN, own: tuple[Option, ...] = ()
) -> tuple[tuple[str, str], ...]:
    """The rows ``(option, unit)`` of a report's Inputs table, in order: the study's name
    and kind, the options ``shows`` (shared ones, or another kind's it reads: the mistuning
    study's disk is the bladed-disk study's), a kind's own options ``own``, then the options
    of the model and of the solver (each option's ``role``)."""
    head = [BY_NAME.get(n) or _DECLARED[n] for n in ("name", "kind", *shows)]
    model = [o for o in OPTIONS if o.role == "model"]
    solver = [o for o in OPTIONS if o.role == "solve" and o.group not in ("cases", "band")]
    rows = dict.fromkeys((o.name, o.unit) for o in (*head, *own, *model, *solver))
    return tuple(rows)
