"""The study specification: one record, filled from defaults, a TOML file and the CLI.

Every option has one name used in three places: the TOML key
(``mesh-size = 4.0``), the command-line flag (``--mesh-size 4``) and, with
dashes as underscores, the :class:`StudySpec` attribute (``spec.mesh_size``; a
kind's own option ``spec.<kind>.<name>``, a contact law's parameter
``spec.law[name]``).
Precedence: built-in default < study file < command line. Lists are TOML
arrays or comma-separated on the command line (``--forces 9.6,30``).
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...config import read_toml
from ...errors import InputError, check_choice, check_int, check_range, did_you_mean
from ...geometry.params import DAMPERS
from ...limits import BAND_RATIO_MAX, BAND_RATIO_WHY, EXTREME_HINT
from ...study_options import LAW_OPTIONS, Option, SharedOptions, options_of
from ...study_options import OPTIONS as COMMON_OPTIONS
from ..kinds import all_kinds, kind_options


def _all_options() -> tuple[Option, ...]:
    """The options every kind shares (workbench/study_options.py, ``kind`` offering the
    registered kinds) and each registered kind's own options."""
    kinds = all_kinds()
    names = tuple(k.name for k in kinds)
    out = [
        dataclasses.replace(o, choices=names, help="what the report shows: " + ", ".join(names))
        if o.name == "kind"
        else o
        for o in COMMON_OPTIONS
    ]
    return (*out, *kind_options())


OPTIONS = _all_options()
BY_NAME = {o.name: o for o in OPTIONS}
if len(BY_NAME) != len(OPTIONS):
    raise RuntimeError("two study options share a name: " + ", ".join(o.name for o in OPTIONS))

__all__ = [
    "BY_NAME",
    "OPTIONS",
    "StudySpec",
    "add_arguments",
    "check_option",
    "cli_values",
    "load_study",
    "resolve",
]


# where each option's value lives in a spec: "" (a field of SharedOptions), "law" (the
# mapping of the contact laws' parameters) or a kind's name (that kind's options record)
_HOME: dict[str, str] = {
    **{o.name: "" for o in options_of(SharedOptions)},
    **{o.name: "law" for o in LAW_OPTIONS},
    **{o.name: k.name for k in all_kinds() for o in k.declared},
}


@dataclass(frozen=True)
class StudySpec(SharedOptions):
    """The resolved options of a study.

    The options every kind shares are the fields of
    :class:`~workbench.study_options.SharedOptions` (``spec.forces``,
    ``spec.mesh_size``: the option's name with underscores); the contact laws'
    parameters are ``spec.law[name]`` (``spec.law["mu"]``, declared in
    ``workbench/contact/laws/``); a kind's own options are the fields of its
    record, ``spec.<kind>.<name>`` (``spec.fidelity.levels_nt``, declared in
    ``workbench/studies/kinds/<kind>/options.py``). The study file and the
    command line name every option alike, flat (``levels-nt = [16, 32]``).
    """

    law: dict[str, float | None] = field(default_factory=dict)
    kinds: dict[str, Any] = field(default_factory=dict)  # kind name -> its options record
    source: dict[str, str] = field(default_factory=dict, compare=False)  # option -> origin

    def __getattr__(self, name: str) -> Any:
        """``spec.<kind>``: that kind's options record."""
        kinds = self.__dict__.get("kinds") or {}
        if name in kinds:
            return kinds[name]
        raise AttributeError(f"StudySpec has no attribute {name!r}")

    def value(self, name: str) -> Any:
        """The value of option ``name`` (dashed or with underscores), wherever it lives."""
        key = name.replace("_", "-")
        home = _HOME[key]
        if home == "law":
            return self.law[key]
        return getattr(self if home == "" else self.kinds[home], key.replace("-", "_"))

    def as_dict(self) -> dict[str, Any]:
        """Option name -> value (dashed names, JSON-able)."""
        return {o.name: _jsonable(self.value(o.name)) for o in OPTIONS}

    def replace(self, **changes: Any) -> StudySpec:
        """A copy with some options changed (names with underscores, as attributes)."""
        shared: dict[str, Any] = {}
        law = dict(self.law)
        kinds = dict(self.kinds)
        for attr, v in changes.items():
            home = _HOME.get(attr.replace("_", "-"))
            if home is None:
                raise TypeError(f"StudySpec.replace: no option {attr!r}")
            if home == "":
                shared[attr] = v
            elif home == "law":
                law[attr.replace("_", "-")] = v
            else:
                kinds[home] = dataclasses.replace(kinds[home], **{attr: v})
        return dataclasses.replace(self, **shared, law=law, kinds=kinds, source=dict(self.source))


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


def check_option(o: Option, value: Any, extreme: bool = False) -> Any:
    """Check and convert one value for option ``o``; InputError names the option.

    ``extreme``: accept values beyond the option's physical range (the
    ``allow-extreme`` option); its hard range still applies.
    """
    v = _check_option(o, value, extreme)
    if not extreme and o.kind in ("float", "int") and v is not None:
        _check_soft(o, v, value)
    if o.power_of_2 and v is not None and v & (v - 1):
        raise InputError(
            o.name,
            value,
            f"a power of 2 ({', '.join(str(1 << k) for k in range(1, 6))}, ...)",
            "the Sobol sequence is balanced only at powers of 2",
        )
    return v


def _check_soft(o: Option, v: float, value: Any) -> None:
    """The physical range of a real rig (``soft_lo``/``soft_hi``), with its reason."""
    lo, hi = o.soft_lo, o.soft_hi
    if (lo is None or v >= lo) and (hi is None or v <= hi):
        return
    u = f" {o.unit}" if o.unit else ""
    left = "" if lo is None else f"{lo:g} <= "
    right = "" if hi is None else f" <= {hi:g}"
    raise InputError(o.name, value, f"{left}{o.name}{right}{u}", f"{o.why}; {EXTREME_HINT}")


def _check_option(o: Option, value: Any, extreme: bool) -> Any:
    if value is None:
        if o.optional:
            return None
        raise InputError(o.name, value, f"a value ({o.help})")
    k = o.kind
    if k == "percent":  # a float in percent; a trailing '%' is allowed ("1%", "0.5 %")
        text = (
            value.strip()[:-1] if isinstance(value, str) and value.strip().endswith("%") else value
        )
        try:
            return check_range(o.name, text, o.lo, o.hi, lo_open=o.lo_open, unit="%")
        except InputError as e:  # name the value as the user wrote it
            raise InputError(o.name, value, e.allowed, e.why) from None
    if k == "float":
        return check_range(o.name, value, o.lo, o.hi, lo_open=o.lo_open)
    if k == "int":
        return check_int(
            o.name, value, None if o.lo is None else int(o.lo), None if o.hi is None else int(o.hi)
        )
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
            out.append(check_option(sub, v, extreme))
        if k == "strs" and len(set(out)) != len(out):
            raise InputError(o.name, items, "distinct values")
        return out
    raise AssertionError(k)


def resolve(
    file_values: Mapping[str, Any] | None = None,
    file_name: str = "",
    cli_values: Mapping[str, Any] | None = None,
) -> StudySpec:
    """Merge defaults, a study file's values and command-line values into a spec."""
    values: dict[str, Any] = {}
    source: dict[str, str] = {}
    extreme = False  # allow-extreme is read first: it decides how the others are checked
    for given in (file_values or {}, cli_values or {}):
        if "allow-extreme" in given:
            extreme = check_option(BY_NAME["allow-extreme"], given["allow-extreme"])
    for o in OPTIONS:
        values[o.attr] = o.default if not isinstance(o.default, list) else list(o.default)
        source[o.name] = "default"
    for origin, given in (
        (file_name or "study file", file_values or {}),
        ("command line", cli_values or {}),
    ):
        for key, v in given.items():
            if key not in BY_NAME:
                hint = did_you_mean(key, BY_NAME)
                raise InputError(
                    key,
                    v,
                    "a study option (see upd study --help)",
                    ("unknown key" + (f"; {hint}" if hint else "")) + f" in {origin}",
                )
            o = BY_NAME[key]
            values[o.attr] = check_option(o, v, extreme)
            source[key] = origin
    spec = StudySpec(
        **{f.name: values[f.name] for f in dataclasses.fields(SharedOptions)},
        law={o.name: values[o.attr] for o in LAW_OPTIONS},
        kinds={
            k.name: k.options(**{f.name: values[f.name] for f in dataclasses.fields(k.options)})
            for k in all_kinds()
            if k.options is not None
        },
        source=source,
    )
    _check_consistency(spec)
    return spec


def _check_consistency(spec: StudySpec) -> None:
    for name in ("band-in-phase", "band-out-of-phase"):
        band = getattr(spec, name.replace("-", "_"))
        if band and (len(band) != 2 or band[0] >= band[1]):
            raise InputError(name, band, "[] (automatic) or [lo, hi] with lo < hi, Hz")
        if band and not spec.allow_extreme and band[1] > BAND_RATIO_MAX * band[0]:
            raise InputError(
                name,
                band,
                f"[lo, hi] with hi <= {BAND_RATIO_MAX:g} x lo, Hz",
                f"{BAND_RATIO_WHY}; {EXTREME_HINT}",
            )
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
    if spec.nt is not None and spec.nt <= 2 * max(spec.harmonics):
        raise InputError(
            "nt",
            spec.nt,
            f"nt > 2 x the highest harmonic = {2 * max(spec.harmonics)} (the sampling theorem)",
        )
    if spec.sweep is not None:
        if spec.sweep not in BY_NAME or BY_NAME[spec.sweep].kind not in ("float", "int"):
            scalars = [o.name for o in OPTIONS if o.kind in ("float", "int")]
            raise InputError(
                "sweep",
                spec.sweep,
                "a numeric option: " + ", ".join(scalars),
                did_you_mean(spec.sweep, scalars),
            )
        if not spec.sweep_values:
            raise InputError("sweep-values", spec.sweep_values, "at least one value")
        for i, v in enumerate(spec.sweep_values):
            check_option(
                dataclasses.replace(BY_NAME[spec.sweep], name=f"sweep-values[{i}]"),
                v,
                spec.allow_extreme,
            )
    _check_kind_options(spec)


def _check_kind_options(spec: StudySpec) -> None:
    """Options a study kind does not use are checked all the same (a typo in them is a
    typo), and options that only a sweep uses are refused elsewhere (they would be
    ignored in silence)."""
    if spec.sweep_values and spec.sweep is None:
        raise InputError(
            "sweep-values", spec.sweep_values, "no sweep-values without sweep (the option swept)"
        )
    if spec.kind == "sweep" and spec.sweep is None:
        raise InputError("sweep", None, "the option to sweep (kind = 'sweep')")
    if spec.sweep is not None and spec.kind != "sweep":
        raise InputError(
            "sweep",
            spec.sweep,
            "no sweep unless kind = 'sweep'",
            f"kind is {spec.kind!r}, which does not sweep",
        )
    for kind in all_kinds():  # every kind's own options, whatever the study's kind
        if kind.check is not None:
            kind.check(spec)


def load_study(path: str | Path | None, cli_values: Mapping[str, Any] | None = None) -> StudySpec:
    """Read a study file (or only defaults when ``path`` is None) and apply CLI values."""
    file_values = read_toml(path) if path is not None else {}
    if path is not None and not file_values:
        raise InputError(
            "file",
            str(path),
            "a study file with at least one option",
            "it is empty; give no file for the built-in defaults",
        )
    for key, v in file_values.items():
        if isinstance(v, dict):
            raise InputError(
                key, f"[{key}] table", "top-level keys named like the upd study options (no tables)"
            )
        o = BY_NAME.get(key)
        if o is not None:
            check_toml_type(o, v, str(path))
        if o is not None and o.kind == "path" and isinstance(v, str) and path is not None:
            # a relative path in a study file is relative to that file, not to the caller
            file_values[key] = str((Path(path).resolve().parent / v).resolve())
    return resolve(file_values, str(path) if path else "", cli_values)


_TOML_TYPES = {
    "float": ("a number", (int, float)),
    "int": ("a whole number", (int,)),
    "bool": ("true or false", (bool,)),
    "str": ("a string", (str,)),
    "path": ("a string (a file name)", (str,)),
    "percent": ("a number or a string like '1%'", (int, float, str)),
}


def _toml_type(v: Any) -> str:
    return {
        bool: "a boolean",
        int: "a whole number",
        float: "a number",
        str: "a string",
        list: "an array",
    }.get(type(v), type(v).__name__)


def check_toml_type(o: Option, value: Any, where: str) -> None:
    """Refuse a study file value of the wrong TOML type (no silent coercion).

    ``forces = "9.6"`` (a string), ``phases = 180`` (not an array) and
    ``stability = "yes"`` are refused with the expected type named; the
    command line, whose values are text, is parsed by :func:`check_option`.
    """
    if o.kind in ("floats", "ints", "strs"):
        item = {
            "floats": ("numbers", (int, float), "a number"),
            "ints": ("whole numbers", (int,), "a whole number"),
            "strs": ("strings", (str,), "a string"),
        }[o.kind]
        example = (
            (f'["{value}"]' if o.kind == "strs" else f"[{value}]")
            if isinstance(value, (str, int, float)) and not isinstance(value, bool)
            else {"floats": "[180.0]", "ints": "[0, 1]", "strs": '["cone"]'}[o.kind]
        )
        if not isinstance(value, list):
            raise InputError(
                o.name,
                value,
                f"a TOML array of {item[0]}, e.g. {o.name} = {example}",
                f"{_toml_type(value)} in {where}",
            )
        for i, v in enumerate(value):
            if isinstance(v, bool) or not isinstance(v, item[1]):
                raise InputError(
                    f"{o.name}[{i}]",
                    v,
                    f"{item[2]} (each item of {o.name})",
                    f"{_toml_type(v)} in {where}",
                )
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
        default += range_text(o)
        if o.kind == "bool":
            g.add_argument(
                f"--{o.name}",
                dest=o.attr,
                default=argparse.SUPPRESS,
                action=argparse.BooleanOptionalAction,
                help=o.help + default,
            )
        else:
            g.add_argument(
                f"--{o.name}",
                dest=o.attr,
                default=argparse.SUPPRESS,
                metavar=_metavar(o),
                help=o.help + default,
            )


def range_text(o: Option) -> str:
    """What an option allows, for its help: '; 0 < X <= 10000 N (beyond: --allow-extreme)'."""
    if o.choices:
        return ""  # the help names them
    if o.kind == "bool":
        return ""
    if o.kind in ("str", "path", "strs"):
        return ""
    whole = o.kind in ("int", "ints")
    x = "N" if whole else "X"
    lo = "" if o.lo is None else f"{o.lo:g} {'<' if o.lo_open else '<='} "
    hi = "" if o.hi is None else f" <= {o.hi:g}"
    if o.soft_lo is not None:
        lo = f"{o.soft_lo:g} <= "
    if o.soft_hi is not None:
        hi = f" <= {o.soft_hi:g}"
    u = f" {o.unit}".replace("%", "%%") if o.unit else ""
    what = "whole number" if whole else "number"
    if o.kind.endswith("s"):
        text = f"; {what}s, each {lo}{x}{hi}{u}" if lo or hi else f"; {what}s{u}"
    else:
        text = f"; a {what} {lo}{x}{hi}{u}" if lo or hi else f"; a {what}{u}"
    if o.kind == "percent":
        text = f"; {lo}{x}{hi} %%"
    if o.name in ("band-in-phase", "band-out-of-phase"):
        text += f", hi <= {BAND_RATIO_MAX:g} x lo"
    if o.power_of_2:
        text += ", a power of 2"
    if o.soft_lo is not None or o.soft_hi is not None:
        text += " (beyond: --allow-extreme)"
    return text


def _metavar(o: Option) -> str:
    return {
        "floats": "X,Y,...",
        "ints": "I,J,...",
        "strs": "A,B,...",
        "float": "X",
        "int": "N",
        "path": "FILE",
        "str": "TEXT",
        "percent": "X[%]",
    }[o.kind]


def _fmt_default(v: Any) -> str:
    return ",".join(map(str, v)) if isinstance(v, list) else str(v)


def cli_values(args: argparse.Namespace) -> dict[str, Any]:
    """The study options given on the command line (dashed names -> raw values)."""
    return {o.name: getattr(args, o.attr) for o in OPTIONS if hasattr(args, o.attr)}


def sequence_of(spec: StudySpec, name: str) -> Sequence[Any]:
    return spec.value(name)
