"""Typed parameter records loaded from TOML, with strict keys and ranges.

A parameter record is a frozen dataclass whose fields are declared with
:func:`param`; the field name is the TOML key and carries its unit as a
suffix (``length_mm``, ``beta_deg``, ``force_n``), so a file reads::

    [cone]
    semi_angle_deg = 10.0   # cone semi-angle alpha_c
    r1_mm = 10.0            # small radius

:func:`load_record` fills a record from a mapping (a parsed TOML table):
unknown keys are refused with a hint naming the closest valid key, values
are checked against the declared range, and nested records are filled from
sub-tables. Every failure is an :class:`~workbench.errors.InputError` naming
the key, its value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import tomllib
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from .errors import InputError, check_choice, check_int, check_range, did_you_mean

T = TypeVar("T")


def param(
    default: Any,
    help: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    choices: tuple[str, ...] | None = None,
    why: str = "",
) -> Any:
    """Declare a record field with its help text and allowed range (``why``: the range's
    reason, said when a value is refused)."""
    meta = dict(help=help, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open, choices=choices, why=why)
    if isinstance(default, (list, dict)):
        return dataclasses.field(default_factory=lambda: type(default)(default), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def _unit_of(name: str) -> str:
    for suffix, unit in (
        ("_mm", "mm"),
        ("_deg", "deg"),
        ("_hz", "Hz"),
        ("_n", "N"),
        ("_gpa", "GPa"),
        ("_kg_m3", "kg/m^3"),
        ("_n_per_mm", "N/mm"),
        ("_n_per_m", "N/m"),
        ("_m", "m"),
        ("_pa", "Pa"),
        ("_s", "s"),
    ):
        if name.endswith(suffix):
            return unit
    return ""


def check_field(f: dataclasses.Field, value: Any, where: str = "", typ: Any = None) -> Any:
    """Check one value against a field declared with :func:`param`.

    ``typ`` is the resolved type of the field (``f.type`` may be a string
    under ``from __future__ import annotations``).
    """
    name = f"{where}{f.name}"
    m = f.metadata
    typ = f.type if typ is None else typ
    if m.get("choices"):
        return check_choice(name, value, m["choices"])
    if typ in (int, "int", float, "float") and isinstance(value, str) and _numeric(value):
        # a quoted number in a parameter file is a typo, not a number: no silent coercion
        # (other text falls through to the range check's "not a number")
        raise InputError(
            name,
            value,
            "a number" if typ in (float, "float") else "a whole number",
            "a string; write it without quotes",
        )
    try:
        if typ in (int, "int"):
            return check_int(name, value, m.get("lo"), m.get("hi"))
        if typ in (float, "float"):
            return check_range(
                name,
                value,
                m.get("lo"),
                m.get("hi"),
                lo_open=m.get("lo_open", False),
                hi_open=m.get("hi_open", False),
                unit=_unit_of(f.name),
            )
    except InputError as e:
        if m.get("why") and not e.why:
            raise InputError(e.param, e.value, e.allowed, m["why"]) from None
        raise
    if typ in (bool, "bool"):
        if not isinstance(value, bool):
            raise InputError(name, value, "true or false")
        return value
    if typ in (str, "str"):
        if not isinstance(value, str):
            raise InputError(name, value, "a string")
        return value
    return value


def _numeric(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def validate(record: Any, where: str = "") -> None:
    """Check every field of a record (recursively) against its declaration."""
    hints = typing.get_type_hints(type(record))
    for f in dataclasses.fields(record):
        v = getattr(record, f.name)
        if dataclasses.is_dataclass(v):
            validate(v, f"{where}{f.name}.")
        elif f.metadata:
            check_field(f, v, where, hints[f.name])


def load_record(cls: type[T], data: Mapping[str, Any] | None = None, where: str = "") -> T:
    """Build ``cls`` from ``data``: defaults for missing keys, errors for unknown ones."""
    data = dict(data or {})
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise InputError(
                f"{where}{key}",
                data[key],
                "one of the keys " + ", ".join(fields),
                ("unknown key; " + did_you_mean(key, fields)).rstrip("; "),
            )
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        typ = hints[name]
        if name not in data:
            continue
        value = data[name]
        if dataclasses.is_dataclass(typ):
            if not isinstance(value, Mapping):
                raise InputError(f"{where}{name}", value, f"a table [{where}{name}]")
            kwargs[name] = load_record(typ, value, f"{where}{name}.")
        else:
            kwargs[name] = check_field(f, value, where, typ)
    rec = cls(**kwargs)
    validate(rec, where)
    return rec


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; a missing or malformed file is an InputError."""
    p = Path(path)
    if not p.is_file():
        raise InputError("file", str(p), "an existing TOML file")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as e:
        raise InputError("file", str(p), "valid TOML", str(e)) from None
    except UnicodeDecodeError as e:
        raise InputError(
            "file",
            str(p),
            "a UTF-8 text file (TOML)",
            f"byte 0x{e.object[e.start]:02x} at offset {e.start} is not UTF-8",
        ) from None
    except OSError as e:
        raise InputError(
            "file", str(p), "a readable TOML file", e.strerror or type(e).__name__
        ) from None


def record_to_dict(record: Any) -> dict[str, Any]:
    """Plain nested dict of a record (for hashing, JSON and HDF5 attributes)."""
    return dataclasses.asdict(record)
