"""The study specification: one record, filled from defaults, a TOML file and the CLI.

Every option has one name used in three places: the TOML key
(``mesh-size = 4.0``), the command-line flag (``--mesh-size 4``) and, with
dashes as underscores, the :class:`StudySpec` attribute (``spec.mesh_size``).
Precedence: built-in default < study file < command line. Lists are TOML
arrays or comma-separated on the command line (``--forces 9.6,30``).
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..config import read_toml
from ..errors import InputError, check_choice, check_int, check_range, did_you_mean

DAMPERS = ("cone", "cylinder", "wedge")
KINDS = ("comparison", "sweep", "fidelity", "robustness", "uncertainty")
# robustness study: the named solution methods and hard cases (defined in
# workbench/studies/robustness.py; the names are here so the options can check them)
ROBUSTNESS_METHODS = ("default", "fd-jacobian", "ls-basic", "ls-l2", "ls-cp",
                      "tangent-predictor", "constant-predictor", "fixed-step",
                      "frequency-stepping")
ROBUSTNESS_CASES = ("near-separation", "high-kt-ratio", "high-force", "wedge-in-phase",
                    "turning-point", "light-damping")


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

    @property
    def attr(self) -> str:
        return self.name.replace("-", "_")


OPTIONS: tuple[Option, ...] = (
    # what to compute
    Option("name", "str", "study", "a name for the study (report title, file names)", "study"),
    Option("kind", "str", "comparison", "what the report shows: " + ", ".join(KINDS), "study",
           choices=KINDS),
    Option("dampers", "strs", list(DAMPERS), "dampers to compare", "cases", choices=DAMPERS),
    Option("phases", "floats", [0.0, 180.0],
           "inter-blade phase angles, deg (0 in-phase, 180 out-of-phase)", "cases",
           lo=-360.0, hi=360.0),
    Option("forces", "floats", [0.096, 3.84, 9.6, 15.0, 20.0, 25.0, 30.0],
           "excitation force amplitudes on each blade, N", "cases", lo=0.0, lo_open=True),
    Option("response-blade", "int", 1, "blade whose response is reported (1 or 2)", "cases",
           lo=1, hi=2),
    # frequency band
    Option("band-in-phase", "floats", [], "band of the in-phase family [lo, hi], Hz "
           "(empty: automatic from the linear stuck and sliding limits)", "band", lo=0.0,
           lo_open=True),
    Option("band-out-of-phase", "floats", [], "band of the out-of-phase family [lo, hi], Hz "
           "(empty: automatic)", "band", lo=0.0, lo_open=True),
    Option("band-margin", "float", 0.04, "automatic band: relative margin beyond the linear "
           "limits", "band", lo=0.0, lo_open=True, hi=0.5),
    # contact and loads (None: geometry/contact.toml)
    Option("mu", "float", None, "friction coefficient", "contact", lo=0.0, hi=2.0, optional=True),
    Option("cf", "float", None, "centrifugal force on the damper, N", "contact", lo=0.0,
           lo_open=True, optional=True),
    Option("kt-line", "float", None, "tangential stiffness per metre of line (cone, cylinder), "
           "N/m per m", "contact", lo=0.0, lo_open=True, optional=True),
    Option("kn-line", "float", None, "normal stiffness per metre of line, N/m per m", "contact",
           lo=0.0, lo_open=True, optional=True),
    Option("kt-face", "float", None, "tangential stiffness per m^2 of face (wedge), N/m per m^2",
           "contact", lo=0.0, lo_open=True, optional=True),
    Option("kn-face", "float", None, "normal stiffness per m^2 of face (wedge), N/m per m^2",
           "contact", lo=0.0, lo_open=True, optional=True),
    Option("damping", "float", 0.002, "modal damping ratio of the assembly (stuck contacts)",
           "contact", lo=0.0, hi=0.5),
    # modelling knobs (fidelity)
    Option("mesh-size", "float", None, "global mesh size, mm (None: the geometry file's)",
           "fidelity", lo=0.0, lo_open=True, optional=True),
    Option("modes", "int", 12, "fixed-interface modes per body (Craig-Bampton)", "fidelity",
           lo=0, hi=400),
    Option("rigid-damper", "bool", False, "rigid 6-DOF damper instead of Craig-Bampton",
           "fidelity"),
    Option("points-per-line", "int", None, "contact points per line (cone, cylinder)",
           "fidelity", lo=2, hi=400, optional=True),
    Option("harmonics", "ints", [0, 1, 2, 3], "harmonics of the balance", "fidelity", lo=0,
           hi=64),
    Option("nt", "int", None, "AFT time samples per period (None: solver default)", "fidelity",
           lo=4, hi=8192, optional=True),
    # geometry
    Option("geometry", "path", None, "TOML overriding geometry tables (rig, cone, ...)",
           "geometry", optional=True),
    Option("cone-angle", "float", None, "cone semi-angle, deg (None: cone.toml's)", "geometry",
           lo=0.0, lo_open=True, hi=89.0, optional=True),
    # solver
    Option("max-points", "int", 400, "largest number of continuation points per curve",
           "solver", lo=5, hi=100000),
    Option("stability", "bool", True, "Hill stability of every point", "solver"),
    Option("nonlinear-modes", "bool", False, "comparison study: also one nonlinear mode "
           "(backbone) per damper and family, the forced responses synthesised from it and "
           "their check against the curves (workbench/studies/nlmodes.py)", "solver"),
    # sweeps and the fidelity/robustness studies
    Option("sweep", "str", None, "name of a scalar option to sweep (e.g. cf, cone-angle, mu)",
           "sweep", optional=True),
    Option("sweep-values", "floats", [], "values of the swept option", "sweep"),
    Option("tolerance", "percent", None, "accepted error, percent ('1' or '1%%'): pick the "
           "cheapest settings meeting it (fidelity studies)", "fidelity", lo=0.0, lo_open=True,
           hi=100.0, optional=True),
    # ---- fidelity study options (kind = "fidelity"; workbench/studies/fidelity.py) ----
    Option("knobs", "strs", ["mesh-size", "modes", "harmonics", "nt", "points-per-line",
                             "rigid-damper"],
           "knobs a fidelity study varies, one at a time about the base setting (the study's "
           "own mesh-size, modes, ...)", "fidelity",
           choices=("mesh-size", "modes", "harmonics", "nt", "points-per-line", "rigid-damper")),
    Option("levels-mesh-size", "floats", [14.0, 11.0, 9.0, 7.0],
           "fidelity: global mesh sizes to try, mm (finest = smallest)", "fidelity", lo=0.0,
           lo_open=True),
    Option("levels-modes", "ints", [4, 8, 12, 24, 40],
           "fidelity: fixed-interface modes per body to try", "fidelity", lo=0, hi=400),
    Option("levels-harmonics", "strs", ["1", "0-1", "0-3", "0-5", "0-7"],
           "fidelity: harmonic sets to try, each 'a-b' (a range) or 'h+h+...' (a list)",
           "fidelity"),
    Option("levels-nt", "ints", [16, 32, 64, 128, 256, 512],
           "fidelity: AFT time samples per period to try", "fidelity", lo=4, hi=8192),
    Option("levels-points-per-line", "ints", [5, 11, 23, 33, 45],
           "fidelity: contact points per line to try", "fidelity", lo=2, hi=400),
    Option("levels-rigid-damper", "strs", ["rigid", "flexible"],
           "fidelity: damper models to try (finest = flexible)", "fidelity",
           choices=("rigid", "flexible")),
    # ---- robustness study options (kind = "robustness"; workbench/studies/robustness.py) ----
    Option("methods", "strs", list(ROBUSTNESS_METHODS), "solution methods of a robustness "
           "study (named solver variants; the first is the reference): "
           + ", ".join(ROBUSTNESS_METHODS), "robustness", choices=ROBUSTNESS_METHODS),
    Option("hard-cases", "strs", list(ROBUSTNESS_CASES), "hard cases of a robustness study: "
           + ", ".join(ROBUSTNESS_CASES), "robustness", choices=ROBUSTNESS_CASES),
    Option("peak-tolerance", "float", 1.0, "robustness: a method that converges but whose "
           "peak amplitude differs from the first method's by more than this, percent, is a "
           "wrong answer", "robustness", lo=0.0,
           lo_open=True, hi=100.0),
    Option("time-check", "bool", True, "robustness: check the harmonic balance against time "
           "integration at its suspect points (small models)", "robustness"),
    # ---- uncertainty study options (kind = "uncertainty"; workbench/studies/uncertainty.py) --
    # a distribution is "uniform LO HI", "normal MEAN SD [LO HI]" or
    # "lognormal MEDIAN SIGMA_LN [LO HI]" (bounds truncate); cf, kt, kn are factors on the
    # nominal value (study option or geometry/contact.toml), mu and damping absolute values,
    # seat-tilt the misalignment of one side's seat, deg
    Option("uq-inputs", "strs", ["mu", "cf", "kt", "kn", "damping", "seat-tilt"],
           "uncertainty: the inputs that vary (the others stay nominal)", "uncertainty",
           choices=("mu", "cf", "kt", "kn", "damping", "seat-tilt")),
    Option("uq-mu", "str", "normal 0.5 0.1 0.25 0.75", "uncertainty: friction coefficient",
           "uncertainty"),
    Option("uq-cf", "str", "normal 1 0.1 0.7 1.3", "uncertainty: factor on the nominal "
           "centrifugal force", "uncertainty"),
    Option("uq-kt", "str", "lognormal 1 0.5 0.25 4", "uncertainty: factor on the nominal "
           "tangential contact stiffness (line and face)", "uncertainty"),
    Option("uq-kn", "str", "lognormal 1 0.5 0.25 4", "uncertainty: factor on the nominal "
           "normal contact stiffness (line and face)", "uncertainty"),
    Option("uq-damping", "str", "lognormal 0.002 0.3 0.001 0.004", "uncertainty: modal "
           "damping ratio", "uncertainty"),
    Option("uq-seat-tilt", "str", "normal 0 0.01 -0.03 0.03", "uncertainty: seat "
           "misalignment of one side, deg (tilts the preload along the line or face; "
           "opens one end when large)", "uncertainty"),
    Option("uq-samples", "int", 16, "uncertainty: base samples N per damper and family "
           "(Saltelli design: N (D + 2) cases; a power of 2; a larger N reuses a smaller)",
           "uncertainty", lo=2, hi=1 << 20),
    Option("uq-seed", "int", 2026, "uncertainty: seed of the scrambled Sobol sequence",
           "uncertainty", lo=0, hi=2**31 - 1),
    Option("uq-threshold", "float", None, "uncertainty: peak amplitude threshold, mm (the "
           "report gives the probability of exceeding it; None: per family, 1.2 x the "
           "median peak of every damper's samples)", "uncertainty", lo=0.0, lo_open=True,
           optional=True),
    Option("uq-schedule", "str", "dynamic", "uncertainty: how samples spread over MPI ranks: "
           "dynamic (a shared counter, each rank takes the next sample when free) or static "
           "(round-robin, for comparison)", "uncertainty", choices=("dynamic", "static")),
)

BY_NAME = {o.name: o for o in OPTIONS}


def _fields() -> list[tuple[str, Any, Any]]:
    out = []
    for o in OPTIONS:
        default = dataclasses.field(default_factory=lambda d=o.default: list(d)) \
            if isinstance(o.default, list) else o.default
        out.append((o.attr, Any, default))
    return out


_Base = dataclasses.make_dataclass("_Base", _fields(), frozen=True)


class StudySpec(_Base):  # type: ignore[misc, valid-type]
    """The resolved options of a study (attributes: option names with underscores)."""

    source: dict[str, str]  # option name -> "default" | file path | "command line"

    def as_dict(self) -> dict[str, Any]:
        """Option name -> value (dashed names, JSON-able)."""
        return {o.name: _jsonable(getattr(self, o.attr)) for o in OPTIONS}

    def replace(self, **changes: Any) -> StudySpec:
        spec = dataclasses.replace(self, **changes)
        object.__setattr__(spec, "source", dict(self.source))
        return spec


def _jsonable(v: Any) -> Any:
    if isinstance(v, Path):
        return str(v)
    if isinstance(v, tuple):
        return list(v)
    return v


def _split(text: Any) -> list[Any]:
    if isinstance(text, (list, tuple)):
        return list(text)
    if isinstance(text, str):
        return [t for t in (s.strip() for s in text.split(",")) if t]
    return [text]


def check_option(o: Option, value: Any) -> Any:
    """Check and convert one value for option ``o``; InputError names the option."""
    if value is None:
        if o.optional:
            return None
        raise InputError(o.name, value, f"a value ({o.help})")
    k = o.kind
    if k == "percent":  # a float in percent; a trailing '%' is allowed ("1%", "0.5 %")
        text = value.strip()[:-1] if isinstance(value, str) and value.strip().endswith("%") \
            else value
        try:
            return check_range(o.name, text, o.lo, o.hi, lo_open=o.lo_open, unit="%")
        except InputError as e:  # name the value as the user wrote it
            raise InputError(o.name, value, e.allowed, e.why) from None
    if k == "float":
        return check_range(o.name, value, o.lo, o.hi, lo_open=o.lo_open)
    if k == "int":
        return check_int(o.name, value, None if o.lo is None else int(o.lo),
                         None if o.hi is None else int(o.hi))
    if k == "bool":
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in ("true", "yes", "1", "false", "no", "0"):
            return value.lower() in ("true", "yes", "1")
        raise InputError(o.name, value, "true or false")
    if k == "str":
        if not isinstance(value, str):
            raise InputError(o.name, value, "a string")
        return check_choice(o.name, value, o.choices) if o.choices else value
    if k == "path":
        p = Path(str(value))
        if not p.is_file():
            raise InputError(o.name, str(value), "an existing file")
        return p
    if k in ("floats", "ints", "strs"):
        items = _split(value)
        out = []
        for i, v in enumerate(items):
            sub = dataclasses.replace(o, name=f"{o.name}[{i}]", kind=k[:-1], optional=False)
            out.append(check_option(sub, v))
        if k == "strs" and len(set(out)) != len(out):
            raise InputError(o.name, items, "distinct values")
        return out
    raise AssertionError(k)


def resolve(file_values: Mapping[str, Any] | None = None, file_name: str = "",
            cli_values: Mapping[str, Any] | None = None) -> StudySpec:
    """Merge defaults, a study file's values and command-line values into a spec."""
    values: dict[str, Any] = {}
    source: dict[str, str] = {}
    for o in OPTIONS:
        values[o.attr] = o.default if not isinstance(o.default, list) else list(o.default)
        source[o.name] = "default"
    for origin, given in ((file_name or "study file", file_values or {}),
                          ("command line", cli_values or {})):
        for key, v in given.items():
            if key not in BY_NAME:
                hint = did_you_mean(key, BY_NAME)
                raise InputError(key, v, "a study option (see upd study --help)",
                                 ("unknown key" + (f"; {hint}" if hint else "")) + f" in {origin}")
            o = BY_NAME[key]
            values[o.attr] = check_option(o, v)
            source[key] = origin
    spec = StudySpec(**values)
    object.__setattr__(spec, "source", source)
    _check_consistency(spec)
    return spec


def _check_consistency(spec: StudySpec) -> None:
    for name in ("band-in-phase", "band-out-of-phase"):
        band = getattr(spec, name.replace("-", "_"))
        if band and (len(band) != 2 or band[0] >= band[1]):
            raise InputError(name, band, "[] (automatic) or [lo, hi] with lo < hi, Hz")
    if not spec.forces:
        raise InputError("forces", spec.forces, "at least one force, N")
    if not spec.phases:
        raise InputError("phases", spec.phases, "at least one phase angle, deg")
    if not spec.dampers:
        raise InputError("dampers", spec.dampers, "at least one of " + ", ".join(DAMPERS))
    if 1 not in spec.harmonics:
        raise InputError("harmonics", spec.harmonics, "a list containing 1 (the excitation)")
    if len(set(spec.harmonics)) != len(spec.harmonics):
        raise InputError("harmonics", spec.harmonics, "distinct harmonics")
    if spec.sweep is not None:
        if spec.sweep not in BY_NAME or BY_NAME[spec.sweep].kind not in ("float", "int"):
            scalars = [o.name for o in OPTIONS if o.kind in ("float", "int")]
            raise InputError("sweep", spec.sweep, "a numeric option: " + ", ".join(scalars),
                             did_you_mean(spec.sweep, scalars))
        if not spec.sweep_values:
            raise InputError("sweep-values", spec.sweep_values, "at least one value")
        for i, v in enumerate(spec.sweep_values):
            check_option(dataclasses.replace(BY_NAME[spec.sweep], name=f"sweep-values[{i}]"), v)


def load_study(path: str | Path | None, cli_values: Mapping[str, Any] | None = None) -> StudySpec:
    """Read a study file (or only defaults when ``path`` is None) and apply CLI values."""
    file_values = read_toml(path) if path is not None else {}
    for key, v in file_values.items():
        if isinstance(v, dict):
            raise InputError(key, f"[{key}] table", "top-level keys named like the "
                             "upd study options (no tables)")
        o = BY_NAME.get(key)
        if o is not None:
            check_toml_type(o, v, str(path))
        if o is not None and o.kind == "path" and isinstance(v, str) and path is not None:
            # a relative path in a study file is relative to that file, not to the caller
            file_values[key] = str((Path(path).resolve().parent / v).resolve())
    return resolve(file_values, str(path) if path else "", cli_values)


_TOML_TYPES = {
    "float": ("a number", (int, float)), "int": ("a whole number", (int,)),
    "bool": ("true or false", (bool,)), "str": ("a string", (str,)),
    "path": ("a string (a file name)", (str,)), "percent": ("a number or a string like '1%'",
                                                            (int, float, str)),
}


def _toml_type(v: Any) -> str:
    return {bool: "a boolean", int: "a whole number", float: "a number", str: "a string",
            list: "an array"}.get(type(v), type(v).__name__)


def check_toml_type(o: Option, value: Any, where: str) -> None:
    """Refuse a study file value of the wrong TOML type (no silent coercion).

    ``forces = "9.6"`` (a string), ``phases = 180`` (not an array) and
    ``stability = "yes"`` are refused with the expected type named; the
    command line, whose values are text, is parsed by :func:`check_option`.
    """
    if o.kind in ("floats", "ints", "strs"):
        item = {"floats": ("numbers", (int, float), "a number"),
                "ints": ("whole numbers", (int,), "a whole number"),
                "strs": ("strings", (str,), "a string")}[o.kind]
        example = (f'["{value}"]' if o.kind == "strs" else f"[{value}]") \
            if isinstance(value, (str, int, float)) and not isinstance(value, bool) else \
            {"floats": "[180.0]", "ints": "[0, 1]", "strs": '["cone"]'}[o.kind]
        if not isinstance(value, list):
            raise InputError(o.name, value, f"a TOML array of {item[0]}, e.g. {o.name} = "
                             f"{example}", f"{_toml_type(value)} in {where}")
        for i, v in enumerate(value):
            if isinstance(v, bool) or not isinstance(v, item[1]):
                raise InputError(f"{o.name}[{i}]", v, f"{item[2]} (each item of {o.name})",
                                 f"{_toml_type(v)} in {where}")
        return
    name, types = _TOML_TYPES[o.kind]
    if (isinstance(value, bool) and o.kind != "bool") or not isinstance(value, types):
        raise InputError(o.name, value, f"{name} (TOML type)", f"{_toml_type(value)} in {where}")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add every study option to ``upd study`` (values stay raw; checked by resolve)."""
    groups: dict[str, Any] = {}
    for o in OPTIONS:
        g = groups.setdefault(o.group, parser.add_argument_group(f"{o.group} options"))
        default = "" if o.default in (None, []) else f" [default: {_fmt_default(o.default)}]"
        if o.kind == "bool":
            g.add_argument(f"--{o.name}", dest=o.attr, default=argparse.SUPPRESS,
                           action=argparse.BooleanOptionalAction, help=o.help + default)
        else:
            g.add_argument(f"--{o.name}", dest=o.attr, default=argparse.SUPPRESS,
                           metavar=_metavar(o), help=o.help + default)


def _metavar(o: Option) -> str:
    return {"floats": "X,Y,...", "ints": "I,J,...", "strs": "A,B,...", "float": "X",
            "int": "N", "path": "FILE", "str": "TEXT", "percent": "X[%]"}[o.kind]


def _fmt_default(v: Any) -> str:
    return ",".join(map(str, v)) if isinstance(v, list) else str(v)


def cli_values(args: argparse.Namespace) -> dict[str, Any]:
    """The study options given on the command line (dashed names -> raw values)."""
    return {o.name: getattr(args, o.attr) for o in OPTIONS if hasattr(args, o.attr)}


def sequence_of(spec: StudySpec, name: str) -> Sequence[Any]:
    return getattr(spec, name.replace("-", "_"))
